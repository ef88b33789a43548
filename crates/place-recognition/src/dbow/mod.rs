//! The DBoW2-style baseline: a bag of binary words over a vocabulary tree trained offline,
//! after Gálvez-López & Tardós, "Bags of binary words for fast place recognition in image
//! sequences" (IEEE T-RO 2012) — the reference method of Khan 2017, §4.6.1 (Table 4.2).
//!
//! * [`BinaryVocabulary`]: hierarchical k-medians over 512-bit descriptors (branching
//!   `k_w = 10`, depth `L_w = 6`, k-means++ seeding by Hamming distance, bitwise-majority
//!   centres); the leaves are the words, weighted by `idf_i = ln(N / n_i)`.
//! * [`BowVector`]: tf-idf weights, L1-normalised, and the L1 score
//!   `s(v1, v2) = 1 − ½ |v1/|v1| − v2/|v2||_1`; [`DirectIndex`]: the image's descriptors
//!   grouped by their tree node at a chosen level.
//! * [`Dbow`]: the image database, a [`PlaceRecognizer`]. Frames become images
//!   ([`frame_image`](crate::frame_image)), then descriptors
//!   ([`detect_and_describe`](crate::detect_and_describe)), then a bag of words; an inverted
//!   index (word → images, weights) scores only the database images that share a word with
//!   the query.
//!
//! ## Decisions (not in the paper, or differing from it)
//!
//! * Cluster centres are the majority of eq. (4.1) of Khan 2017 (ties → 1), shared with
//!   IBuILD; the paper truncates non-binary medians to 0. Only exact ties differ.
//! * A node with at most `k_w` descriptors (or only equal ones) is not split: it is a word.
//!   k-medians runs at most [`VocabularyConfig::iterations`] rounds (ours, 10).
//! * `N` in the idf is the number of training images (images without descriptors count).
//!   Words seen in every training image get weight 0 and drop out of the vectors.
//! * The paper's normalised score `η(v_t, v_j) = s(v_t, v_j) / s(v_t, v_{t−Δt})` is
//!   [`DbowConfig::normalise_by_previous`], **off by default** so that scores are comparable
//!   across frames (the thresholds of the precision–recall sweep apply to them directly).
//!   When on, `v_{t−Δt}` is the most recently inserted frame for [`Dbow::query`] and frame
//!   `i − 1` for [`Dbow::query_stored`]; a frame whose previous score is at most
//!   [`DbowConfig::min_previous_score`] (or without previous frame) gives no candidates.
//! * Island grouping, temporal consistency and the geometric check of the paper's loop
//!   detector are not here: the database only ranks; acceptance is the evaluation's job. The
//!   direct index is kept in each description for a geometric check.

mod bow;
mod vocabulary;

#[cfg(test)]
mod tests;

use std::sync::Arc;

pub use bow::{BowVector, DirectIndex};
pub use vocabulary::{BinaryVocabulary, VocabularyConfig};

use crate::{
    Bits512, Candidate, FeatureConfig, Frame, ImageConfig, Keypoint, PlaceRecognizer, Result,
};

/// Parameters of the [`Dbow`] database.
#[derive(Clone, Debug, PartialEq)]
pub struct DbowConfig {
    /// How frames become images (default: [`ImageConfig::default`]).
    pub image: ImageConfig,
    /// Keypoints and descriptors (default: [`FeatureConfig::default`]).
    pub features: FeatureConfig,
    /// Divide scores by the query's score against its previous frame, the paper's `η`.
    /// Default `false` (ours; see the module docs).
    pub normalise_by_previous: bool,
    /// With `normalise_by_previous`, frames whose score against the previous frame is at most
    /// this give no candidates (the paper skips such frames). Default 0.0 (ours: only frames
    /// sharing no word with the previous one).
    pub min_previous_score: f64,
    /// Tree level (root = 0) of the nodes kept in the direct index. Default 4, two levels
    /// above the deepest words of a depth-6 tree (ours; the paper compares several levels).
    pub direct_index_level: usize,
}

impl Default for DbowConfig {
    fn default() -> Self {
        Self {
            image: ImageConfig::default(),
            features: FeatureConfig::default(),
            normalise_by_previous: false,
            min_previous_score: 0.0,
            direct_index_level: 4,
        }
    }
}

/// What [`Dbow`] keeps per frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DbowDescription {
    /// The keypoints of the descriptors, in descriptor order.
    pub keypoints: Vec<Keypoint>,
    /// The tf-idf bag-of-words vector (empty when the image has no usable descriptor).
    pub bow: BowVector,
    /// Descriptor indices grouped by tree node at [`DbowConfig::direct_index_level`].
    pub direct_index: DirectIndex,
}

/// The bag-of-binary-words database (Gálvez-López & Tardós 2012) with an inverted index.
#[derive(Clone, Debug)]
pub struct Dbow {
    vocabulary: Arc<BinaryVocabulary>,
    config: DbowConfig,
    descriptions: Vec<DbowDescription>,
    /// Word → `(frame, weight)` in insertion order.
    inverted: Vec<Vec<(u32, f64)>>,
}

