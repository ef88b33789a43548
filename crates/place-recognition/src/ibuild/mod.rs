//! IBuILD: online, incremental binary bag of words for appearance-based loop closure
//! (Khan 2017, §4.4; Khan and Wollherr, ICRA 2015).
//!
//! No training: the vocabulary grows from the images themselves. Per frame `I_{t+1}`
//! (Fig. 4.6):
//!
//! 1. keypoints and 512-bit descriptors ([`frame_image`], [`detect_and_describe`]);
//! 2. its descriptors are matched with those of the previous frame (`H < δ`), and the
//!    eq. (4.1) centroid of each matched pair is a pose-invariant descriptor
//!    ([`match_consecutive`], §4.4.1);
//! 3. near-duplicates are merged into visual words ([`merge_descriptors`], Fig. 4.8);
//! 4. each word is assigned the **first** vocabulary word within δ, or counted as new
//!    (Assign-BoW-Index, Fig. 4.9; the linear scan or exact multi-index hashing, same
//!    answers, [`VocabularySearch`]);
//! 5. hypotheses are the images `< t − β` sharing an old word, scored by the modified Jaccard
//!    index and normalised over the hypotheses, with no candidate when `|L| ≤ 1` (§4.4.3);
//! 6. the vocabulary is updated: new words appended, frequencies and inverted index (§4.4.3).
//!
//! Through [`PlaceRecognizer`]: `describe` runs steps 1–4 (the assignment against the current
//! vocabulary is cached in the description), `query` step 5, `insert` step 6 (re-assigning only
//! when the vocabulary changed since `describe`). [`Ibuild::describe_descriptors`] starts at
//! step 2 for callers with their own descriptors. The temporal consistency test (Fig. 4.11)
//! acts on accepted loop closures and lives with the online acceptance, not here.
//! [`Ibuild::stage_times`] accumulates the time per stage for a row like Table 4.3.
//!
//! Decisions not in the thesis (ours):
//! * The first frame (and the first after [`Ibuild::reset_tracking`]) has no predecessor; it is
//!   matched with itself, so its merged raw descriptors become its words. Frame indices thus
//!   stay those of the input, and every frame can be retrieved in kidnapped mode.
//! * δ defaults to 80 bits; see [`IbuildConfig`] for the other defaults and ablation flags,
//!   [`match_consecutive`] and [`merge_descriptors`] for the matching and merging conventions,
//!   and [`Vocabulary`] for frequencies and word updates.
//! * A stored frame queried in kidnapped mode ([`PlaceRecognizer::query_stored`]) uses its
//!   stored words as the old words, `N_new = 0` and the current frequencies; it scores `S = 1`
//!   against itself, the largest possible value. As printed, `S` only counts the hypothesis'
//!   words missing from the query (`T`), so a frame whose words are a subset of the query's
//!   also scores 1: ties at the top are possible.
//!
//! ```
//! use raypath_place_recognition::{BinaryDescriptor, Bits512, Ibuild, IbuildConfig, PlaceRecognizer};
//!
//! let mut ibuild = Ibuild::new(IbuildConfig::default())?;
//! // Twenty random descriptors per "place" (SplitMix64 bits).
//! let place = |seed: u64| -> Vec<Bits512> {
//!     let mix = |mut z: u64| {
//!         z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
//!         z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
//!         z ^ (z >> 31)
//!     };
//!     (0..20u64).map(|k| BinaryDescriptor(std::array::from_fn(|w| mix(seed * 1_000 + k * 8 + w as u64)))).collect()
//! };
//! // Place 1 seen three times, place 2 three times, then place 1 again (the first frame back
//! // has no tracked features: nothing matches across the jump).
//! for seed in [1, 1, 1, 2, 2, 2, 1] {
//!     let d = ibuild.describe_descriptors(place(seed));
//!     ibuild.insert(d);
//! }
//! let d = ibuild.describe_descriptors(place(1));
//! let candidates = ibuild.query(&d, 6); // frames 0..6 (online: t − β)
//! let best = candidates.iter().max_by(|a, b| a.score.total_cmp(&b.score)).expect("|L| = 3");
//! assert!(best.frame < 3);
//! # Ok::<(), raypath_place_recognition::PlaceError>(())
//! ```

mod config;
mod matching;
mod multi_index;
mod search;
mod similarity;
mod timing;
mod vocabulary;

#[cfg(test)]
mod tests;

use std::borrow::Cow;
use std::time::Instant;

pub use config::{IbuildConfig, IbuildScore, PlanarDescriptors};
pub use matching::{match_consecutive, merge_descriptors};
pub use multi_index::MultiIndexLayout;
pub use search::{VocabularySearch, WordIndex};
pub use timing::StageTimes;
pub use vocabulary::Vocabulary;

use timing::{Stage, StageClock};

use crate::{Bits512, Candidate, Frame, PlaceRecognizer, Result};
#[cfg(doc)]
use crate::{detect_and_describe, frame_image};

/// What IBuILD keeps of a frame: its visual words, and their assignment against the vocabulary
/// as it was when the frame was described.
#[derive(Clone, Debug, PartialEq)]
pub struct IbuildDescription {
    words: Vec<Bits512>,
    cached: Option<(u64, Vec<Option<u32>>)>,
}

impl IbuildDescription {
    /// A description from visual words (assigned when queried or inserted).
    pub fn from_words(words: Vec<Bits512>) -> Self {
        Self {
            words,
            cached: None,
        }
    }

