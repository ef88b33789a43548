//! A set of cell ids as one bit per id (ids are dense arena indexes).

/// A bit set over cell ids, growing to the largest id inserted.
#[derive(Clone, Debug, Default)]
pub(super) struct IdBits {
    words: Vec<u64>,
}

impl IdBits {
    /// Adds `id`.
    #[inline]
    pub(super) fn insert(&mut self, id: u32) {
        let word = id as usize / 64;
        if word >= self.words.len() {
            self.words.resize(word + 1, 0);
        }
        self.words[word] |= 1 << (id % 64);
    }

    /// Whether `id` is in the set.
    #[inline]
    pub(super) fn contains(&self, id: u32) -> bool {
        self.words
            .get(id as usize / 64)
            .is_some_and(|w| w & (1 << (id % 64)) != 0)
    }

    /// Removes `id`; returns whether it was in the set.
    #[inline]
    pub(super) fn remove(&mut self, id: u32) -> bool {
        let Some(word) = self.words.get_mut(id as usize / 64) else {
            return false;
        };
        let bit = 1 << (id % 64);
        let was = *word & bit != 0;
        *word &= !bit;
        was
    }

    /// Bytes held.
    pub(super) fn memory_bytes(&self) -> usize {
        self.words.capacity() * size_of::<u64>()
    }
}
