//! Ground truth of revisits from reference poses (the crate's [`GroundTruth`]) and the
//! exclusion windows of this evaluation, plus the counts the report needs (revisit queries,
//! opposite-direction revisits, the start of the second pass).

use raypath_geometry::{Pose2, Pose3, wrap_angle};
use raypath_place_recognition::{Exclusion, GroundTruth};

/// 2-D exclusion: frames closer than this in the evaluated sequence are no revisit. Frames,
/// not seconds: several corrected CARMEN logs carry unusable time stamps (all zero in
/// freiburg-campus, 6 significant digits of an absolute time in belgioioso and csail).
pub const MIN_GAP_FRAMES: usize = 50;
/// 3-D exclusion: frames closer than this in the real KITTI time stamps are no revisit.
pub const MIN_GAP_S: f64 = 30.0;
/// 3-D revisit radius, metres (Khan 2017, §4.6.2: "less than 5 m").
pub const RADIUS_3D_M: f64 = 5.0;
/// 2-D revisit radius, metres.
pub const RADIUS_2D_M: f64 = 2.0;
/// 2-D field of view of the CARMEN lasers (180° fans): headings within ±90° overlap by at
/// least half.
pub const FOV_2D_RAD: f64 = std::f64::consts::PI;

/// The rule of the 2-D logs, in words.
pub fn rule_2d() -> String {
    format!(
        "positions less than {RADIUS_2D_M} m apart with overlapping fields of view (headings \
         within ±90°, i.e. the 180° fans share at least half their view) and at least \
         {MIN_GAP_FRAMES} frames apart in the evaluated (possibly subsampled) sequence"
    )
}

/// The rule of the 3-D drives, in words.
pub fn rule_3d() -> String {
    format!(
        "positions less than {RADIUS_3D_M} m apart (3-D, any heading: the lidar sees 360°) \
         and at least {MIN_GAP_S} s apart in the real KITTI time stamps"
    )
}

/// The ground truth of a planar log.
pub fn planar(poses: &[Pose2]) -> anyhow::Result<GroundTruth> {
    Ok(GroundTruth::from_planar_poses(
        poses,
        None,
        RADIUS_2D_M,
        FOV_2D_RAD,
        Exclusion {
            frames: MIN_GAP_FRAMES,
            seconds: 0.0,
        },
    )?)
}

/// The ground truth of a 3-D drive with time stamps.
pub fn spatial(poses: &[Pose3], times: &[f64]) -> anyhow::Result<GroundTruth> {
    let positions: Vec<[f64; 3]> = poses
        .iter()
        .map(|p| {
            let t = p.translation();
            [t.x, t.y, t.z]
        })
        .collect();
    Ok(GroundTruth::from_positions(
        &positions,
        Some(times),
        RADIUS_3D_M,
        Exclusion {
            frames: 1,
            seconds: MIN_GAP_S,
        },
    )?)
}

/// The database frames a query may search online: `0..before(t)`, the frames outside the
/// exclusion window (2-D: `t − 50`; 3-D: the frames ≥ 30 s older).
pub fn online_limits(n: usize, times: Option<&[f64]>) -> Vec<usize> {
    match times {
        None => (0..n).map(|t| t.saturating_sub(MIN_GAP_FRAMES)).collect(),
        Some(times) => (0..n)
            .map(|t| times.partition_point(|&s| s <= times[t] - MIN_GAP_S).min(t))
            .collect(),
    }
}

/// Number of query frames with a true revisit among the earlier frames.
pub fn revisit_queries(truth: &GroundTruth) -> usize {
    (0..truth.len())
        .filter(|&t| truth.has_earlier_revisit(t))
        .count()
}

/// The first query with an earlier revisit (the start of the second pass).
pub fn first_revisit(truth: &GroundTruth) -> Option<usize> {
    (0..truth.len()).find(|&t| truth.has_earlier_revisit(t))
}

/// Revisit queries whose earlier partners were all driven in the opposite direction (headings
/// more than 90° apart).
pub fn opposite_queries(truth: &GroundTruth, yaws: &[f64]) -> usize {
    (0..truth.len())
        .filter(|&t| {
            let earlier: Vec<usize> = truth
                .revisits(t)
                .iter()
                .copied()
                .filter(|&j| j < t)
                .collect();
            !earlier.is_empty()
                && earlier
                    .iter()
                    .all(|&j| wrap_angle(yaws[t] - yaws[j]).abs() > std::f64::consts::FRAC_PI_2)
        })
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn online_limits_follow_the_windows() {
        assert_eq!(online_limits(3, None), vec![0, 0, 0]);
        assert_eq!(online_limits(60, None)[55], 5);
        let times: Vec<f64> = (0..100).map(f64::from).collect();
        let limits = online_limits(100, Some(&times));
        // Frame 40 (t = 40 s) may search frames with t ≤ 10 s: 0..=10.
        assert_eq!(limits[40], 11);
        assert_eq!(limits[10], 0);
    }

    #[test]
    fn opposite_direction_revisits_are_counted() {
        // Out along x for 60 s at 1 m/s, then back on the same line.
        let mut poses: Vec<Pose3> = (0..60)
            .map(|i| Pose3::from_xyz_rpy(f64::from(i), 0.0, 0.0, 0.0, 0.0, 0.0))
            .collect();
        poses.extend(
            (0..60).rev().map(|i| {
                Pose3::from_xyz_rpy(f64::from(i), 0.0, 0.0, 0.0, 0.0, std::f64::consts::PI)
            }),
        );
        let times: Vec<f64> = (0..120).map(f64::from).collect();
        let yaws: Vec<f64> = poses.iter().map(|p| p.to_planar().theta()).collect();
        let truth = spatial(&poses, &times).expect("valid input");
        let queries = revisit_queries(&truth);
        assert!(queries > 0);
        assert_eq!(opposite_queries(&truth, &yaws), queries);
        // Frame 60 + k is at x = 59 − k: the first with a partner ≥ 30 s back within 5 m.
        let first = first_revisit(&truth).expect("a revisit");
        assert!(first > 60);
    }
}
