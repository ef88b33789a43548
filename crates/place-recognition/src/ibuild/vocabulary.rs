//! The incremental binary vocabulary of IBuILD (Khan 2017, §4.4.2, Fig. 4.10): the words
//! `V_{t−1}` (contiguous 512-bit rows), their occurrence frequencies `F_{t−1}`, the inverted
//! index word → images and, per image, its word list; Assign-BoW-Index (Fig. 4.9) and the
//! vocabulary update (§4.4.3).
//!
//! Decisions not in the thesis (ours):
//! * A frequency counts the **images** in which a word appears (+1 per image): duplicates within
//!   an image are merged before assignment, and two words of one image that find the same old
//!   word count once.
//! * A matched (old) word keeps its descriptor by default; [`IbuildConfig::recentroid_matched`]
//!   replaces it by the eq. (4.1) centroid with the matching word (ablation; §4.5.2 averages
//!   real-valued words).
//! * Every new word of an image is appended, even if two new words of the same image are within
//!   δ of each other (the thesis appends the `N_new` new words).
//!
//! [`IbuildConfig::recentroid_matched`]: super::IbuildConfig::recentroid_matched

use super::matching::pair_centroid;
use super::search::{VocabularySearch, WordIndex};
use crate::{Bits512, Result};

/// The vocabulary of Khan 2017, Fig. 4.10: words with a first-match search, occurrence
/// frequencies (the number of images containing each word: +1 per image, ours) and the inverted
/// index word → images, with each image's word list. Matched words keep their descriptor unless
/// [`IbuildConfig::recentroid_matched`] is set.
///
/// [`IbuildConfig::recentroid_matched`]: super::IbuildConfig::recentroid_matched
#[derive(Clone, Debug)]
pub struct Vocabulary {
    index: WordIndex,
    frequencies: Vec<u32>,
    inverted: Vec<Vec<u32>>,
    image_words: Vec<Vec<u32>>,
    /// Per image, `Σ_{w ∈ words(i)} 1/f_w` with the current frequencies (kept up to date by
    /// the update so that the `T` sums of the similarity need no pass over the image's words).
    inverse_frequency_sums: Vec<f64>,
    version: u64,
}

impl Vocabulary {
    /// An empty vocabulary for the threshold δ.
    pub(crate) fn new(delta: u32, search: VocabularySearch) -> Result<Self> {
        Ok(Self {
            index: WordIndex::new(delta, search)?,
            frequencies: Vec::new(),
            inverted: Vec::new(),
            image_words: Vec::new(),
            inverse_frequency_sums: Vec::new(),
            version: 0,
        })
    }

    /// Assign-BoW-Index (Fig. 4.9): for each word the lowest vocabulary index within δ, `None`
    /// for a new word.
    pub fn assign(&self, words: &[Bits512]) -> Vec<Option<u32>> {
        words.iter().map(|w| self.index.first_match(w)).collect()
    }

    /// Vocabulary update (§4.4.3) with the words of the next image and their assignment
    /// (`assignment.len() == words.len()`, from [`assign`](Self::assign) on this state): new
    /// words are appended with frequency 1, old words' frequencies grow by one, and the inverted
    /// index gains the image. `recentroid = Some(strict_majority)` replaces each matched word
    /// by its eq. (4.1) centroid with the image's word. Returns the image's index.
    pub(crate) fn update(
        &mut self,
        words: &[Bits512],
        assignment: &[Option<u32>],
        recentroid: Option<bool>,
    ) -> u32 {
        assert_eq!(words.len(), assignment.len(), "one assignment per word");
        let image =
            u32::try_from(self.image_words.len()).expect("vocabulary limited to 2^32 images");
        let mut ids = Vec::with_capacity(words.len());
        for (w, a) in words.iter().zip(assignment) {
            match *a {
                Some(j) => {
                    if let Some(strict) = recentroid {
                        let old = self.index.words()[j as usize];
                        self.index.replace(j, pair_centroid(&old, w, strict)); // Eq. (4.1)
                    }
                    ids.push(j);
                }
                None => {
                    ids.push(self.index.push(*w));
                    self.frequencies.push(0);
                    self.inverted.push(Vec::new());
                }
            }
        }
        ids.sort_unstable();
        ids.dedup();
        let mut own = 0.0;
        for &j in &ids {
            let j = j as usize;
            let f = self.frequencies[j];
            if f > 0 {
                let change = 1.0 / f64::from(f + 1) - 1.0 / f64::from(f);
                for &i in &self.inverted[j] {
                    self.inverse_frequency_sums[i as usize] += change;
                }
            }
            self.frequencies[j] = f + 1;
            self.inverted[j].push(image);
            own += 1.0 / f64::from(f + 1);
        }
        self.inverse_frequency_sums.push(own);
        self.image_words.push(ids);
        self.version += 1;
        image
    }

    /// Changes with every update; cached assignments are valid while it stays the same.
    pub(crate) fn version(&self) -> u64 {
        self.version
    }

    /// `Σ_{w ∈ words(image)} 1/f_w`.
    pub(crate) fn inverse_frequency_sum(&self, image: usize) -> f64 {
        self.inverse_frequency_sums[image]
    }

    /// Number of words `n`.
    pub fn len(&self) -> usize {
        self.index.len()
    }

    /// True without words.
    pub fn is_empty(&self) -> bool {
        self.index.is_empty()
    }

    /// The words `V`, by index.
    pub fn words(&self) -> &[Bits512] {
        self.index.words()
    }

    /// The first-match index over the words.
    pub fn index(&self) -> &WordIndex {
        &self.index
    }

    /// Occurrence frequencies `F`: the number of images containing each word.
    pub fn frequencies(&self) -> &[u32] {
        &self.frequencies
    }

    /// Images containing word `word`, ascending (empty for an unknown word).
    pub fn images_with(&self, word: u32) -> &[u32] {
        self.inverted.get(word as usize).map_or(&[], Vec::as_slice)
    }

    /// Sorted distinct words of image `image` (empty for an unknown image).
    pub fn words_of(&self, image: usize) -> &[u32] {
        self.image_words.get(image).map_or(&[], Vec::as_slice)
    }

    /// Number of images added.
    pub fn num_images(&self) -> usize {
        self.image_words.len()
    }
}
