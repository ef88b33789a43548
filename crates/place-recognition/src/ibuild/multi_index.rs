//! Exact sub-linear first-match search by multi-index hashing (Norouzi, Punjani and Fleet,
//! "Fast search in Hamming space with multi-index hashing", CVPR 2012).
//!
//! The 512 bits of a word are split into `m` disjoint substrings, and table `k` maps the value
//! of substring `k` to the words having it. By the pigeonhole principle, `H(q, v) ≤ δ − 1`
//! implies that at least one substring of `q` and `v` differs in at most `r = ⌊(δ − 1)/m⌋` bits.
//! Probing, in every table, all keys within radius `r` of the query's substring therefore finds
//! every word with `H < δ`; each candidate is verified with the full Hamming distance, and the
//! lowest verified index is the answer — exactly the index of the thesis' linear first-match
//! scan (Khan 2017, Fig. 4.9).
//!
//! Buckets are singly linked lists of word indices in ascending order (one `next` array per
//! table, heads and tails in a hash map), so appending a word is O(m), a bucket walk stops at the
//! first index not below the best match found so far, and memory stays `4·m` bytes per word plus
//! the table heads.
//!
//! **Choice of `m` (ours).** For each `m` with `r = ⌊(δ − 1)/m⌋ ≤ 2` and substrings of at most
//! 32 bits (`m ≥ 16`), the expected cost of one query on uniformly random words is
//! `m · V(s, r) · (1 + N_ref / 2^s)`: `m · V(s, r)` probes, `V(s, r) = Σ_{k≤r} C(s, k)` keys
//! within radius `r` of an `s = 512/m`-bit key, each bucket holding `N_ref / 2^s` words on
//! average. The `m` of least cost is taken, with `N_ref = 2^18` words, the order of an IBuILD
//! vocabulary after a few thousand images. This gives, e.g., `m = 30, r = 0` for `δ = 30`,
//! `m = 21, r = 1` for `δ = 40`, `m = 27, r = 2` for `δ = 80` and `m = 40, r = 2` for `δ = 120`.
//! Above `δ ≈ 100` too many candidates must be verified and the linear scan is faster at any
//! vocabulary size; [`MultiIndexLayout::linear_crossover`] estimates where hashing starts to
//! pay off (see `benches/vocabulary_search.rs`).

use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::hash::{BuildHasherDefault, Hasher};

use crate::{Bits512, PlaceError, Result};

/// Vocabulary size the cost model of [`MultiIndexLayout::for_delta`] assumes (ours).
const REFERENCE_WORDS: f64 = 262_144.0;

/// End of a bucket list.
const NONE: u32 = u32::MAX;

/// How multi-index hashing splits the 512 bits for a matching threshold δ.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MultiIndexLayout {
    substrings: u32,
    radius: u32,
}

impl MultiIndexLayout {
    /// The layout of least expected cost for the threshold `delta` (`H < δ`, δ in 1..=512),
    /// with the search radius per substring `r ≤ 2` (rule in the module documentation).
    pub fn for_delta(delta: u32) -> Result<Self> {
        if !(1..=512).contains(&delta) {
            return Err(PlaceError::InvalidParameter {
                name: "delta",
                reason: format!("must be in 1..=512 bits, got {delta}"),
            });
        }
        let d = delta - 1;
        let mut best: Option<(f64, u32)> = None;
        for m in 16..=512u32 {
            let r = d / m;
            if r > 2 {
                continue;
            }
            let s = 512.0 / f64::from(m);
            let cost = f64::from(m) * keys_within(s, r) * (1.0 + REFERENCE_WORDS / s.exp2());
            if best.is_none_or(|(c, _)| cost < c) {
                best = Some((cost, m));
            }
        }
        // m = 512 always qualifies (r = ⌊511/512⌋ = 0), so `best` is set.
        let m = best.map_or(512, |(_, m)| m);
        Ok(Self {
            substrings: m,
            radius: d / m,
        })
    }

    /// Number of substrings (and hash tables) `m`.
    pub fn substrings(&self) -> u32 {
        self.substrings
    }

    /// Search radius per substring, `r = ⌊(δ − 1)/m⌋`.
    pub fn radius(&self) -> u32 {
        self.radius
    }

    /// The vocabulary size above which this layout is expected to answer faster than the
    /// linear scan, `None` when it never is (large δ). Cost model (ours, measured with
    /// `benches/vocabulary_search.rs`): in units of one word comparison of the scan, a probe
    /// costs 10 and a candidate 46 (a bucket-list step and a word, both cache misses); the
    /// hashing cost `P·(10 + 46·n/2^s)` with `P = m·V(s, r)` probes is compared with `n`.
    pub fn linear_crossover(&self) -> Option<usize> {
        const PROBE: f64 = 10.0;
        const CANDIDATE: f64 = 46.0;
        let s = 512.0 / f64::from(self.substrings);
        let probes = f64::from(self.substrings) * keys_within(s, self.radius);
        let per_word = 1.0 - probes * CANDIDATE / s.exp2();
        (per_word > 0.0).then(|| (probes * PROBE / per_word).ceil() as usize)
    }

