//! The fused-cell index: which fused cell holds a base cube, without an R-tree search.
//!
//! Fused cells are not in the lattice index (it holds unfused base cubes). This index
//! registers every fused cell once per block of 4³ base cubes its box touches, in a
//! [`RobinTable`] under the block's hash, tagged with the octants (2³ sub-blocks) of the block
//! the box covers. The cube `k` is found among the entries of its block whose tag has `k`'s
//! octant, by testing their boxes (read through the caller's `box_of(id)`); leaves never
//! overlap, so the first box containing `k` is the answer and a miss proves `k` lies in no
//! fused cell — Guttman's point query (Khan 2017, §2.4) in `O(1)` expected time, at 6 bytes
//! per slot and one entry per block a fused cell touches.

use crate::key::{Key, KeyBox};
use crate::robin::RobinTable;

/// log2 of the block edge in base cubes.
const SHIFT: u32 = 2;

/// Fused cell ids by the 4³ blocks their boxes touch.
#[derive(Clone, Debug, Default)]
pub(crate) struct FusedIndex {
    table: RobinTable<8>,
}

/// The hash of a block.
#[inline]
fn hash(block: [u32; 3]) -> u64 {
    let packed = u64::from(block[0]) | (u64::from(block[1]) << 16) | (u64::from(block[2]) << 32);
    let mut h = packed.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    h ^= h >> 29;
    h.wrapping_mul(0xBF58_476D_1CE4_E5B9)
}

/// The block of base cube `key`.
#[inline]
fn block_of(key: Key) -> [u32; 3] {
    key.map(|k| u32::from(k) >> SHIFT)
}

/// The bit of `key`'s octant in its block.
#[inline]
fn octant_bit(key: Key) -> u8 {
    let o = key.map(|k| (k >> (SHIFT - 1)) & 1);
    1 << (o[0] | (o[1] << 1) | (o[2] << 2))
}

/// Per axis, the octants (bit `x | y << 1 | z << 2`) with a low / high coordinate on it,
/// indexed by which halves are reached (0b01 low, 0b10 high, 0b11 both).
const AXIS_HALVES: [[u8; 4]; 3] = [
    [0, 0x55, 0xAA, 0xFF],
    [0, 0x33, 0xCC, 0xFF],
    [0, 0x0F, 0xF0, 0xFF],
];

/// Calls `f(block, octants)` for every block `bx` touches, with the octants it covers there.
#[inline]
fn for_blocks(bx: &KeyBox, mut f: impl FnMut([u32; 3], u8)) {
    let (lo, hi) = (block_of(bx.lo), block_of(bx.hi));
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                let block = [x, y, z];
                // Per axis, the octant halves (low 0b01, high 0b10) the box reaches in this
                // block; an octant is covered when its half is reached on every axis.
                let mut octants = 0xFFu8;
                for (a, halves) in AXIS_HALVES.iter().enumerate() {
                    let base = block[a] << SHIFT;
                    let first = (u32::from(bx.lo[a]).max(base) - base) >> 1;
                    let last = (u32::from(bx.hi[a]).min(base + 3) - base) >> 1;
                    let reached = (0b11 >> (1 - last)) & (0b11 << first);
                    octants &= halves[reached as usize];
                }
                f(block, octants);
            }
        }
    }
}

/// Number of blocks `bx` touches.
fn blocks_of(bx: &KeyBox) -> usize {
    let (lo, hi) = (block_of(bx.lo), block_of(bx.hi));
    (0..3).map(|a| (hi[a] - lo[a] + 1) as usize).product()
}

impl FusedIndex {
    /// An empty index for `entries` block registrations (at rest).
    pub(crate) fn with_capacity(entries: usize) -> Self {
        Self {
            table: RobinTable::for_entries(entries),
        }
    }

