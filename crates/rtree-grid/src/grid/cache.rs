//! A direct-mapped cache from coarse lattice blocks to the fused cell last found there.
//!
//! Keys inside fused cells are not in the lattice index; without the cache each costs an
//! R-tree point query. A scan's keys are sorted (x fastest), so neighbouring rows and slices
//! hit the same fused cuboids again: the cache remembers, per block of 4³ base cubes
//! (hashed into 2¹⁶ slots), the last fused cell found there. Entries are hints, checked by
//! the grid against the cell's box and liveness; compaction clears them.

use crate::key::Key;

/// No cell.
const EMPTY: u32 = u32::MAX;

/// The cache (256 KiB; per-scan scratch, not part of the map).
#[derive(Clone, Debug)]
pub(crate) struct FusedCache {
    slots: Vec<u32>,
}

impl FusedCache {
    const BITS: u32 = 16;
    const SHIFT: u32 = 2;

    /// An empty cache (allocated on first use).
    pub(crate) fn new() -> Self {
        Self { slots: Vec::new() }
    }

    #[inline]
    fn slot(key: Key) -> usize {
        let b = u64::from(key[0] >> Self::SHIFT)
            | (u64::from(key[1] >> Self::SHIFT) << 16)
            | (u64::from(key[2] >> Self::SHIFT) << 32);
        (b.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> (64 - Self::BITS)) as usize
    }

    /// The cell remembered for the block of `key`, if any.
    #[inline]
    pub(crate) fn get(&self, key: Key) -> Option<u32> {
        self.slots
            .get(Self::slot(key))
            .copied()
            .filter(|&id| id != EMPTY)
    }

    /// Remembers `id` for the block of `key`.
    #[inline]
    pub(crate) fn put(&mut self, key: Key, id: u32) {
        if self.slots.is_empty() {
            self.slots = vec![EMPTY; 1 << Self::BITS];
        }
        if let Some(slot) = self.slots.get_mut(Self::slot(key)) {
            *slot = id;
        }
    }

    /// Forgets everything and releases the table.
    pub(crate) fn clear(&mut self) {
        self.slots = Vec::new();
    }
}
