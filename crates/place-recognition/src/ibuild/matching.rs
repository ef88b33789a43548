//! Pose-invariant descriptors by consecutive-frame matching, and merging them into visual words
//! (Khan 2017, §4.4.1, Figs. 4.7 and 4.8).
//!
//! * **Matching** (§4.4.1): every descriptor of `I_t` is matched to its nearest neighbour in
//!   `I_{t+1}` by Hamming distance (ties: the lowest index); a match is kept when `H < δ`, and
//!   the eq. (4.1) centroid of the pair goes to `D̄_t`, in the order of `I_t`'s descriptors.
//!   The thesis does not say whether matches are mutual; by default they are not (several
//!   descriptors of `I_t` may share a neighbour — Merge removes the resulting near-duplicates),
//!   and [`IbuildConfig::mutual_matching`] also requires `d_t` to be the nearest neighbour of
//!   its match (ours).
//! * **Merge** (Fig. 4.8): a greedy pass in index order; descriptor `i` absorbs every later
//!   surviving descriptor `j` with `H(d̄_i, d̄_j) < δ` and is replaced by their centroid, which
//!   is used for the next `j`. The thesis says the process continues "until no further merging
//!   can take place" but prints a single pass; we run the printed pass, and
//!   [`IbuildConfig::merge_until_fixed_point`] repeats it until a pass merges nothing.
//! * **Centroid**: eq. (4.1) for a pair, i.e. the bitwise OR (ties go to 1). The ablation
//!   [`IbuildConfig::strict_majority`] sends ties to 0, the bitwise AND (ours).

use super::IbuildConfig;
use crate::Bits512;

/// The eq. (4.1) centroid of two descriptors: OR (ties → 1, as printed), or AND for the
/// strict-majority ablation (ties → 0).
#[inline]
pub(crate) fn pair_centroid(a: &Bits512, b: &Bits512, strict_majority: bool) -> Bits512 {
    if strict_majority {
        let mut out = *a;
        for (o, w) in out.0.iter_mut().zip(b.0.iter()) {
            *o &= *w;
        }
        out
    } else {
        // Eq. (4.1) with k = 2: Σ ≥ 1 → 1.
        a.pair_centroid(b)
    }
}

/// Index and distance of the nearest descriptor of `set` (lowest index on ties).
fn nearest(query: &Bits512, set: &[Bits512]) -> Option<(usize, u32)> {
    let mut best: Option<(usize, u32)> = None;
    for (j, d) in set.iter().enumerate() {
        let h = query.hamming(d);
        if best.is_none_or(|(_, b)| h < b) {
            best = Some((j, h));
        }
    }
    best
}

/// Matches the descriptors of the previous frame to those of the current one and returns the
/// centroids of the matched pairs, `D̄_t` (Khan 2017, §4.4.1).
///
/// Each previous descriptor takes its nearest current descriptor (lowest index on ties) and
/// is kept when `H < δ`; with [`IbuildConfig::mutual_matching`] the previous descriptor must
/// also be the nearest of its match. The pair's eq. (4.1) centroid is the OR (ties → 1), or the
/// AND with [`IbuildConfig::strict_majority`]. Output order: the previous frame's.
pub fn match_consecutive(
    previous: &[Bits512],
    current: &[Bits512],
    config: &IbuildConfig,
) -> Vec<Bits512> {
    let mut out = Vec::new();
    for (i, a) in previous.iter().enumerate() {
        let Some((j, h)) = nearest(a, current) else {
            break;
        };
        if h >= config.delta {
            continue;
        }
        let b = &current[j];
        if config.mutual_matching {
            // `a` must be the nearest descriptor of `b` in the previous frame (lowest index on
            // ties).
            if nearest(b, previous).is_none_or(|(k, _)| k != i) {
                continue;
            }
        }
        out.push(pair_centroid(a, b, config.strict_majority));
    }
    out
}

/// Merges near-duplicate descriptors of one image into visual words, `D̂_t` (Khan 2017,
/// Fig. 4.8): one greedy pass in index order as printed — descriptor `i` absorbs each later
/// surviving `j` with `H < δ` and becomes their centroid for the next `j` — or passes until
/// nothing merges with [`IbuildConfig::merge_until_fixed_point`].
pub fn merge_descriptors(mut descriptors: Vec<Bits512>, config: &IbuildConfig) -> Vec<Bits512> {
    loop {
        let merged = merge_pass(&mut descriptors, config.delta, config.strict_majority);
        if !merged || !config.merge_until_fixed_point {
            return descriptors;
        }
    }
}

