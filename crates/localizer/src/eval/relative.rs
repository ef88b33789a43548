//! Relative-motion (drift) errors over pose pairs a fixed arc length apart.
//!
//! For start points every `spacing_m` of ground-truth arc length s, the end point is at
//! s + `distance_m`; both times come from the arc-length index. With ground-truth poses
//! G₀, G₁ and estimated poses E₀, E₁ at those times, the relative motions are
//! ΔG = G₀⁻¹ G₁ and ΔE = E₀⁻¹ E₁ and the error is ΔG⁻¹ ΔE: its translation length and
//! rotation angle (full SE(2) or SE(3), unlike the planar trajectory errors). This is the
//! relative pose error of Sturm et al. (IROS 2012) and, divided by the distance, the drift
//! measure of the KITTI odometry benchmark (Geiger et al., CVPR 2012). It is insensitive to
//! a constant offset between the two trajectories.

use serde::{Deserialize, Serialize};

use super::arc::{ArcLengthIndex, point_count};
use super::stats::ErrorStats;
use crate::error::{LocalizerError, require_positive};
use crate::state::FilterState;
use crate::track::PoseTrack;

/// The result of [`relative_motion_errors`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RelativeMotionErrors {
    /// Arc length between the two poses of a pair, metres.
    pub distance_m: f64,
    /// Pairs skipped because the estimate did not cover one of their times.
    pub skipped_pairs: usize,
    /// Translation error ‖t(ΔG⁻¹ ΔE)‖ per pair, metres.
    pub translation_m: ErrorStats,
    /// Rotation error ∠(ΔG⁻¹ ΔE) per pair, radians.
    pub rotation_rad: ErrorStats,
    /// Translation error divided by `distance_m` (dimensionless drift).
    pub translation_per_m: ErrorStats,
    /// Rotation error divided by `distance_m`, radians per metre.
    pub rotation_per_m: ErrorStats,
}

/// The relative-motion errors of `estimate` over pairs `distance_m` apart, starting every
/// `spacing_m` of ground-truth arc length (module docs).
pub fn relative_motion_errors<S: FilterState>(
    ground_truth: &PoseTrack<S>,
    estimate: &PoseTrack<S>,
    distance_m: f64,
    spacing_m: f64,
) -> Result<RelativeMotionErrors, LocalizerError> {
    require_positive("distance_m", distance_m)?;
    require_positive("spacing_m", spacing_m)?;
    let arc = ArcLengthIndex::new(ground_truth);
    let mut translation = Vec::new();
    let mut rotation = Vec::new();
    let mut skipped_pairs = 0;
    for k in 0..point_count(arc.total_m(), spacing_m)? {
        let start_m = k as f64 * spacing_m;
        let (Some(t0), Some(t1)) = (arc.time_at(start_m), arc.time_at(start_m + distance_m)) else {
            break;
        };
        if !(estimate.covers(t0) && estimate.covers(t1)) {
            skipped_pairs += 1;
            continue;
        }
        let delta_gt = ground_truth
            .pose_at(t0)?
            .inverse()
            .compose(&ground_truth.pose_at(t1)?);
        let delta_est = estimate
            .pose_at(t0)?
            .inverse()
            .compose(&estimate.pose_at(t1)?);
        let error = delta_gt.inverse().compose(&delta_est);
        translation.push(error.translation_norm());
        rotation.push(error.rotation_angle());
    }
    Ok(RelativeMotionErrors {
        distance_m,
        skipped_pairs,
        translation_m: ErrorStats::from_values(translation.iter().copied()),
        rotation_rad: ErrorStats::from_values(rotation.iter().copied()),
        translation_per_m: ErrorStats::from_values(translation.iter().map(|e| e / distance_m)),
        rotation_per_m: ErrorStats::from_values(rotation.iter().map(|e| e / distance_m)),
    })
}
