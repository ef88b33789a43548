//! A fast hasher for block keys (multiply–rotate, after rustc's `FxHasher`).
//!
//! Block keys are integers we compute ourselves, so the DoS resistance of the standard
//! SipHash is not needed; this hasher is one multiply per key.

use std::hash::{BuildHasherDefault, Hasher};

/// Multiply–rotate hasher for `u64` keys.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct KeyHasher(u64);

const SEED: u64 = 0x51_7c_c1_b7_27_22_0a_95;

impl Hasher for KeyHasher {
    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }

    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for &byte in bytes {
            self.write_u64(u64::from(byte));
        }
    }

    #[inline]
    fn write_u64(&mut self, value: u64) {
        self.0 = (self.0.rotate_left(5) ^ value).wrapping_mul(SEED);
    }
}

/// `BuildHasher` for [`KeyHasher`].
pub(crate) type BuildKeyHasher = BuildHasherDefault<KeyHasher>;
