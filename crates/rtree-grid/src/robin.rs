//! A Robin Hood hash table of cell ids, the storage of the grid's two look-up indexes.
//!
//! Entries are a 4-byte cell id plus a `TAG_BITS`-bit tag chosen by the index (hash bits of
//! the key, or which octants of a block a cell covers) under a home slot the index computes;
//! the table stores no key. Robin Hood insertion keeps the entries of one home slot together
//! and ordered by home, so a look-up visits only its home's entries (the displacement stored
//! in the other `16 − TAG_BITS` bits tells them apart) and a miss stops at the first entry of
//! a later home; deletion shifts the following entries back (no tombstones). A slot is
//! 6 unaligned bytes (one memory access per probe), any slot count. Tables grow (double) at
//! load ⅘ and are built at load 9/10 (compact, for a map at rest).
//!
//! Why not `hashbrown` (or `std`'s map with `rustc-hash`): a keyed map stores the key beside
//! the value — at least 8 + 4 bytes plus a control byte per entry, padded to 16 — and cannot
//! hold several cells under one block key. Here the key is recomputed from the cell (its box
//! or lattice key), so an entry is 6 bytes; the index is part of the map size the
//! `octomap` evaluation compares with OctoMap's `memoryUsage()`.

/// One slot: a cell id and `tag | displacement << TAG_BITS` (all displacement bits set:
/// empty).
#[derive(Clone, Copy, Debug)]
struct Slot {
    id: [u8; 4],
    meta: [u8; 2],
}

impl Slot {
    #[inline]
    fn id(&self) -> u32 {
        u32::from_le_bytes(self.id)
    }

    #[inline]
    fn meta(&self) -> u16 {
        u16::from_le_bytes(self.meta)
    }
}

/// Cell ids with `TAG_BITS`-bit tags by home slot.
#[derive(Clone, Debug, Default)]
pub(crate) struct RobinTable<const TAG_BITS: u32> {
    slots: Vec<Slot>,
    len: usize,
}

impl<const TAG_BITS: u32> RobinTable<TAG_BITS> {
    /// Displacement marking an empty slot (the largest one).
    const FREE: u16 = u16::MAX >> TAG_BITS;
    const EMPTY: Slot = Slot {
        id: [0; 4],
        meta: u16::MAX.to_le_bytes(),
    };

    /// An empty table sized for `entries` entries at load 9/10 (at least 64 slots).
    pub(crate) fn for_entries(entries: usize) -> Self {
        Self::with_slots((entries * 10).div_ceil(9).max(64))
    }

    /// An empty table of `slots` slots.
    pub(crate) fn with_slots(slots: usize) -> Self {
        Self {
            slots: vec![Self::EMPTY; slots],
            len: 0,
        }
    }

    #[inline]
    fn disp(slot: &Slot) -> u16 {
        slot.meta() >> TAG_BITS
    }

    #[inline]
    fn tag(slot: &Slot) -> u16 {
        slot.meta() & ((1 << TAG_BITS) - 1)
    }

    #[inline]
    fn slot(id: u32, tag: u16, disp: u16) -> Slot {
        Slot {
            id: id.to_le_bytes(),
            meta: (tag | (disp << TAG_BITS)).to_le_bytes(),
        }
    }

    /// Number of slots.
    #[inline]
    pub(crate) fn slots(&self) -> usize {
        self.slots.len()
    }