/// One greedy pass of Fig. 4.8; true when something merged.
fn merge_pass(d: &mut Vec<Bits512>, delta: u32, strict_majority: bool) -> bool {
    let n = d.len();
    let mut alive = vec![true; n];
    let mut merged = false;
    for i in 0..n {
        if !alive[i] {
            continue;
        }
        for j in i + 1..n {
            if alive[j] && d[i].hamming(&d[j]) < delta {
                d[i] = pair_centroid(&d[i], &d[j], strict_majority); // Eq. (4.1)
                alive[j] = false;
                merged = true;
            }
        }
    }
    let mut k = 0;
    d.retain(|_| {
        k += 1;
        alive[k - 1]
    });
    merged
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A descriptor with bits `0..ones` set, plus the listed extra bits.
    fn word(ones: usize, extra: &[usize]) -> Bits512 {
        let mut w = Bits512::zeros();
        for i in (0..ones).chain(extra.iter().copied()) {
            w.set_bit(i, true);
        }
        w
    }

    fn config(delta: u32) -> IbuildConfig {
        IbuildConfig {
            delta,
            ..IbuildConfig::default()
        }
    }

    #[test]
    fn merge_is_one_greedy_pass_with_running_centroid() {
        // a = bits 0..10, b = a + {100, 101}, c = a + {200, 201, 202}, e far away.
        let a = word(10, &[]);
        let b = word(10, &[100, 101]);
        let c = word(10, &[200, 201, 202]);
        let e = word(300, &[]);
        // δ = 4: a–b (2) and a–c (3) merge. After a ∪ b, the running centroid is 5 bits from c,
        // so c survives.
        let out = merge_descriptors(vec![a, b, c, e], &config(4));
        assert_eq!(out, vec![a.pair_centroid(&b), c, e]);
        // δ = 6 merges c into the running centroid too.
        let out = merge_descriptors(vec![a, b, c, e], &config(6));
        assert_eq!(out, vec![a.pair_centroid(&b).pair_centroid(&c), e]);
    }

    #[test]
    fn fixed_point_flag_repeats_passes() {
        // δ = 3. d0–d1 = 3 (no merge), d0–d2 = 2 (merge). The running centroid d0 ∪ d2 ends
        // 1 bit from the survivor d1, which only a second pass merges.
        let d0 = word(10, &[20, 21]);
        let d1 = word(10, &[20, 21, 30, 31, 32]);
        let d2 = word(10, &[20, 21, 30, 31]);
        let single = merge_descriptors(vec![d0, d1, d2], &config(3));
        assert_eq!(single, vec![d0.pair_centroid(&d2), d1]);
        let mut c = config(3);
        c.merge_until_fixed_point = true;
        assert_eq!(merge_descriptors(vec![d0, d1, d2], &c), vec![d1]);
        // Strict majority (AND): d0 ∧ d2 = d0, still 3 from d1 — nothing more to merge.
        c.strict_majority = true;
        assert_eq!(merge_descriptors(vec![d0, d1, d2], &c), vec![d0, d1]);
    }

    #[test]
    fn consecutive_matching_keeps_centroids_below_delta() {
        let prev = vec![word(10, &[]), word(300, &[]), word(20, &[])];
        let cur = vec![word(10, &[400]), word(10, &[450, 451]), word(100, &[])];
        // prev[0] → cur[0] (1 bit); prev[1] has nothing within 5; prev[2] → cur[0] at 11 bits.
        let out = match_consecutive(&prev, &cur, &config(5));
        assert_eq!(out, vec![prev[0].pair_centroid(&cur[0])]);
        let out = match_consecutive(&prev, &cur, &config(12));
        assert_eq!(
            out,
            vec![
                prev[0].pair_centroid(&cur[0]),
                prev[2].pair_centroid(&cur[0])
            ]
        );
        // Mutual: cur[0]'s nearest in prev is prev[0], so prev[2]'s match is dropped.
        let mut c = config(12);
        c.mutual_matching = true;
        assert_eq!(
            match_consecutive(&prev, &cur, &c),
            vec![prev[0].pair_centroid(&cur[0])]
        );
        assert!(match_consecutive(&prev, &[], &c).is_empty());
    }
}
