//! Which coarse blocks of the lattice fused cells touch.
//!
//! A key missing from the lattice index is either unknown or inside a fused cuboid; only
//! the R-tree can tell. Most such keys are new cells far from any fused cell, so a count of
//! fused cells per block of 16³ base cubes lets the grid skip the tree search there.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use crate::key::{Key, KeyBox};

/// log2 of the block edge in base cubes.
const SHIFT: u32 = 4;

/// A multiplicative hasher for packed block keys (no DoS concern: keys come from the map).
#[derive(Default, Clone, Copy)]
pub(crate) struct BlockHasher(u64);

impl Hasher for BlockHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ u64::from(b)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
    }

    fn write_u64(&mut self, v: u64) {
        self.0 = (v ^ (v >> 29)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

/// Fused-cell counts per block.
#[derive(Clone, Debug, Default)]
pub(crate) struct FusedCoverage {
    blocks: HashMap<u64, u32, BuildHasherDefault<BlockHasher>>,
}

#[inline]
fn block(x: u32, y: u32, z: u32) -> u64 {
    u64::from(x) | (u64::from(y) << 16) | (u64::from(z) << 32)
}

impl FusedCoverage {
    /// Whether a fused cell may contain `key`.
    #[inline]
    pub(crate) fn may_contain(&self, key: Key) -> bool {
        !self.blocks.is_empty()
            && self.blocks.contains_key(&block(
                u32::from(key[0]) >> SHIFT,
                u32::from(key[1]) >> SHIFT,
                u32::from(key[2]) >> SHIFT,
            ))
    }

    fn for_blocks(bx: &KeyBox, mut f: impl FnMut(u64)) {
        let lo = bx.lo.map(|k| u32::from(k) >> SHIFT);
        let hi = bx.hi.map(|k| u32::from(k) >> SHIFT);
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    f(block(x, y, z));
                }
            }
        }
    }

    /// Records a fused cell.
    pub(crate) fn add(&mut self, bx: &KeyBox) {
        Self::for_blocks(bx, |b| *self.blocks.entry(b).or_insert(0) += 1);
    }

    /// Forgets a fused cell.
    pub(crate) fn remove(&mut self, bx: &KeyBox) {
        Self::for_blocks(bx, |b| {
            if let Some(n) = self.blocks.get_mut(&b) {
                *n -= 1;
                if *n == 0 {
                    self.blocks.remove(&b);
                }
            }
        });
    }

    /// Bytes of the table (capacity × entry, plus control bytes).
    pub(crate) fn memory_bytes(&self) -> usize {
        self.blocks.capacity() * (size_of::<(u64, u32)>() + 1)
    }
}