    /// First bit and width of substring `k`: the first `512 mod m` substrings are one bit wider.
    pub fn substring(&self, k: u32) -> (u32, u32) {
        let base = 512 / self.substrings;
        let extra = 512 % self.substrings;
        let width = base + u32::from(k < extra);
        (k * base + k.min(extra), width)
    }
}

/// `Σ_{k ≤ r} C(s, k)` for a real width `s` (the cost model only).
fn keys_within(s: f64, r: u32) -> f64 {
    match r {
        0 => 1.0,
        1 => 1.0 + s,
        _ => 1.0 + s + s * (s - 1.0) / 2.0,
    }
}

/// Bits `start..start + width` of a word (`width ≤ 32`).
#[inline]
fn substring_key(word: &Bits512, start: u32, width: u32) -> u32 {
    let w = (start / 64) as usize;
    let o = start % 64;
    let mut v = word.0[w] >> o;
    if o + width > 64 {
        v |= word.0[w + 1] << (64 - o);
    }
    (v & ((1u64 << width) - 1)) as u32
}

/// Hasher of 32-bit keys: a multiplicative hash folded so that low and high bits both mix.
///
/// Kept instead of `rustc_hash::FxBuildHasher` for a measured reason: with Fx the table
/// search got 42 % slower on a 10⁶-word vocabulary at δ = 80 (212 ms against 149 ms per 64
/// queries) and 38 % faster on 10⁴ words at δ = 120, in the same criterion run
/// (`cargo bench -p raypath-place-recognition --bench vocabulary_search -- multi_index`);
/// large vocabularies are where the multi-index search has to pay off.
#[derive(Default)]
struct KeyHasher(u64);

impl Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ u64::from(b)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
    }

    fn write_u32(&mut self, key: u32) {
        let h = u64::from(key).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        self.0 = h ^ (h >> 32);
    }
}

/// One hash table: substring value → (first, last) index of its ascending bucket list.
#[derive(Debug, Default, Clone)]
struct Table {
    start: u32,
    width: u32,
    heads: HashMap<u32, (u32, u32), BuildHasherDefault<KeyHasher>>,
    next: Vec<u32>,
}

impl Table {
    /// Appends word `id` (the largest index so far) to the bucket of `key`.
    fn push(&mut self, id: u32, key: u32) {
        self.next.push(NONE);
        match self.heads.entry(key) {
            Entry::Occupied(mut e) => {
                let (_, tail) = e.get_mut();
                self.next[*tail as usize] = id;
                *tail = id;
            }
            Entry::Vacant(e) => {
                e.insert((id, id));
            }
        }
    }

    /// Removes `id` from the bucket of `key`.
    fn remove(&mut self, id: u32, key: u32) {
        let Entry::Occupied(mut e) = self.heads.entry(key) else {
            return;
        };
        let (head, tail) = *e.get();
        let after = self.next[id as usize];
        if head == id {
            if after == NONE {
                e.remove();
            } else {
                e.get_mut().0 = after;
            }
        } else {
            let mut p = head;
            while p != NONE && self.next[p as usize] != id {
                p = self.next[p as usize];
            }
            if p == NONE {
                return;
            }
            self.next[p as usize] = after;
            if tail == id {
                e.get_mut().1 = p;
            }
        }
        self.next[id as usize] = NONE;
    }

    /// Inserts `id` into the bucket of `key`, keeping it ascending.
    fn insert_sorted(&mut self, id: u32, key: u32) {
        match self.heads.entry(key) {
            Entry::Vacant(e) => {
                e.insert((id, id));
                self.next[id as usize] = NONE;
            }
            Entry::Occupied(mut e) => {
                let (head, tail) = *e.get();
                if id < head {
                    self.next[id as usize] = head;
                    e.get_mut().0 = id;
                    return;
                }
                let mut p = head;
                while self.next[p as usize] < id {
                    p = self.next[p as usize];
                }
                self.next[id as usize] = self.next[p as usize];
                self.next[p as usize] = id;
                if tail == p {
                    e.get_mut().1 = id;
                }
            }
        }
    }

    /// Walks the bucket of `key` below `best` and lowers `best` to the first verified match.
    #[inline]
    fn probe(&self, key: u32, words: &[Bits512], query: &Bits512, delta: u32, best: &mut u32) {
        let Some(&(head, _)) = self.heads.get(&key) else {
            return;
        };
        let mut id = head;
        while id < *best {
            if words[id as usize].hamming(query) < delta {
                *best = id;
                return;
            }
            id = self.next[id as usize];
        }
    }
}

