//! Binary descriptors as `W` 64-bit words, the Hamming distance by popcount and the bitwise
//! majority centroid of IBuILD (Khan 2017, §4.4.1, eq. (4.1)).

use serde::{Deserialize, Serialize};

/// A binary descriptor of `64 · W` bits stored as `W` little-endian words (bit `i` is bit
/// `i % 64` of word `i / 64`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct BinaryDescriptor<const W: usize>(#[serde(with = "words")] pub [u64; W]);

/// The 512-bit descriptor IBuILD uses (BRISK's dimension, p = 512; Khan 2017, §4.6.1).
pub type Bits512 = BinaryDescriptor<8>;

/// A 256-bit descriptor (ORB/BRIEF-256).
pub type Bits256 = BinaryDescriptor<4>;

impl<const W: usize> Default for BinaryDescriptor<W> {
    fn default() -> Self {
        Self([0; W])
    }
}

impl<const W: usize> BinaryDescriptor<W> {
    /// Number of bits, `p = 64 · W`.
    pub const BITS: usize = 64 * W;

    /// The all-zero descriptor.
    pub fn zeros() -> Self {
        Self([0; W])
    }

    /// Bit `i` (panics when `i ≥ 64 · W`, a programming error).
    pub fn bit(&self, i: usize) -> bool {
        (self.0[i / 64] >> (i % 64)) & 1 == 1
    }

    /// Sets bit `i` to `value`.
    pub fn set_bit(&mut self, i: usize, value: bool) {
        let mask = 1u64 << (i % 64);
        if value {
            self.0[i / 64] |= mask;
        } else {
            self.0[i / 64] &= !mask;
        }
    }

    /// Number of set bits.
    pub fn count_ones(&self) -> u32 {
        self.0.iter().map(|w| w.count_ones()).sum()
    }

    /// Hamming distance `H(a, b) = Σ_i a[i] ⊕ b[i]` (Khan 2017, §4.4.1): XOR and popcount.
    #[inline]
    pub fn hamming(&self, other: &Self) -> u32 {
        let mut d = 0;
        for k in 0..W {
            d += (self.0[k] ^ other.0[k]).count_ones();
        }
        d
    }

    /// The bitwise-majority centroid of eq. (4.1): bit `i` is 1 when at least half of the
    /// descriptors have it set (ties go to 1, as printed). For two descriptors this is their
    /// bitwise OR. `None` for an empty set.
    pub fn centroid<'a>(descriptors: impl IntoIterator<Item = &'a Self>) -> Option<Self> {
        let mut counts = vec![0u32; Self::BITS];
        let mut k = 0u32;
        for d in descriptors {
            k += 1;
            for (w, word) in d.0.iter().enumerate() {
                let mut bits = *word;
                while bits != 0 {
                    let b = bits.trailing_zeros() as usize;
                    counts[w * 64 + b] += 1;
                    bits &= bits - 1;
                }
            }
        }
        if k == 0 {
            return None;
        }
        let mut out = Self::zeros();
        for (i, &c) in counts.iter().enumerate() {
            // Eq. (4.1): 1 if Σ_j d^j[i] ≥ k/2, i.e. 2·Σ ≥ k.
            if 2 * c >= k {
                out.set_bit(i, true);
            }
        }
        Some(out)
    }

    /// A uniformly random descriptor (for tests, benchmarks and synthetic vocabularies).
    pub fn random(rng: &mut impl rand::Rng) -> Self {
        Self(std::array::from_fn(|_| rng.random()))
    }

    /// A copy with `n` randomly chosen bits flipped (the same bit may be drawn twice, so the
    /// Hamming distance to `self` is at most `n`).
    pub fn with_flipped_bits(mut self, n: usize, rng: &mut impl rand::Rng) -> Self {
        for _ in 0..n {
            let i = rng.random_range(0..Self::BITS);
            self.set_bit(i, !self.bit(i));
        }
        self
    }

    /// The centroid of a pair, eq. (4.1) with k = 2: the bitwise OR.
    #[inline]
    pub fn pair_centroid(&self, other: &Self) -> Self {
        let mut out = *self;
        for k in 0..W {
            out.0[k] |= other.0[k];
        }
        out
    }
}

/// Serde for `[u64; W]` of any `W` (serde derives arrays only up to 32 elements by value).
mod words {
    use serde::de::Error;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer, const W: usize>(
        words: &[u64; W],
        s: S,
    ) -> Result<S::Ok, S::Error> {
        words.as_slice().serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>, const W: usize>(
        d: D,
    ) -> Result<[u64; W], D::Error> {
        let v = Vec::<u64>::deserialize(d)?;
        let n = v.len();
        v.try_into()
            .map_err(|_| D::Error::custom(format!("expected {W} words, got {n}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hamming_counts_differing_bits() {
        let mut a = Bits512::zeros();
        let mut b = Bits512::zeros();
        a.set_bit(3, true);
        a.set_bit(511, true);
        b.set_bit(3, true);
        b.set_bit(64, true);
        assert_eq!(a.hamming(&b), 2);
        assert_eq!(a.hamming(&a), 0);
    }

    #[test]
    fn centroid_is_majority_with_ties_to_one() {
        let mut a = Bits256::zeros();
        let mut b = Bits256::zeros();
        let mut c = Bits256::zeros();
        a.set_bit(0, true);
        b.set_bit(0, true);
        c.set_bit(1, true);
        let m = Bits256::centroid([&a, &b, &c]).expect("three descriptors");
        assert!(m.bit(0));
        assert!(!m.bit(1));
        // Pairs: ties go to 1, so the centroid is the OR.
        let p = Bits256::centroid([&a, &c]).expect("two descriptors");
        assert_eq!(p, a.pair_centroid(&c));
        assert!(p.bit(0) && p.bit(1));
        assert_eq!(Bits256::centroid(std::iter::empty::<&Bits256>()), None);
    }
}
