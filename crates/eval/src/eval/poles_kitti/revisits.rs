//! Revisits of a trajectory, found from the ground truth alone: a later stretch whose
//! positions come within [`REVISIT_RADIUS_M`] of the path driven at least
//! [`MIN_SEPARATION_M`] of arc length earlier (the later-pass protocol of `poles-kitti`).
//!
//! Positions are planar `(x, y)` in metres; the earlier path is the polyline through the
//! earlier positions (point-to-segment distances), so sparse (strided) scans still match.

use nalgebra::Point2;

/// How close a later position must come to the earlier path, metres.
pub(super) const REVISIT_RADIUS_M: f64 = 3.0;
/// The earlier path must lie at least this much arc length back, metres.
pub(super) const MIN_SEPARATION_M: f64 = 100.0;
/// Revisiting runs separated by less than this arc length are one stretch, metres.
pub(super) const MERGE_GAP_M: f64 = 10.0;
/// The map of a stretch is built from the scans up to this arc length before the stretch
/// starts (more than a local map's reach of 15 m + a 5 m segment), metres.
pub(super) const MAP_GAP_M: f64 = 30.0;

/// A revisiting stretch of scans.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Revisit {
    /// First scan of the stretch.
    pub start: usize,
    /// One past the last scan of the stretch.
    pub end: usize,
    /// Scans `0..map_end` form the earlier pass(es) the map is built from.
    pub map_end: usize,
    /// Arc length of the stretch, metres.
    pub length_m: f64,
    /// Arc length driven from the earlier pass to the stretch start, metres.
    pub separation_m: f64,
}

/// Cumulative arc length at every position, metres.
pub(super) fn arc_lengths(positions: &[Point2<f64>]) -> Vec<f64> {
    let mut s = 0.0;
    let mut prev: Option<&Point2<f64>> = None;
    positions
        .iter()
        .map(|p| {
            if let Some(q) = prev {
                s += (p - q).norm();
            }
            prev = Some(p);
            s
        })
        .collect()
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: &Point2<f64>, a: &Point2<f64>, b: &Point2<f64>) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm()
}

/// The nearest point (arc length) of the polyline `positions[..=last]` within `radius` of
/// `p`, if any.
fn near_path(
    p: &Point2<f64>,
    positions: &[Point2<f64>],
    arc: &[f64],
    last: usize,
    radius: f64,
) -> Option<f64> {
    let mut best: Option<(f64, f64)> = None;
    for i in 0..last.min(positions.len().saturating_sub(1)) {
        let d = segment_distance(p, &positions[i], &positions[i + 1]);
        if d <= radius && best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, arc[i]));
        }
    }
    if best.is_none() && last == 0 && !positions.is_empty() {
        let d = (p - positions[0]).norm();
        if d <= radius {
            best = Some((d, 0.0));
        }
    }
    best.map(|(_, s)| s)
}