    /// The visual words `D̂_t`.
    pub fn words(&self) -> &[Bits512] {
        &self.words
    }
}

/// The IBuILD loop-closure method (see the module documentation).
#[derive(Debug)]
pub struct Ibuild {
    config: IbuildConfig,
    vocabulary: Vocabulary,
    previous: Option<Vec<Bits512>>,
    clock: StageClock,
}

impl Ibuild {
    /// An empty IBuILD with a validated configuration.
    pub fn new(config: IbuildConfig) -> Result<Self> {
        config.validate()?;
        // Shape descriptors are sparse (a few dozen of 512 bits set), so most of their
        // multi-index substrings are zero and land in one bucket: hashing then verifies far more
        // words than it skips. `Auto`'s cost model assumes dense bits (BRIEF), so it scans here.
        let search = match (&config.planar, config.search) {
            (PlanarDescriptors::Shape(_), VocabularySearch::Auto) => VocabularySearch::Linear,
            (_, search) => search,
        };
        Ok(Self {
            vocabulary: Vocabulary::new(config.delta, search)?,
            config,
            previous: None,
            clock: StageClock::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &IbuildConfig {
        &self.config
    }

    /// The vocabulary (words, frequencies, inverted index).
    pub fn vocabulary(&self) -> &Vocabulary {
        &self.vocabulary
    }

    /// Describes a frame from its raw descriptors: consecutive matching with the previous
    /// frame's raw descriptors, merging, and the assignment against the current vocabulary
    /// (cached in the description). The raw descriptors are kept for the next frame.
    pub fn describe_descriptors(&mut self, raw: Vec<Bits512>) -> IbuildDescription {
        let start = Instant::now();
        let matched = match &self.previous {
            Some(previous) => match_consecutive(previous, &raw, &self.config),
            None => raw.clone(), // matched with itself: centroid(d, d) = d
        };
        let words = merge_descriptors(matched, &self.config);
        self.previous = Some(raw);
        let start = self.clock.lap(Stage::MatchingMerging, start);
        let indices = self.vocabulary.assign(&words);
        self.clock.lap(Stage::Assignment, start);
        self.clock.count(0);
        IbuildDescription {
            words,
            cached: Some((self.vocabulary.version(), indices)),
        }
    }

    /// Forgets the previous frame: the next frame starts a new track (as the first frame).
    pub fn reset_tracking(&mut self) {
        self.previous = None;
    }

    /// Cumulative time per stage since creation or [`reset_stage_times`](Self::reset_stage_times).
    pub fn stage_times(&self) -> StageTimes {
        self.clock.snapshot()
    }

    /// Sets the stage times to zero.
    pub fn reset_stage_times(&self) {
        self.clock.reset();
    }

    /// The assignment of a description against the current vocabulary (cached when valid).
    fn assignment<'a>(&self, d: &'a IbuildDescription) -> Cow<'a, [Option<u32>]> {
        match &d.cached {
            Some((version, indices)) if *version == self.vocabulary.version() => {
                Cow::Borrowed(indices.as_slice())
            }
            _ => {
                let start = Instant::now();
                let indices = self.vocabulary.assign(&d.words);
                self.clock.lap(Stage::Assignment, start);
                Cow::Owned(indices)
            }
        }
    }
}

impl PlaceRecognizer for Ibuild {
    type Description = IbuildDescription;

    fn name(&self) -> &'static str {
        "ibuild"
    }

    fn describe(&mut self, frame: &Frame<'_>) -> Result<IbuildDescription> {
        let start = Instant::now();
        let raw = match (frame, &self.config.planar) {
            (Frame::Planar(scan), PlanarDescriptors::Shape(shape)) => {
                crate::scan_shape_descriptors(scan, shape)?
            }
            _ => {
                let image = crate::frame_image(frame, &self.config.image)?;
                crate::detect_and_describe(&image, &self.config.features)?.1
            }
        };
        self.clock.lap(Stage::Features, start);
        Ok(self.describe_descriptors(raw))
    }

    fn query(&self, description: &IbuildDescription, before: usize) -> Vec<Candidate> {
        let assignment = self.assignment(description);
        let start = Instant::now();
        let mut old: Vec<u32> = assignment.iter().flatten().copied().collect();
        old.sort_unstable();
        old.dedup();
        let n_new = assignment.iter().filter(|a| a.is_none()).count();
        let out = similarity::hypotheses(&self.vocabulary, &old, n_new, before, self.config.score);
        self.clock.lap(Stage::Hypotheses, start);
        self.clock.count(1);
        out
    }

    fn query_stored(&self, index: usize, before: usize) -> Vec<Candidate> {
        let start = Instant::now();
        let old = self.vocabulary.words_of(index);
        let out = similarity::hypotheses(&self.vocabulary, old, 0, before, self.config.score);
        self.clock.lap(Stage::Hypotheses, start);
        self.clock.count(1);
        out
    }

    fn insert(&mut self, description: IbuildDescription) {
        let assignment = self.assignment(&description).into_owned();
        let start = Instant::now();
        let recentroid = self
            .config
            .recentroid_matched
            .then_some(self.config.strict_majority);
        self.vocabulary
            .update(&description.words, &assignment, recentroid);
        self.clock.lap(Stage::Update, start);
        self.clock.count(2);
    }

    fn len(&self) -> usize {
        self.vocabulary.num_images()
    }

    fn start_sequence(&mut self) {
        self.reset_tracking();
    }
}
