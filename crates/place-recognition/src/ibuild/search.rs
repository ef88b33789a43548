//! The first-match search of Assign-BoW-Index (Khan 2017, §4.4.2, Fig. 4.9): for a visual word
//! `d̂`, the **lowest** vocabulary index `j` with `H(d̂, v_j) < δ` — the first match of a linear
//! scan, not the nearest word.
//!
//! Two engines answer it identically: the thesis' linear scan over the contiguous words, with an
//! early exit on the first match and a half-descriptor lower bound (`H` over the first 256 bits
//! already `≥ δ` skips the rest), and exact multi-index hashing (see [`MultiIndexLayout`]), which
//! is sub-linear in the vocabulary size for the usual thresholds. The default
//! [`VocabularySearch::Auto`] hashes only where its cost model predicts a gain (large
//! vocabularies, δ up to about 100 bits) and scans otherwise.

use serde::{Deserialize, Serialize};

use super::multi_index::{MultiIndex, MultiIndexLayout};
use crate::{Bits512, PlaceError, Result};

/// Which engine answers the first-match search (all give identical answers).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum VocabularySearch {
    /// Linear scan in index order, as the thesis (Fig. 4.9).
    Linear,
    /// Exact multi-index hashing (Norouzi et al., CVPR 2012) at every vocabulary size.
    MultiIndex,
    /// Multi-index hashing once the vocabulary is larger than
    /// [`MultiIndexLayout::linear_crossover`], the linear scan before (and always, without
    /// tables, when hashing never pays off at this δ). The default.
    #[default]
    Auto,
}

/// An engine of the first-match search over words stored elsewhere (contiguously, by index).
pub(crate) trait FirstMatch {
    /// Word `id` (the next index) was appended.
    fn push(&mut self, id: u32, word: &Bits512);
    /// Word `id` changed from `old` to `new`.
    fn replace(&mut self, id: u32, old: &Bits512, new: &Bits512);
    /// The lowest `j` with `H(query, words[j]) < delta`.
    fn first_match(&self, words: &[Bits512], query: &Bits512, delta: u32) -> Option<u32>;
}

/// The linear scan (no state besides the words).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct LinearScan;

impl FirstMatch for LinearScan {
    fn push(&mut self, _id: u32, _word: &Bits512) {}

    fn replace(&mut self, _id: u32, _old: &Bits512, _new: &Bits512) {}

    fn first_match(&self, words: &[Bits512], query: &Bits512, delta: u32) -> Option<u32> {
        let q = &query.0;
        for (j, w) in words.iter().enumerate() {
            let w = &w.0;
            let head = (w[0] ^ q[0]).count_ones()
                + (w[1] ^ q[1]).count_ones()
                + (w[2] ^ q[2]).count_ones()
                + (w[3] ^ q[3]).count_ones();
            if head >= delta {
                continue;
            }
            let tail = (w[4] ^ q[4]).count_ones()
                + (w[5] ^ q[5]).count_ones()
                + (w[6] ^ q[6]).count_ones()
                + (w[7] ^ q[7]).count_ones();
            if head + tail < delta {
                return Some(j as u32);
            }
        }
        None
    }
}

#[derive(Clone, Debug)]
enum Engine {
    Linear(LinearScan),
    /// Tables, and the vocabulary size below which the scan answers instead.
    MultiIndex(Box<MultiIndex>, usize),
}

/// Binary visual words (contiguous, append-only but for re-centroiding) with a first-match
/// search at a fixed threshold δ.
#[derive(Clone, Debug)]
pub struct WordIndex {
    words: Vec<Bits512>,
    delta: u32,
    search: VocabularySearch,
    engine: Engine,
}

impl WordIndex {
    /// An empty index for `H < delta` (δ in 1..=512 bits).
    pub fn new(delta: u32, search: VocabularySearch) -> Result<Self> {
        if !(1..=512).contains(&delta) {
            return Err(PlaceError::InvalidParameter {
                name: "delta",
                reason: format!("must be in 1..=512 bits, got {delta}"),
            });
        }
        let engine = match search {
            VocabularySearch::Linear => Engine::Linear(LinearScan),
            VocabularySearch::MultiIndex => {
                Engine::MultiIndex(Box::new(MultiIndex::new(delta)?), 0)
            }
            VocabularySearch::Auto => {
                let tables = MultiIndex::new(delta)?;
                match tables.layout().linear_crossover() {
                    Some(n) => Engine::MultiIndex(Box::new(tables), n),
                    None => Engine::Linear(LinearScan),
                }
            }
        };
        Ok(Self {
            words: Vec::new(),
            delta,
            search,
            engine,
        })
    }