    /// Bytes of the slot arrays.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.table.memory_bytes()
    }

    /// The fused cell whose box (`box_of(id)`) contains `key`.
    #[inline]
    pub(crate) fn find(&self, key: Key, box_of: impl Fn(u32) -> KeyBox) -> Option<u32> {
        let home = self.table.home(hash(block_of(key)));
        let bit = octant_bit(key);
        self.table.find(home, |id, octants| {
            octants & u16::from(bit) != 0 && box_of(id).contains_key(key)
        })
    }

    /// Registers fused cell `id` with box `bx`; `box_of` gives the boxes of the cells
    /// already registered (read when the table grows).
    pub(crate) fn insert(&mut self, id: u32, bx: &KeyBox, box_of: impl Fn(u32) -> KeyBox) {
        if !self.table.has_room(blocks_of(bx)) {
            self.grow(&box_of);
        }
        self.place(id, bx, &box_of);
    }

    /// Registers `id` without the load check (growing only when it does not fit).
    fn place(&mut self, id: u32, bx: &KeyBox, box_of: &impl Fn(u32) -> KeyBox) {
        while !self.try_place(id, bx) {
            self.grow(box_of);
        }
    }

    /// Registers `id` under every block of `bx`; on a failed placement (a displacement
    /// beyond 8 bits) removes what it placed and returns `false`.
    fn try_place(&mut self, id: u32, bx: &KeyBox) -> bool {
        let mut ok = true;
        for_blocks(bx, |block, octants| {
            if ok {
                let home = self.table.home(hash(block));
                ok = self.table.insert(home, id, u16::from(octants));
            }
        });
        if !ok {
            self.remove(id, bx);
        }
        ok
    }

    fn grow(&mut self, box_of: &impl Fn(u32) -> KeyBox) {
        let mut ids = self.table.drain_ids();
        ids.sort_unstable();
        ids.dedup();
        self.table = self.table.doubled();
        for id in ids {
            let placed = self.try_place(id, &box_of(id));
            debug_assert!(placed);
        }
    }

    /// Forgets fused cell `id` with box `bx` (entries it never got are skipped).
    pub(crate) fn remove(&mut self, id: u32, bx: &KeyBox) {
        for_blocks(bx, |block, octants| {
            let home = self.table.home(hash(block));
            self.table
                .remove(home, |i, t| i == id && t == u16::from(octants));
        });
    }

    /// Rebuilds the index for the cells `cells` (id and box) with room for `room` times as
    /// many entries; `box_of` gives the box of any of them.
    pub(crate) fn rebuild(
        &mut self,
        cells: &[(u32, KeyBox)],
        room: usize,
        box_of: impl Fn(u32) -> KeyBox,
    ) {
        let entries: usize = cells.iter().map(|(_, b)| blocks_of(b)).sum();
        *self = Self::with_capacity(room * entries);
        for (id, bx) in cells {
            self.place(*id, bx, &box_of);
        }
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    proptest! {
        #[test]
        fn finds_exactly_the_registered_boxes(
            ops in prop::collection::vec((0u16..12, 0u16..12, 0u16..3, any::<bool>()), 1..300),
        ) {
            // Disjoint boxes: box `id` is the cell of a 12 × 12 × 3 grid of 3 × 2 × 8 boxes
            // offset by one cube (so they straddle blocks and octants).
            let box_of = |id: u32| {
                let (x, y, z) = ((id % 12) as u16, ((id / 12) % 12) as u16, (id / 144) as u16);
                KeyBox { lo: [x * 3 + 1, y * 2 + 1, z * 8 + 1], hi: [x * 3 + 3, y * 2 + 2, z * 8 + 8] }
            };
            let mut index = FusedIndex::default();
            let mut live = std::collections::BTreeSet::new();
            for (x, y, z, insert) in ops {
                let id = u32::from(x) + 12 * u32::from(y) + 144 * u32::from(z);
                if insert && live.insert(id) {
                    index.insert(id, &box_of(id), box_of);
                } else if !insert && live.remove(&id) {
                    index.remove(id, &box_of(id));
                }
            }
            for x in 1..37u16 {
                for y in 1..25u16 {
                    for z in 1..25u16 {
                        let id = u32::from((x - 1) / 3) + 12 * u32::from((y - 1) / 2) + 144 * u32::from((z - 1) / 8);
                        let expected = live.contains(&id).then_some(id);
                        prop_assert_eq!(index.find([x, y, z], box_of), expected);
                    }
                }
            }
        }
    }
}