impl Dbow {
    /// An empty database over a trained vocabulary (pass an `Arc` to share one vocabulary
    /// between databases).
    pub fn new(vocabulary: impl Into<Arc<BinaryVocabulary>>, config: DbowConfig) -> Self {
        let vocabulary = vocabulary.into();
        let inverted = vec![Vec::new(); vocabulary.word_count()];
        Self {
            vocabulary,
            config,
            descriptions: Vec::new(),
            inverted,
        }
    }

    /// The vocabulary.
    pub fn vocabulary(&self) -> &BinaryVocabulary {
        &self.vocabulary
    }

    /// The configuration.
    pub fn config(&self) -> &DbowConfig {
        &self.config
    }

    /// The stored description of frame `index`.
    pub fn description(&self, index: usize) -> Option<&DbowDescription> {
        self.descriptions.get(index)
    }

    /// Describes already extracted keypoints and descriptors (what
    /// [`describe`](PlaceRecognizer::describe) does after feature extraction).
    pub fn describe_descriptors(
        &self,
        keypoints: Vec<Keypoint>,
        descriptors: &[Bits512],
    ) -> DbowDescription {
        let (bow, direct_index) = self
            .vocabulary
            .transform(descriptors, self.config.direct_index_level);
        DbowDescription {
            keypoints,
            bow,
            direct_index,
        }
    }

    /// L1 scores of `bow` against frames `0..before` through the inverted index; frames that
    /// share no word are absent.
    fn scores(&self, bow: &BowVector, before: usize) -> Vec<Candidate> {
        let before = before.min(self.descriptions.len());
        let mut score = vec![0.0f64; before];
        let mut touched = vec![false; before];
        let mut frames = Vec::new();
        for &(word, a) in bow.entries() {
            let Some(list) = self.inverted.get(word as usize) else {
                continue;
            };
            let end = list.partition_point(|&(f, _)| (f as usize) < before);
            for &(f, b) in &list[..end] {
                let f = f as usize;
                // s(v1, v2) = ½ Σ_common (|v1_i| + |v2_i| − |v1_i − v2_i|)
                score[f] += bow::common_term(a, b);
                if !touched[f] {
                    touched[f] = true;
                    frames.push(f);
                }
            }
        }
        frames.sort_unstable();
        frames
            .into_iter()
            .map(|frame| Candidate {
                frame,
                score: score[frame].clamp(0.0, 1.0),
            })
            .collect()
    }

    /// Applies `η = s / s(v_t, v_{t−Δt})` when configured; `previous` is the frame `t − Δt`.
    fn normalise(
        &self,
        mut candidates: Vec<Candidate>,
        bow: &BowVector,
        previous: Option<usize>,
    ) -> Vec<Candidate> {
        if !self.config.normalise_by_previous {
            return candidates;
        }
        let Some(prev) = previous.and_then(|p| self.descriptions.get(p)) else {
            return Vec::new();
        };
        let s_prev = bow.score(&prev.bow);
        if s_prev <= self.config.min_previous_score || s_prev <= 0.0 {
            return Vec::new();
        }
        for c in &mut candidates {
            c.score /= s_prev; // η(v_t, v_j) = s(v_t, v_j) / s(v_t, v_{t−Δt})
        }
        candidates
    }
}

impl PlaceRecognizer for Dbow {
    type Description = DbowDescription;

    fn name(&self) -> &'static str {
        "dbow"
    }

    /// Frame → image → keypoints and descriptors → bag of words. An image without features
    /// gives an empty description (no candidates), not an error.
    fn describe(&mut self, frame: &Frame<'_>) -> Result<DbowDescription> {
        let image = crate::frame_image(frame, &self.config.image)?;
        let (keypoints, descriptors) = crate::detect_and_describe(&image, &self.config.features)?;
        Ok(self.describe_descriptors(keypoints, &descriptors))
    }

    fn query(&self, description: &DbowDescription, before: usize) -> Vec<Candidate> {
        let candidates = self.scores(&description.bow, before);
        let previous = self.descriptions.len().checked_sub(1);
        self.normalise(candidates, &description.bow, previous)
    }

    /// Frame `index` scores exactly 1 against itself (before `η`), so it comes first; an
    /// out-of-range `index` gives no candidates.
    fn query_stored(&self, index: usize, before: usize) -> Vec<Candidate> {
        let Some(d) = self.descriptions.get(index) else {
            return Vec::new();
        };
        let mut candidates = self.scores(&d.bow, before);
        if let Some(c) = candidates.iter_mut().find(|c| c.frame == index) {
            c.score = 1.0; // s(v, v) = 1
        }
        self.normalise(candidates, &d.bow, index.checked_sub(1))
    }

    /// Appends the description and its words to the inverted index (words outside the
    /// vocabulary, from a description made with another vocabulary, are not indexed).
    fn insert(&mut self, description: DbowDescription) {
        let frame = self.descriptions.len() as u32;
        for &(word, weight) in description.bow.entries() {
            debug_assert!((word as usize) < self.inverted.len());
            if let Some(list) = self.inverted.get_mut(word as usize) {
                list.push((frame, weight));
            }
        }
        self.descriptions.push(description);
    }

    fn len(&self) -> usize {
        self.descriptions.len()
    }
}