    /// Number of entries.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// Bytes of the slot array.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.slots.capacity() * size_of::<Slot>()
    }

    /// Whether `extra` more entries keep the load at most ⅘ (else the owner grows it).
    #[inline]
    pub(crate) fn has_room(&self, extra: usize) -> bool {
        (self.len + extra) * 5 <= self.slots() * 3
    }

    /// An empty table of twice the slots (at least 64).
    pub(crate) fn doubled(&self) -> Self {
        Self::with_slots((self.slots() * 2).max(64))
    }

    /// The home slot of hash `h` (multiply-shift onto any slot count).
    #[inline]
    pub(crate) fn home(&self, h: u64) -> usize {
        ((u128::from(h) * self.slots() as u128) >> 64) as usize
    }

    #[inline]
    fn next(&self, i: usize) -> usize {
        if i + 1 == self.slots() { 0 } else { i + 1 }
    }

    /// The first entry under `home` for which `accept(id, tag)` holds.
    #[inline]
    pub(crate) fn find(&self, home: usize, accept: impl FnMut(u32, u16) -> bool) -> Option<u32> {
        self.position(home, accept).map(|i| self.slots[i].id())
    }

    /// The slot of the first entry under `home` for which `accept(id, tag)` holds.
    #[inline]
    fn position(&self, home: usize, mut accept: impl FnMut(u32, u16) -> bool) -> Option<usize> {
        if self.len == 0 {
            return None;
        }
        let mut i = home;
        let mut d = 0u16;
        loop {
            let slot = self.slots[i];
            let di = Self::disp(&slot);
            // Empty, or the entries of a later home begin: no more entries under `home`.
            if di == Self::FREE || di < d {
                return None;
            }
            if di == d && accept(slot.id(), Self::tag(&slot)) {
                return Some(i);
            }
            i = self.next(i);
            d += 1;
        }
    }

    /// Adds an entry under `home`; `false` (nothing added) when a displacement would not
    /// fit or the table is full — the caller grows the table.
    pub(crate) fn insert(&mut self, home: usize, id: u32, tag: u16) -> bool {
        if self.slots() == 0 || !self.fits(home) {
            return false;
        }
        let (mut id, mut tag, mut d) = (id, tag, 0u16);
        let mut i = home;
        loop {
            let here = self.slots[i];
            let di = Self::disp(&here);
            if di == Self::FREE {
                self.slots[i] = Self::slot(id, tag, d);
                self.len += 1;
                return true;
            }
            if di < d {
                // Robin Hood: the richer entry moves on.
                self.slots[i] = Self::slot(id, tag, d);
                (id, tag, d) = (here.id(), Self::tag(&here), di);
            }
            i = self.next(i);
            d += 1;
        }
    }

    /// Whether inserting under `home` keeps every displacement below `FREE` (a dry run of
    /// [`Self::insert`]; `false` also for a full table).
    fn fits(&self, home: usize) -> bool {
        let mut i = home;
        let mut d = 0u16;
        for _ in 0..self.slots() {
            let di = Self::disp(&self.slots[i]);
            if di == Self::FREE {
                return true;
            }
            d = d.min(di);
            if d + 1 == Self::FREE {
                return false;
            }
            i = self.next(i);
            d += 1;
        }
        false
    }

    /// Removes the first entry under `home` for which `matches(id, tag)` holds; returns
    /// whether one was found.
    pub(crate) fn remove(&mut self, home: usize, matches: impl FnMut(u32, u16) -> bool) -> bool {
        let Some(mut i) = self.position(home, matches) else {
            return false;
        };
        // Backward shift: pull the following displaced entries one slot closer to home.
        loop {
            let j = self.next(i);
            let next = self.slots[j];
            let dj = Self::disp(&next);
            if dj == Self::FREE || dj == 0 {
                self.slots[i] = Self::EMPTY;
                break;
            }
            self.slots[i] = Self::slot(next.id(), Self::tag(&next), dj - 1);
            i = j;
        }
        self.len -= 1;
        true
    }

    /// The ids of all entries (with repeats), emptying the table.
    pub(crate) fn drain_ids(&mut self) -> Vec<u32> {
        let ids = self
            .slots
            .iter()
            .filter(|s| Self::disp(s) != Self::FREE)
            .map(Slot::id)
            .collect();
        self.slots.fill(Self::EMPTY);
        self.len = 0;
        ids
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use proptest::prelude::*;

    use super::*;

    proptest! {
        /// Against a multimap from home to (id, tag): homes collide on purpose (few slots).
        #[test]
        fn behaves_like_a_multimap(ops in prop::collection::vec((0usize..40, 0u32..30, any::<bool>()), 1..400)) {
            let mut table = RobinTable::<8>::with_slots(48);
            let mut model: HashMap<usize, Vec<u32>> = HashMap::new();
            let tag_of = |id: u32| (id % 7) as u16;
            for (home, id, insert) in ops {
                if insert {
                    if table.insert(home, id, tag_of(id)) {
                        model.entry(home).or_default().push(id);
                    }
                } else {
                    let present = model.get(&home).is_some_and(|v| v.contains(&id));
                    prop_assert_eq!(table.remove(home, |i, t| i == id && t == tag_of(id)), present);
                    if let Some(v) = model.get_mut(&home).filter(|_| present) {
                        let at = v.iter().position(|&i| i == id).unwrap_or(0);
                        v.swap_remove(at);
                    }
                }
                prop_assert_eq!(table.len, model.values().map(Vec::len).sum::<usize>());
            }
            for home in 0..40 {
                for id in 0..30 {
                    let present = model.get(&home).is_some_and(|v| v.contains(&id));
                    let found = table.find(home, |i, t| i == id && t == tag_of(id));
                    prop_assert_eq!(found.is_some(), present);
                }
            }
        }
    }
}
