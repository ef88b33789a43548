//! The lattice index: unfused base-cube key → cell id.
//!
//! Unfused base cubes are found in `O(1)` instead of an R-tree descent (Khan 2017, §2.4).
//! A [`RobinTable`] under the key's hash with 4 tag bits of the hash; the key itself is not
//! stored but read back from the cell (`key_of(id)`, its box's lower corner) for the entries
//! whose tag matches — 6 bytes per slot.

use crate::key::{Key, pack};
use crate::robin::RobinTable;

/// Tag bits per slot (the other 12 hold the displacement).
const TAG_BITS: u32 = 4;

/// Key → cell-id table; keys are looked up through a caller-supplied `key_of(id)`.
#[derive(Clone, Debug, Default)]
pub(crate) struct LatticeIndex {
    table: RobinTable<TAG_BITS>,
}

/// The home slot of `key` in `table` and its tag. Keys of one 2³ block get consecutive
/// homes (the block's hash, plus the key's place in the block), so the look-ups of a scan
/// and of a fusion, which walk neighbouring cubes, touch few cache lines; the tag is a byte
/// of the block's hash.
#[inline]
fn home_and_tag(table: &RobinTable<TAG_BITS>, key: Key) -> (usize, u16) {
    let block = pack(key.map(|k| k >> 1));
    let mut h = block.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    h ^= h >> 29;
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    let local = usize::from((key[0] & 1) | ((key[1] & 1) << 1) | ((key[2] & 1) << 2));
    let n = table.slots();
    let mut home = table.home(h) + local;
    if home >= n {
        home -= n;
    }
    (home, (h >> 8) as u16 & ((1 << TAG_BITS) - 1))
}

impl LatticeIndex {
    /// An empty table for `n` entries (at rest: growing starts at the next insertion).
    pub(crate) fn with_capacity(n: usize) -> Self {
        Self {
            table: RobinTable::for_entries(n),
        }
    }

    /// Number of indexed cells.
    #[cfg(test)]
    fn len(&self) -> usize {
        self.table.len()
    }

    /// Bytes of the slot arrays.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.table.memory_bytes()
    }

    /// The id stored for `key`.
    #[inline]
    pub(crate) fn get(&self, key: Key, key_of: impl Fn(u32) -> Key) -> Option<u32> {
        let (home, tag) = home_and_tag(&self.table, key);
        self.table.find(home, |id, t| t == tag && key_of(id) == key)
    }

    /// Stores `id` for `key` (the key must not be present); `key_of` gives the keys of the
    /// stored ids when the table grows.
    pub(crate) fn insert(&mut self, key: Key, id: u32, key_of: impl Fn(u32) -> Key) {
        if !self.table.has_room(1) {
            self.grow(&key_of);
        }
        self.place(key, id, key_of);
    }

    /// Stores `id` for `key` without the load check (growing only when it does not fit).
    pub(crate) fn place(&mut self, key: Key, id: u32, key_of: impl Fn(u32) -> Key) {
        loop {
            let (home, tag) = home_and_tag(&self.table, key);
            if self.table.insert(home, id, tag) {
                return;
            }
            self.grow(&key_of);
        }
    }

    fn grow(&mut self, key_of: &impl Fn(u32) -> Key) {
        let ids = self.table.drain_ids();
        self.table = self.table.doubled();
        for id in ids {
            let (home, tag) = home_and_tag(&self.table, key_of(id));
            let placed = self.table.insert(home, id, tag);
            debug_assert!(placed);
        }
    }

    /// Removes `key`; returns whether it was present.
    pub(crate) fn remove(&mut self, key: Key, key_of: impl Fn(u32) -> Key) -> bool {
        let (home, tag) = home_and_tag(&self.table, key);
        self.table
            .remove(home, |id, t| t == tag && key_of(id) == key)
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use proptest::prelude::*;

    use super::*;

    proptest! {
        #[test]
        fn behaves_like_a_hash_map(ops in prop::collection::vec((0u16..40, any::<bool>()), 1..400)) {
            // id i ↔ key [k, k/3, 7]; ids are the keys' x.
            let key_of = |id: u32| [id as u16, (id / 3) as u16, 7];
            let mut index = LatticeIndex::default();
            let mut model = HashMap::new();
            for (k, insert) in ops {
                let key = key_of(u32::from(k));
                if insert {
                    if let std::collections::hash_map::Entry::Vacant(e) = model.entry(k) {
                        e.insert(());
                        index.insert(key, u32::from(k), key_of);
                    }
                } else {
                    let expected = model.remove(&k).is_some();
                    prop_assert_eq!(index.remove(key, key_of), expected);
                }
                prop_assert_eq!(index.len(), model.len());
            }
            for k in 0u16..40 {
                let expected = model.contains_key(&k).then_some(u32::from(k));
                prop_assert_eq!(index.get(key_of(u32::from(k)), key_of), expected);
            }
        }
    }
}
