//! Pole maps from many local maps (Schaefer 2020, §12.4.2): trajectory segments, merging of
//! poles whose ground-plane squares overlap (score-weighted), and the c-of-w dynamic-object
//! filter.

use std::collections::VecDeque;

use nalgebra::Point3;

use crate::pole::Pole;

/// A trajectory segment: the scans of one local map.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Segment {
    /// Indices of the scans in the segment, in order.
    pub scans: Vec<usize>,
    /// The scan whose pose centres the local map (nearest to the middle of the segment).
    pub center: usize,
}

/// Segments of a trajectory by travelled distance `d` (Schaefer 2020, §12.4.2; `ncltpoles.py`):
/// segment `i` holds the scans with `interval·i ≤ d ≤ interval·i + length`, centred at the scan
/// nearest to `interval·i + length/2`. Empty segments are skipped.
pub fn segments(positions: &[Point3<f64>], interval_m: f64, length_m: f64) -> Vec<Segment> {
    if positions.is_empty()
        || interval_m.is_nan()
        || length_m.is_nan()
        || interval_m <= 0.0
        || length_m <= 0.0
    {
        return Vec::new();
    }
    let mut travelled = Vec::with_capacity(positions.len());
    let mut d = 0.0;
    for (k, p) in positions.iter().enumerate() {
        if let Some(prev) = k.checked_sub(1).and_then(|j| positions.get(j)) {
            let step = (p - prev).norm();
            if step.is_finite() {
                d += step;
            }
        }
        travelled.push(d);
    }
    let total = d;
    let count = (total / interval_m).floor() as usize + 1;
    let mut out = Vec::new();
    let mut first = 0;
    for i in 0..count {
        let lo = interval_m * i as f64;
        let hi = lo + length_m;
        while first < travelled.len() && travelled[first] < lo {
            first += 1;
        }
        let scans: Vec<usize> = (first..travelled.len())
            .take_while(|&k| travelled[k] <= hi)
            .collect();
        if scans.is_empty() {
            continue;
        }
        let mid = lo + 0.5 * length_m;
        let center = scans
            .iter()
            .copied()
            .min_by(|&a, &b| {
                (travelled[a] - mid)
                    .abs()
                    .total_cmp(&(travelled[b] - mid).abs())
            })
            .unwrap_or(first);
        out.push(Segment { scans, center });
    }
    out
}

/// Union–find root of `i` (path halving).
pub(crate) fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// Connected components of the overlap graph of the poles' ground-plane squares (closed
/// intervals on both axes; transitive, as `cluster.py`). Returns a component id per pole.
pub fn overlap_clusters(poles: &[Pole]) -> Vec<usize> {
    let n = poles.len();
    let mut parent: Vec<usize> = (0..n).collect();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| poles[a].x.total_cmp(&poles[b].x));
    let max_width = poles.iter().map(|p| p.width).fold(0.0, f64::max);
    for (k, &i) in order.iter().enumerate() {
        for &j in &order[k + 1..] {
            if poles[j].x - poles[i].x > max_width {
                break;
            }
            if poles[i].overlaps(&poles[j]) {
                let (a, b) = (find(&mut parent, i), find(&mut parent, j));
                if a != b {
                    parent[a] = b;
                }
            }
        }
    }
    (0..n).map(|i| find(&mut parent, i)).collect()
}