    fn engine(&self) -> &dyn FirstMatch {
        match &self.engine {
            Engine::MultiIndex(e, below) if self.words.len() >= *below => e.as_ref(),
            _ => &LinearScan,
        }
    }

    fn engine_mut(&mut self) -> &mut dyn FirstMatch {
        match &mut self.engine {
            Engine::Linear(e) => e,
            Engine::MultiIndex(e, _) => e.as_mut(),
        }
    }

    /// Appends a word and returns its index. Panics beyond `2³² − 1` words (256 GB of words).
    pub fn push(&mut self, word: Bits512) -> u32 {
        let id = u32::try_from(self.words.len())
            .ok()
            .filter(|&id| id != u32::MAX)
            .expect("vocabulary limited to 2^32 - 1 words");
        self.engine_mut().push(id, &word);
        self.words.push(word);
        id
    }

    /// Replaces word `id` (no-op for an index out of range).
    pub fn replace(&mut self, id: u32, word: Bits512) {
        let Some(&old) = self.words.get(id as usize) else {
            return;
        };
        self.engine_mut().replace(id, &old, &word);
        self.words[id as usize] = word;
    }

    /// The lowest index `j` with `H(query, v_j) < δ` (Fig. 4.9), `None` for a new word.
    pub fn first_match(&self, query: &Bits512) -> Option<u32> {
        self.engine().first_match(&self.words, query, self.delta)
    }

    /// The words, by index.
    pub fn words(&self) -> &[Bits512] {
        &self.words
    }

    /// Number of words.
    pub fn len(&self) -> usize {
        self.words.len()
    }

    /// True without words.
    pub fn is_empty(&self) -> bool {
        self.words.is_empty()
    }

    /// The matching threshold δ in bits.
    pub fn delta(&self) -> u32 {
        self.delta
    }

    /// The engine asked for.
    pub fn search(&self) -> VocabularySearch {
        self.search
    }

    /// The multi-index layout, `None` without hash tables.
    pub fn layout(&self) -> Option<MultiIndexLayout> {
        match &self.engine {
            Engine::Linear(_) => None,
            Engine::MultiIndex(e, _) => Some(e.layout()),
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;

    /// Reference: Fig. 4.9 written plainly.
    fn reference(words: &[Bits512], q: &Bits512, delta: u32) -> Option<u32> {
        words
            .iter()
            .position(|w| w.hamming(q) < delta)
            .map(|j| j as u32)
    }

    #[test]
    fn engines_return_the_first_match_not_the_nearest() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let q = Bits512::random(&mut rng);
        for search in [
            VocabularySearch::Linear,
            VocabularySearch::MultiIndex,
            VocabularySearch::Auto,
        ] {
            let mut index = WordIndex::new(60, search).unwrap();
            index.push(Bits512::random(&mut rng));
            index.push(q.with_flipped_bits(50, &mut rng)); // within δ, farther
            index.push(q); // nearest
            assert_eq!(index.first_match(&q), Some(1), "{search:?}");
            assert_eq!(index.first_match(&Bits512::random(&mut rng)), None);
        }
    }

    #[test]
    fn engines_agree_with_reference_after_replacements() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for delta in [1, 5, 17, 40, 64, 80, 121] {
            let mut lin = WordIndex::new(delta, VocabularySearch::Linear).unwrap();
            let mut mih = WordIndex::new(delta, VocabularySearch::MultiIndex).unwrap();
            let base: Vec<Bits512> = (0..20).map(|_| Bits512::random(&mut rng)).collect();
            for i in 0..300 {
                let w = base[i % 20]
                    .with_flipped_bits(rng.random_range(0..2 * delta as usize), &mut rng);
                lin.push(w);
                mih.push(w);
                if i % 7 == 3 {
                    let id = rng.random_range(0..=i as u32);
                    let new = w.with_flipped_bits(30, &mut rng);
                    lin.replace(id, new);
                    mih.replace(id, new);
                }
            }
            for _ in 0..200 {
                let q = base[rng.random_range(0..20)]
                    .with_flipped_bits(rng.random_range(0..2 * delta as usize), &mut rng);
                let want = reference(lin.words(), &q, delta);
                assert_eq!(lin.first_match(&q), want, "linear, delta {delta}");
                assert_eq!(mih.first_match(&q), want, "multi-index, delta {delta}");
            }
        }
        assert!(WordIndex::new(0, VocabularySearch::Linear).is_err());
        assert!(WordIndex::new(513, VocabularySearch::MultiIndex).is_err());
    }
}
