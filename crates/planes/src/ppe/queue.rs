//! The priority queue of PPE's candidates: least increment first, ties broken by the packed
//! action, so the order of the pops is a function of the queued set alone.
//!
//! Buckets of the key's floating-point exponent and top mantissa bits (64 per octave), each
//! a binary heap, and a bitmap of the non-empty ones: a pop touches only the heap of the
//! least non-empty bucket, which stays small and in cache while the whole queue holds
//! hundreds of thousands of candidates.

use std::cmp::Reverse;
use std::collections::hash_map::Entry;
use std::collections::{BinaryHeap, HashMap};
use std::hash::{BuildHasherDefault, Hasher};

/// Keys below `2^-MIN_OCTAVE` share the first bucket.
const MIN_OCTAVE: u64 = 80;
/// Sub-buckets per octave (`2^SUB_BITS`).
const SUB_BITS: u64 = 6;
/// Buckets: octaves `2^-MIN_OCTAVE … 2^0`, then one for keys of 1 and above.
const BUCKETS: usize = ((MIN_OCTAVE << SUB_BITS) + 2) as usize;
const WORDS: usize = BUCKETS.div_ceil(64);

/// A queue entry: the total-order image of the key (high 64 bits) and the packed action.
pub type Item = u128;

/// The total-order image of `key` as an unsigned integer (as [`f64::total_cmp`]).
pub fn order_bits(key: f64) -> u64 {
    let b = key.to_bits();
    if b >> 63 == 1 { !b } else { b | (1 << 63) }
}

/// The key of [`order_bits`]' image `o`.
pub fn key_of(o: u64) -> f64 {
    f64::from_bits(if o >> 63 == 1 { o & !(1 << 63) } else { !o })
}

/// The entry of `key` and the packed action.
pub fn item(key: f64, action: u64) -> Item {
    (u128::from(order_bits(key)) << 64) | u128::from(action)
}

/// Key and packed action of an entry.
pub fn split(item: Item) -> (f64, u64) {
    (key_of((item >> 64) as u64), item as u64)
}

/// The bucket of total-order image `o`, monotone in `o`.
fn bucket(o: u64) -> usize {
    const ONE: u64 = (1 << 63) | 1.0f64.to_bits();
    const LOW: u64 = (1 << 63) | ((1023 - MIN_OCTAVE) << 52);
    if o < LOW {
        0
    } else if o >= ONE {
        BUCKETS - 1
    } else {
        (((o - LOW) >> (52 - SUB_BITS)) + 1) as usize
    }
}

/// The bucketed min-queue.
pub struct Queue {
    heaps: Vec<BinaryHeap<Reverse<Item>>>,
    nonempty: [u64; WORDS],
    /// No bucket below this word of `nonempty` is non-empty.
    lowest: usize,
    len: usize,
}

impl Default for Queue {
    fn default() -> Self {
        Self {
            heaps: (0..BUCKETS).map(|_| BinaryHeap::new()).collect(),
            nonempty: [0; WORDS],
            lowest: WORDS,
            len: 0,
        }
    }
}

impl Queue {
    pub fn push(&mut self, item: Item) {
        let b = bucket((item >> 64) as u64);
        self.heaps[b].push(Reverse(item));
        self.nonempty[b / 64] |= 1 << (b % 64);
        self.lowest = self.lowest.min(b / 64);
        self.len += 1;
    }

    /// The least non-empty bucket.
    fn first(&self) -> Option<usize> {
        let words = self.nonempty.get(self.lowest..)?;
        let w = self.lowest + words.iter().position(|&w| w != 0)?;
        Some(w * 64 + self.nonempty[w].trailing_zeros() as usize)
    }

    pub fn peek(&self) -> Option<Item> {
        let b = self.first()?;
        self.heaps[b].peek().map(|r| r.0)
    }

