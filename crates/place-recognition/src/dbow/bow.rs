//! Bag-of-words vectors, their L1 score and the per-image direct index (Gálvez-López &
//! Tardós 2012).

use serde::{Deserialize, Serialize};

/// A sparse, L1-normalised bag-of-words vector: `(word, weight)` sorted by word, every weight
/// positive, weights summing to 1 (or no entries at all).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BowVector {
    entries: Vec<(u32, f64)>,
}

impl BowVector {
    /// Builds a vector from `(word, weight)` pairs sorted by strictly increasing word:
    /// non-positive and non-finite weights are dropped, the rest divided by their sum.
    pub fn from_weights(weights: impl IntoIterator<Item = (u32, f64)>) -> Self {
        let mut entries: Vec<(u32, f64)> = weights
            .into_iter()
            .filter(|(_, w)| w.is_finite() && *w > 0.0)
            .collect();
        debug_assert!(entries.windows(2).all(|p| p[0].0 < p[1].0));
        let sum: f64 = entries.iter().map(|(_, w)| w).sum();
        if sum > 0.0 && sum.is_finite() {
            for (_, w) in &mut entries {
                *w /= sum; // v / |v|_1
            }
        } else {
            entries.clear();
        }
        Self { entries }
    }

    /// The `(word, weight)` entries, sorted by word.
    pub fn entries(&self) -> &[(u32, f64)] {
        &self.entries
    }

    /// Number of non-zero entries.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True for the empty vector (an image without usable words).
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The L1 score `s(v1, v2) = 1 − ½ |v1/|v1| − v2/|v2||_1` in [0, 1] (1 for equal vectors,
    /// 0 when either is empty), evaluated over the common words only as
    /// `½ Σ_{i: v1_i ≠ 0 ≠ v2_i} (|v1_i| + |v2_i| − |v1_i − v2_i|)`.
    pub fn score(&self, other: &Self) -> f64 {
        let (a, b) = (&self.entries, &other.entries);
        let (mut i, mut j) = (0, 0);
        let mut s = 0.0;
        while i < a.len() && j < b.len() {
            match a[i].0.cmp(&b[j].0) {
                std::cmp::Ordering::Less => i += 1,
                std::cmp::Ordering::Greater => j += 1,
                std::cmp::Ordering::Equal => {
                    s += common_term(a[i].1, b[j].1);
                    i += 1;
                    j += 1;
                }
            }
        }
        s.clamp(0.0, 1.0)
    }
}

/// One common word's share of the L1 score: `½ (|a| + |b| − |a − b|)` (= min(a, b) here).
#[inline]
pub(super) fn common_term(a: f64, b: f64) -> f64 {
    0.5 * (a.abs() + b.abs() - (a - b).abs())
}

/// The direct index of one image: for each tree node at the chosen level, the indices of the
/// image's descriptors under it (sorted by node, then by descriptor). Lets geometric
/// verification compare only descriptors that share a node (Gálvez-López & Tardós 2012).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DirectIndex {
    entries: Vec<(u32, Vec<u32>)>,
}

impl DirectIndex {
    /// Groups `(node, descriptor index)` pairs by node.
    pub(super) fn from_pairs(mut pairs: Vec<(u32, u32)>) -> Self {
        pairs.sort_unstable();
        let mut entries: Vec<(u32, Vec<u32>)> = Vec::new();
        for (node, j) in pairs {
            match entries.last_mut() {
                Some((last, list)) if *last == node => list.push(j),
                _ => entries.push((node, vec![j])),
            }
        }
        Self { entries }
    }

    /// The `(node, descriptor indices)` entries, sorted by node.
    pub fn entries(&self) -> &[(u32, Vec<u32>)] {
        &self.entries
    }

    /// The descriptor indices under `node` (empty when none).
    pub fn features(&self, node: u32) -> &[u32] {
        match self.entries.binary_search_by_key(&node, |(n, _)| *n) {
            Ok(i) => &self.entries[i].1,
            Err(_) => &[],
        }
    }
}
