//! Which coarse blocks of the lattice fused cells touch.
//!
//! A key missing from the lattice index is either unknown or inside a fused cuboid; only
//! the R-tree can tell. Most such keys are new cells far from any fused cell, so a count of
//! fused cells per block of 16³ base cubes lets the grid skip the tree search there. Each
//! block also keeps a 64-bit mask of the 4³ sub-blocks fused cells have touched since the
//! block was last empty (a superset: bits are cleared only with the count), so keys next
//! to, but not inside, fused cells mostly skip the search too.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use crate::key::{Key, KeyBox};

/// log2 of the block edge in base cubes.
const SHIFT: u32 = 4;

/// log2 of the sub-block edge (4 × 4 × 4 sub-blocks per block).
const SUB_SHIFT: u32 = 2;

/// The bit of `key`'s sub-block in its block's mask.
#[inline]
fn sub_block(k: [u32; 3]) -> u32 {
    let s = k.map(|v| (v >> SUB_SHIFT) & 3);
    s[0] | (s[1] << 2) | (s[2] << 4)
}

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
    blocks: HashMap<u64, (u32, u64), BuildHasherDefault<BlockHasher>>,
}

#[inline]
fn block(x: u32, y: u32, z: u32) -> u64 {
    u64::from(x) | (u64::from(y) << 16) | (u64::from(z) << 32)
}

impl FusedCoverage {
    /// Whether a fused cell may contain `key`.
    #[inline]
    pub(crate) fn may_contain(&self, key: Key) -> bool {
        if self.blocks.is_empty() {
            return false;
        }
        let k = key.map(u32::from);
        self.blocks
            .get(&block(k[0] >> SHIFT, k[1] >> SHIFT, k[2] >> SHIFT))
            .is_some_and(|&(_, mask)| mask & (1 << sub_block(k)) != 0)
    }

    fn for_blocks(bx: &KeyBox, mut f: impl FnMut(u64, u64)) {
        let lo = bx.lo.map(|k| u32::from(k) >> SHIFT);
        let hi = bx.hi.map(|k| u32::from(k) >> SHIFT);
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    // The sub-blocks of this block the box touches.
                    let base = [x, y, z].map(|b| b << SHIFT);
                    let sub_lo = [0, 1, 2]
                        .map(|a| (u32::from(bx.lo[a]).max(base[a]) - base[a]) >> SUB_SHIFT);
                    let sub_hi = [0, 1, 2].map(|a| {
                        (u32::from(bx.hi[a]).min(base[a] + (1 << SHIFT) - 1) - base[a]) >> SUB_SHIFT
                    });
                    let mut mask = 0u64;
                    for sz in sub_lo[2]..=sub_hi[2] {
                        for sy in sub_lo[1]..=sub_hi[1] {
                            for sx in sub_lo[0]..=sub_hi[0] {
                                mask |= 1 << (sx | (sy << 2) | (sz << 4));
                            }
                        }
                    }
                    f(block(x, y, z), mask);
                }
            }
        }
    }

    /// Records a fused cell.
    pub(crate) fn add(&mut self, bx: &KeyBox) {
        Self::for_blocks(bx, |b, mask| {
            let entry = self.blocks.entry(b).or_insert((0, 0));
            entry.0 += 1;
            entry.1 |= mask;
        });
    }

    /// Forgets a fused cell.
    pub(crate) fn remove(&mut self, bx: &KeyBox) {
        Self::for_blocks(bx, |b, _| {
            if let Some(n) = self.blocks.get_mut(&b) {
                n.0 -= 1;
                if n.0 == 0 {
                    self.blocks.remove(&b);
                }
            }
        });
    }

    /// Bytes of the table (capacity × entry, plus control bytes).
    pub(crate) fn memory_bytes(&self) -> usize {
        self.blocks.capacity() * (size_of::<(u64, (u32, u64))>() + 1)
    }
}
