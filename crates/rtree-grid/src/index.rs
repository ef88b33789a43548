//! The lattice index: base-cube key → cell id, an open-addressing hash table.
//!
//! Unfused base cubes are found in O(1) instead of an R-tree descent. The table stores only
//! the 4-byte cell id per slot; the key is read back from the cell, so an entry costs
//! 4 bytes / load factor (≤ ¾) — 5.3 to 10.7 bytes per indexed cell. Linear probing with
//! backward-shift deletion (no tombstones).

use crate::key::{Key, pack};

const EMPTY: u32 = u32::MAX;

/// Key → cell-id table; keys are looked up through a caller-supplied `key_of(id)`.
#[derive(Clone, Debug, Default)]
#[allow(dead_code)]
pub struct LatticeIndex {
    slots: Vec<u32>,
    len: usize,
}

#[inline]
fn hash(key: Key) -> u64 {
    let mut h = pack(key).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    h ^= h >> 29;
    h.wrapping_mul(0xBF58_476D_1CE4_E5B9)
}

#[allow(dead_code)]
impl LatticeIndex {
    /// An empty table with room for `n` entries before it grows.
    pub fn with_capacity(n: usize) -> Self {
        let slots = ((n * 4).div_ceil(3) + 1).next_power_of_two().max(64);
        Self {
            slots: vec![EMPTY; slots],
            len: 0,
        }
    }

    /// Number of indexed cells.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no cell is indexed.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Bytes of the slot array.
    pub fn memory_bytes(&self) -> usize {
        self.slots.capacity() * 4
    }

    #[inline]
    fn mask(&self) -> usize {
        self.slots.len() - 1
    }

    /// The id stored for `key`.
    #[inline]
    pub fn get(&self, key: Key, key_of: impl Fn(u32) -> Key) -> Option<u32> {
        if self.slots.is_empty() {
            return None;
        }
        let mask = self.mask();
        let mut i = hash(key) as usize & mask;
        loop {
            let id = self.slots[i];
            if id == EMPTY {
                return None;
            }
            if key_of(id) == key {
                return Some(id);
            }
            i = (i + 1) & mask;
        }
    }

    /// Stores `id` for `key` (the key must not be present).
    pub fn insert(&mut self, key: Key, id: u32, key_of: impl Fn(u32) -> Key) {
        if (self.len + 1) * 4 > self.slots.len() * 3 {
            self.grow(&key_of);
        }
        let mask = self.mask();
        let mut i = hash(key) as usize & mask;
        while self.slots[i] != EMPTY {
            i = (i + 1) & mask;
        }
        self.slots[i] = id;
        self.len += 1;
    }

    fn grow(&mut self, key_of: &impl Fn(u32) -> Key) {
        let new_len = (self.slots.len() * 2).max(64);
        debug_assert!(new_len.is_power_of_two());
        let old = std::mem::replace(&mut self.slots, vec![EMPTY; new_len]);
        let mask = self.mask();
        for id in old.into_iter().filter(|&id| id != EMPTY) {
            let mut i = hash(key_of(id)) as usize & mask;
            while self.slots[i] != EMPTY {
                i = (i + 1) & mask;
            }
            self.slots[i] = id;
        }
    }

    /// Removes `key`; returns its id.
    pub fn remove(&mut self, key: Key, key_of: impl Fn(u32) -> Key) -> Option<u32> {
        if self.slots.is_empty() {
            return None;
        }
        let mask = self.mask();
        let mut i = hash(key) as usize & mask;
        loop {
            let id = self.slots[i];
            if id == EMPTY {
                return None;
            }
            if key_of(id) == key {
                break;
            }
            i = (i + 1) & mask;
        }
        let removed = self.slots[i];
        // Backward-shift deletion.
        let mut hole = i;
        let mut j = (i + 1) & mask;
        loop {
            let id = self.slots[j];
            if id == EMPTY {
                break;
            }
            let home = hash(key_of(id)) as usize & mask;
            // Move `id` into the hole when its home is not cyclically in (hole, j].
            let dist_home = j.wrapping_sub(home) & mask;
            let dist_hole = j.wrapping_sub(hole) & mask;
            if dist_home >= dist_hole {
                self.slots[hole] = id;
                hole = j;
            }
            j = (j + 1) & mask;
        }
        self.slots[hole] = EMPTY;
        self.len -= 1;
        Some(removed)
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
                    let expected = model.remove(&k).map(|_| u32::from(k));
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