    pub fn pop(&mut self) -> Option<Item> {
        let Some(b) = self.first() else {
            self.lowest = WORDS;
            return None;
        };
        self.lowest = b / 64;
        let heap = &mut self.heaps[b];
        let top = heap.pop().map(|r| r.0);
        if heap.is_empty() {
            self.nonempty[b / 64] &= !(1 << (b % 64));
        }
        self.len -= 1;
        top
    }

    /// Removes and returns every entry (in no particular order).
    pub fn take_all(&mut self) -> Vec<Item> {
        let mut out = Vec::with_capacity(self.len);
        for heap in &mut self.heaps {
            out.extend(heap.drain().map(|r| r.0));
        }
        self.nonempty = [0; WORDS];
        self.lowest = WORDS;
        self.len = 0;
        out
    }
}

/// The least key of the merge candidate queued for each unordered pair of planes (a merge
/// is queued again only with a smaller key, which keeps the queue small).
#[derive(Default)]
pub struct Queued(HashMap<u64, f64, BuildHasherDefault<PairHasher>>);

impl Queued {
    fn pair(a: u32, b: u32) -> u64 {
        (u64::from(a.min(b)) << 32) | u64::from(a.max(b))
    }

    /// Whether two pairs are the same unordered pair.
    pub fn same(x: (u32, u32), y: (u32, u32)) -> bool {
        Self::pair(x.0, x.1) == Self::pair(y.0, y.1)
    }

    /// Records a merge of `a` and `b` queued with `key` if none is recorded or `key` is
    /// smaller than the recorded one; returns whether it did.
    pub fn lower(&mut self, a: u32, b: u32, key: f64) -> bool {
        match self.0.entry(Self::pair(a, b)) {
            Entry::Vacant(v) => {
                v.insert(key);
                true
            }
            Entry::Occupied(mut o) if key < *o.get() => {
                o.insert(key);
                true
            }
            Entry::Occupied(_) => false,
        }
    }

    /// Records a merge of `a` and `b` queued with `key`, replacing any record.
    pub fn set(&mut self, a: u32, b: u32, key: f64) {
        self.0.insert(Self::pair(a, b), key);
    }

    pub fn remove(&mut self, a: u32, b: u32) {
        self.0.remove(&Self::pair(a, b));
    }

    pub fn clear(&mut self) {
        self.0.clear();
    }
}

/// Multiplicative hash of a pair of plane ids.
#[derive(Default)]
pub struct PairHasher(u64);

impl Hasher for PairHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0 ^ x).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }

    fn finish(&self) -> u64 {
        self.0 ^ (self.0 >> 32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_bits_follow_total_cmp_and_invert() {
        let keys = [
            -1.0,
            -0.0,
            0.0,
            1e-300,
            2.0f64.powi(-81),
            2.0f64.powi(-80),
            1e-9,
            0.01,
            0.04,
            0.999,
            1.0,
            7.5,
        ];
        for w in keys.windows(2) {
            assert!(order_bits(w[0]) < order_bits(w[1]), "{} {}", w[0], w[1]);
            assert!(bucket(order_bits(w[0])) <= bucket(order_bits(w[1])));
        }
        for k in keys {
            assert_eq!(key_of(order_bits(k)).to_bits(), k.to_bits());
        }
    }

    #[test]
    fn pops_in_key_then_action_order() {
        let mut q = Queue::default();
        let mut all = Vec::new();
        let mut x = 12345u64;
        for i in 0..5000u64 {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let key = match i % 4 {
                0 => 0.0,
                1 => (x >> 11) as f64 / (1u64 << 53) as f64 * 0.05,
                2 => 1e-30 * (x % 7) as f64,
                _ => 3.0 * (x % 3) as f64,
            };
            let it = item(key, x % 97);
            q.push(it);
            all.push(it);
        }
        all.sort_unstable();
        assert_eq!(q.len, all.len());
        for want in all {
            assert_eq!(q.peek(), Some(want));
            assert_eq!(q.pop(), Some(want));
        }
        assert_eq!(q.pop(), None);
    }
}
