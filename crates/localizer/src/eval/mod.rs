//! Trajectory evaluation as in Schaefer (2020), ch. 12 (§12.5.1, §12.5.2: the NCLT and KITTI
//! protocols, as the polex implementation runs them).
//!
//! 1. The ground-truth track is projected onto the ground plane and its **arc length** is
//!    accumulated. Evaluation points lie every [`EvaluationConfig::spacing_m`] (1 m) of arc
//!    length, starting at 0; each point's time is interpolated linearly in arc length between
//!    the neighbouring ground-truth samples.
//! 2. At each point's time both tracks are interpolated by time ([`crate::PoseTrack`]: linear
//!    position, shorter-arc rotation). Points outside the estimate's time span are skipped
//!    and counted.
//! 3. The planar error pose is `E = T_gt⁻¹ · T_est`: **longitudinal** error = x of E (along the
//!    ground-truth heading), **lateral** error = y of E (to its left), **position** error =
//!    ‖(x, y)‖ (Euclidean in the plane), **heading** error = θ of E wrapped to (−π, π].
//! 4. For each error: mean of absolute values (the thesis's Δ), RMSE, signed mean, standard
//!    deviation of the signed values (the thesis's σ in Table 12.2) and maximum
//!    ([`ErrorStats`]).
//! 5. **Divergence**: a point is diverged when its position error exceeds
//!    [`EvaluationConfig::divergence_threshold_m`]. The thesis gives no threshold ("never even
//!    partially diverges"), so the default is 5 m — far above the 0.1 – 0.4 m errors of a
//!    tracking filter and below the "few metres" of the one diverging NCLT session. Reported:
//!    the number of divergence episodes (maximal runs of diverged points) and the fraction of
//!    time diverged (each point weighted by half the time to its neighbours).
//!
//! [`relative_motion_errors`] adds the relative-motion (drift) error over pairs of poses a
//! fixed arc length apart, for odometry and SLAM evaluations.

mod arc;
mod relative;
mod stats;
mod trajectory;

pub use arc::ArcLengthIndex;
pub use relative::{RelativeMotionErrors, relative_motion_errors};
pub use stats::ErrorStats;
pub use trajectory::{
    DivergenceSummary, EvaluationConfig, EvaluationPoint, TrajectoryEvaluation, evaluate_trajectory,
};