/// Merges poles (e.g. of all local maps) into a map: overlap clusters with at least
/// `min_members` poles become one pole, the score-weighted mean of centre, heights and
/// widths, with the mean score (Schaefer 2020, §12.4.2; NCLT `n_mapdetections` = 3, KITTI 1).
pub fn merge_poles(poles: &[Pole], min_members: usize) -> Vec<Pole> {
    let ids = overlap_clusters(poles);
    let mut order: Vec<usize> = (0..poles.len()).collect();
    order.sort_by_key(|&i| ids[i]);
    let mut out = Vec::new();
    for group in order.chunk_by(|&a, &b| ids[a] == ids[b]) {
        if group.len() < min_members.max(1) {
            continue;
        }
        let mut acc = [0.0f64; 5];
        let (mut wsum, mut score_sum) = (0.0, 0.0);
        for &i in group {
            let p = &poles[i];
            let w = p.score.max(1e-9);
            for (a, v) in acc.iter_mut().zip([p.x, p.y, p.z_start, p.z_end, p.width]) {
                *a += w * v;
            }
            wsum += w;
            score_sum += p.score;
        }
        let [x, y, z_start, z_end, width] = acc.map(|a| a / wsum);
        out.push(Pole {
            x,
            y,
            z_start,
            z_end,
            width,
            score: score_sum / group.len() as f64,
        });
    }
    out.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    out
}

/// The c-of-w dynamic-object filter (Schaefer 2020, §12.4.2–§12.4.3): a pole of the newest local
/// map is active when it was seen (overlapping squares) in at least `c` of the last `w` local maps,
/// the newest included (localization: c = 2, w = 3).
#[derive(Clone, Debug)]
pub struct SlidingWindowFilter {
    c: usize,
    w: usize,
    window: VecDeque<Vec<Pole>>,
}

impl SlidingWindowFilter {
    /// A filter with `c ≤ w` (both at least 1; clamped).
    pub fn new(c: usize, w: usize) -> Self {
        let w = w.max(1);
        Self {
            c: c.clamp(1, w),
            w,
            window: VecDeque::with_capacity(w),
        }
    }

    /// Adds the poles of the newest local map (all in one common frame) and returns its
    /// active poles.
    pub fn push(&mut self, poles: Vec<Pole>) -> Vec<Pole> {
        if self.window.len() == self.w {
            self.window.pop_front();
        }
        let active = poles
            .iter()
            .filter(|p| {
                1 + self
                    .window
                    .iter()
                    .filter(|map| map.iter().any(|q| q.overlaps(p)))
                    .count()
                    >= self.c
            })
            .copied()
            .collect();
        self.window.push_back(poles);
        active
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pole(x: f64, y: f64, width: f64, score: f64) -> Pole {
        Pole {
            x,
            y,
            z_start: 0.0,
            z_end: 2.0,
            width,
            score,
        }
    }

    #[test]
    fn segments_cover_the_trajectory() {
        let positions: Vec<Point3<f64>> = (0..31)
            .map(|i| Point3::new(0.5 * i as f64, 0.0, 0.0))
            .collect();
        let segs = segments(&positions, 3.0, 5.0);
        assert_eq!(segs.len(), 6);
        assert_eq!(segs[0].scans, (0..=10).collect::<Vec<_>>());
        assert_eq!(segs[0].center, 5);
        assert_eq!(segs[1].scans.first(), Some(&6));
    }

    #[test]
    fn overlapping_poles_merge_weighted_by_score() {
        let poles = [
            pole(0.0, 0.0, 0.4, 0.9),
            pole(0.3, 0.0, 0.4, 0.6),
            pole(5.0, 5.0, 0.2, 0.7),
        ];
        let merged = merge_poles(&poles, 1);
        assert_eq!(merged.len(), 2);
        assert!((merged[0].x - 0.12).abs() < 1e-12);
        assert!((merged[0].score - 0.75).abs() < 1e-12);
        assert_eq!(merge_poles(&poles, 2).len(), 1);
    }

    #[test]
    fn sliding_window_needs_c_detections() {
        let mut filter = SlidingWindowFilter::new(2, 3);
        assert!(filter.push(vec![pole(0.0, 0.0, 0.3, 1.0)]).is_empty());
        assert_eq!(filter.push(vec![pole(0.1, 0.0, 0.3, 1.0)]).len(), 1);
        assert!(filter.push(vec![pole(9.0, 0.0, 0.3, 1.0)]).is_empty());
    }
}