/// The revisiting stretches of at least `min_length_m`, each cut where its positions leave
/// the reach of its map's scans (`0..map_end`).
pub(super) fn find_revisits(positions: &[Point2<f64>], min_length_m: f64) -> Vec<Revisit> {
    let arc = arc_lengths(positions);
    // The last index whose arc length is at most `s`.
    let last_before = |s: f64| arc.partition_point(|&a| a <= s).saturating_sub(1);
    let revisiting: Vec<bool> = positions
        .iter()
        .zip(&arc)
        .map(|(p, &s)| {
            s >= MIN_SEPARATION_M
                && near_path(
                    p,
                    positions,
                    &arc,
                    last_before(s - MIN_SEPARATION_M),
                    REVISIT_RADIUS_M,
                )
                .is_some()
        })
        .collect();
    // Maximal runs, merged across short gaps.
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut open: Option<usize> = None;
    for (j, &r) in revisiting.iter().chain([&false]).enumerate() {
        match (r, open) {
            (true, None) => open = Some(j),
            (false, Some(a)) => {
                match runs.last_mut() {
                    Some(last) if arc[a] - arc[last.1 - 1] < MERGE_GAP_M => last.1 = j,
                    _ => runs.push((a, j)),
                }
                open = None;
            }
            _ => {}
        }
    }
    let mut out = Vec::new();
    for (start, end) in runs {
        let map_end = arc.partition_point(|&a| a < arc[start] - MAP_GAP_M);
        if map_end < 2 {
            continue;
        }
        // Cut at the first position out of reach of the mapped path.
        let mapped_last = map_end - 1;
        let reach = |j: usize| {
            near_path(
                &positions[j],
                positions,
                &arc,
                mapped_last,
                REVISIT_RADIUS_M,
            )
        };
        let end = (start..end).find(|&j| reach(j).is_none()).unwrap_or(end);
        if end <= start + 1 {
            continue;
        }
        let length_m = arc[end - 1] - arc[start];
        if length_m < min_length_m {
            continue;
        }
        let separation_m = reach(start).map_or(f64::NAN, |s| arc[start] - s);
        out.push(Revisit {
            start,
            end,
            map_end,
            length_m,
            separation_m,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 50 m × 50 m square driven 1.5 times at 1 m spacing, then 40 m east away from it.
    fn square_and_a_half() -> Vec<Point2<f64>> {
        let corners = [(0.0, 0.0), (50.0, 0.0), (50.0, 50.0), (0.0, 50.0)];
        let mut out = Vec::new();
        for k in 0..6 {
            let (ax, ay) = corners[k % 4];
            let (bx, by) = corners[(k + 1) % 4];
            for t in 0..50 {
                let f = f64::from(t) / 50.0;
                out.push(Point2::new(ax + (bx - ax) * f, ay + (by - ay) * f));
            }
        }
        for t in 0..40 {
            out.push(Point2::new(50.0 + f64::from(t), 50.0));
        }
        out
    }

    #[test]
    fn the_second_lap_of_a_square_is_a_revisit_mapped_from_the_first() {
        let path = square_and_a_half();
        let revisits = find_revisits(&path, 50.0);
        assert_eq!(revisits.len(), 1, "{revisits:?}");
        let r = &revisits[0];
        // Scan i is at arc length i m. The second lap comes within 3 m of the start at scan
        // 197, (0, 3); it leaves the square eastwards at scan 300, (50, 50), and is out of
        // reach of the first lap 4 m later.
        assert_eq!((r.start, r.end), (197, 304), "{r:?}");
        assert!((r.length_m - 106.0).abs() < 1e-9, "{r:?}");
        // The map comes from scans more than 30 m of arc before the stretch.
        assert_eq!(r.map_end, 167);
        // The nearest earlier point, (0, 0), was passed 197 m earlier.
        assert!((r.separation_m - 197.0).abs() < 1e-9, "{r:?}");
    }

    #[test]
    fn a_straight_drive_and_short_revisits_have_none() {
        let line: Vec<Point2<f64>> = (0..500).map(|i| Point2::new(f64::from(i), 0.0)).collect();
        assert!(find_revisits(&line, 50.0).is_empty());
        // Driving back along the same road after a U-turn is a revisit (≥ 100 m back).
        let mut back = line.clone();
        back.extend((0..500).rev().map(|i| Point2::new(f64::from(i), 2.0)));
        let revisits = find_revisits(&back, 50.0);
        assert_eq!(revisits.len(), 1, "{revisits:?}");
        // Scan 500 + m is at (499 − m, 2), arc 501 + m; the path 100 m back ends at
        // (401 + m, 0): within 3 m from m = 48 on.
        assert_eq!((revisits[0].start, revisits[0].end), (548, 1000));
        assert_eq!(revisits[0].map_end, 518);
        // Too short to count.
        assert!(find_revisits(&back[..560], 50.0).is_empty());
        assert!(arc_lengths(&[]).is_empty());
        assert!(find_revisits(&[], 50.0).is_empty());
    }
}