/// The multi-index hash tables of a vocabulary.
#[derive(Clone, Debug)]
pub(crate) struct MultiIndex {
    layout: MultiIndexLayout,
    tables: Vec<Table>,
}

impl MultiIndex {
    /// Empty tables for the threshold `delta`.
    pub(crate) fn new(delta: u32) -> Result<Self> {
        let layout = MultiIndexLayout::for_delta(delta)?;
        let tables = (0..layout.substrings)
            .map(|k| {
                let (start, width) = layout.substring(k);
                Table {
                    start,
                    width,
                    ..Table::default()
                }
            })
            .collect();
        Ok(Self { layout, tables })
    }

    /// The layout in use.
    pub(crate) fn layout(&self) -> MultiIndexLayout {
        self.layout
    }
}

impl super::search::FirstMatch for MultiIndex {
    fn push(&mut self, id: u32, word: &Bits512) {
        for t in &mut self.tables {
            let key = substring_key(word, t.start, t.width);
            t.push(id, key);
        }
    }

    fn replace(&mut self, id: u32, old: &Bits512, new: &Bits512) {
        for t in &mut self.tables {
            let (a, b) = (
                substring_key(old, t.start, t.width),
                substring_key(new, t.start, t.width),
            );
            if a != b {
                t.remove(id, a);
                t.insert_sorted(id, b);
            }
        }
    }

    fn first_match(&self, words: &[Bits512], query: &Bits512, delta: u32) -> Option<u32> {
        let mut best = NONE;
        // Exact keys in every table first, then radius 1, then 2: near matches are found early
        // and cut the later bucket walks short.
        for radius in 0..=self.layout.radius {
            for t in &self.tables {
                let key = substring_key(query, t.start, t.width);
                match radius {
                    0 => t.probe(key, words, query, delta, &mut best),
                    1 => {
                        for i in 0..t.width {
                            t.probe(key ^ (1 << i), words, query, delta, &mut best);
                        }
                    }
                    _ => {
                        for i in 0..t.width {
                            let ki = key ^ (1 << i);
                            for j in i + 1..t.width {
                                t.probe(ki ^ (1 << j), words, query, delta, &mut best);
                            }
                        }
                    }
                }
                if best == 0 {
                    return Some(0);
                }
            }
        }
        (best != NONE).then_some(best)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_keeps_radius_small_and_covers_all_bits() {
        for delta in 1..=512 {
            let l = MultiIndexLayout::for_delta(delta).unwrap();
            assert!(l.radius() <= 2, "delta {delta}");
            assert_eq!(l.radius(), (delta - 1) / l.substrings());
            let mut next = 0;
            for k in 0..l.substrings() {
                let (start, width) = l.substring(k);
                assert_eq!(start, next);
                assert!((1..=32).contains(&width));
                next = start + width;
            }
            assert_eq!(next, 512);
        }
        assert!(MultiIndexLayout::for_delta(0).is_err());
        assert!(MultiIndexLayout::for_delta(513).is_err());
        let l80 = MultiIndexLayout::for_delta(80).unwrap();
        assert_eq!((l80.substrings(), l80.radius()), (27, 2));
        // Hashing pays off early at small δ, from ~10⁵ words at δ = 80, never at δ = 120.
        let crossover = |d| MultiIndexLayout::for_delta(d).unwrap().linear_crossover();
        assert!(crossover(40).is_some_and(|n| n < 10_000));
        assert!(crossover(80).is_some_and(|n| (50_000..200_000).contains(&n)));
        assert_eq!(crossover(120), None);
    }

    #[test]
    fn substring_key_crosses_word_boundaries() {
        let mut w = Bits512::zeros();
        w.set_bit(63, true);
        w.set_bit(64, true);
        w.set_bit(70, true);
        assert_eq!(substring_key(&w, 60, 12), 0b0100_0001_1000);
        assert_eq!(substring_key(&w, 64, 1), 1);
        assert_eq!(substring_key(&w, 0, 32), 0);
    }

    #[test]
    fn remove_and_insert_keep_buckets_sorted() {
        let mut t = Table::default();
        for id in 0..5 {
            t.push(id, 7);
        }
        t.remove(2, 7);
        t.remove(0, 7);
        t.remove(4, 7);
        t.insert_sorted(2, 7);
        t.insert_sorted(0, 9);
        let mut ids = Vec::new();
        let mut id = t.heads[&7].0;
        while id != NONE {
            ids.push(id);
            id = t.next[id as usize];
        }
        assert_eq!(ids, vec![1, 2, 3]);
        assert_eq!(t.heads[&7].1, 3);
        assert_eq!(t.heads[&9], (0, 0));
    }
}
