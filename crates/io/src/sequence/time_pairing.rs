//! Ground-truth time pairing: the pose of a trajectory at the times of a sequence's frames,
//! taken as it is when a pose's time matches, else interpolated between the two poses around
//! the time when they are close enough (`raypath loop-closure --ground-truth`).

use raypath_geometry::Pose3;

/// Largest gap between two trajectory poses that a frame's pose is interpolated over,
/// seconds (ours).
pub const MAX_GAP_SECS: f64 = 1.0;

/// Largest distance between a frame time and a pose time outside the trajectory's span that
/// still pairs them (the corrected CARMEN logs print the stamps with fewer digits), seconds.
pub const MATCH_TOLERANCE_SECS: f64 = 2e-3;

/// The pose of the trajectory `poses` (at `times`, index-aligned, in any order) at each time
/// of `at`: a pose within [`MATCH_TOLERANCE_SECS`] of the time, else the interpolation between
/// the poses before and after it when they are at most [`MAX_GAP_SECS`] apart, else `None`.
pub fn poses_at_times(poses: &[Pose3], times: &[f64], at: &[f64]) -> Vec<Option<Pose3>> {
    let n = poses.len().min(times.len());
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| times[a].total_cmp(&times[b]));
    let sorted: Vec<f64> = order.iter().map(|&k| times[k]).collect();
    at.iter()
        .map(|&t| {
            let k = sorted.partition_point(|&s| s < t);
            let near = |j: usize| (sorted[j] - t).abs() <= MATCH_TOLERANCE_SECS;
            if k < sorted.len() && near(k) {
                return Some(poses[order[k]]);
            }
            if k > 0 && near(k - 1) {
                return Some(poses[order[k - 1]]);
            }
            if k == 0 || k == sorted.len() || sorted[k] - sorted[k - 1] > MAX_GAP_SECS {
                return None;
            }
            let f = (t - sorted[k - 1]) / (sorted[k] - sorted[k - 1]);
            Some(poses[order[k - 1]].interpolate(&poses[order[k]], f))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_interpolates_and_refuses_gaps() {
        let pose = |x: f64| Pose3::from_xyz_rpy(x, 0.0, 0.0, 0.0, 0.0, 0.0);
        let poses = [pose(2.0), pose(0.0), pose(10.0)];
        let times = [1.0, 0.0, 5.0];
        let got = poses_at_times(&poses, &times, &[0.0005, 0.5, 3.0, 6.0, -1.0]);
        let x = |p: &Option<Pose3>| p.map(|p| p.translation().x);
        assert_eq!(x(&got[0]), Some(0.0));
        assert!((x(&got[1]).unwrap() - 1.0).abs() < 1e-12);
        assert_eq!(got[2], None, "the poses around t = 3 s are 4 s apart");
        assert_eq!(got[3], None);
        assert_eq!(got[4], None);
    }
}
