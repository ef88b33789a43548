//! Trajectory errors at every metre of ground-truth arc length (module docs of [`crate::eval`]).

use raypath_geometry::{Pose2, wrap_angle};
use serde::{Deserialize, Serialize};

use super::arc::{ArcLengthIndex, point_count};
use super::stats::ErrorStats;
use crate::error::{LocalizerError, require_positive};
use crate::state::FilterState;
use crate::track::PoseTrack;

/// Parameters of the trajectory evaluation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvaluationConfig {
    /// Spacing of the evaluation points along the ground-truth arc length, metres.
    /// Default 1 m (Schaefer 2020, ch. 12).
    pub spacing_m: f64,
    /// Position error above which a point counts as diverged, metres. Default 5 m (ours; the
    /// thesis gives none).
    pub divergence_threshold_m: f64,
}

impl Default for EvaluationConfig {
    fn default() -> Self {
        Self {
            spacing_m: 1.0,
            divergence_threshold_m: 5.0,
        }
    }
}

/// The errors at one evaluation point.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvaluationPoint {
    /// Ground-truth arc length at the point, metres.
    pub arc_length_m: f64,
    /// Time of the point, seconds.
    pub stamp_secs: f64,
    /// Ground-truth pose (planar projection).
    pub ground_truth: Pose2,
    /// Estimated pose (planar projection).
    pub estimate: Pose2,
    /// Euclidean position error in the plane, metres.
    pub position_error_m: f64,
    /// Heading error (estimate − ground truth, wrapped), radians.
    pub heading_error_rad: f64,
    /// Lateral error (y of T_gt⁻¹ T_est, positive to the left), metres.
    pub lateral_error_m: f64,
    /// Longitudinal error (x of T_gt⁻¹ T_est, positive ahead), metres.
    pub longitudinal_error_m: f64,
}

/// Divergence of a run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DivergenceSummary {
    /// The threshold used, metres.
    pub threshold_m: f64,
    /// Number of divergence episodes (maximal runs of points above the threshold).
    pub episodes: usize,
    /// Fraction of the evaluated time spent diverged, in [0, 1].
    pub fraction_of_time: f64,
    /// Time of the first diverged point, seconds.
    pub first_divergence_secs: Option<f64>,
}

impl DivergenceSummary {
    /// True when the run diverged at least once.
    pub fn diverged(&self) -> bool {
        self.episodes > 0
    }
}

/// The result of [`evaluate_trajectory`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrajectoryEvaluation {
    /// The configuration used.
    pub config: EvaluationConfig,
    /// Ground-truth arc length, metres.
    pub length_m: f64,
    /// Evaluation points outside the estimate's time span (not evaluated).
    pub skipped_points: usize,
    /// Position errors, metres.
    pub position_m: ErrorStats,
    /// Heading errors, radians.
    pub heading_rad: ErrorStats,
    /// Lateral errors, metres.
    pub lateral_m: ErrorStats,
    /// Longitudinal errors, metres.
    pub longitudinal_m: ErrorStats,
    /// Divergence of the run.
    pub divergence: DivergenceSummary,
    /// The evaluated points, in arc-length order.
    pub points: Vec<EvaluationPoint>,
}

/// Evaluates `estimate` against `ground_truth` (both [`PoseTrack`]s of the same time base)
/// at every `config.spacing_m` of ground-truth arc length (module docs of [`crate::eval`]).
pub fn evaluate_trajectory<S: FilterState>(
    ground_truth: &PoseTrack<S>,
    estimate: &PoseTrack<S>,
    config: &EvaluationConfig,
) -> Result<TrajectoryEvaluation, LocalizerError> {
    require_positive("spacing_m", config.spacing_m)?;
    require_positive("divergence_threshold_m", config.divergence_threshold_m)?;
    let arc = ArcLengthIndex::new(ground_truth);
    let mut points = Vec::new();
    let mut skipped_points = 0;
    for k in 0..point_count(arc.total_m(), config.spacing_m)? {
        let arc_length_m = k as f64 * config.spacing_m;
        let Some(stamp_secs) = arc.time_at(arc_length_m) else {
            break;
        };
        if !estimate.covers(stamp_secs) {
            skipped_points += 1;
            continue;
        }
        let gt = ground_truth.pose_at(stamp_secs)?.to_planar();
        let est = estimate.pose_at(stamp_secs)?.to_planar();
        let error = gt.inverse() * est;
        points.push(EvaluationPoint {
            arc_length_m,
            stamp_secs,
            ground_truth: gt,
            estimate: est,
            position_error_m: error.translation().norm(),
            heading_error_rad: wrap_angle(est.theta() - gt.theta()),
            lateral_error_m: error.y(),
            longitudinal_error_m: error.x(),
        });
    }
    Ok(TrajectoryEvaluation {
        config: *config,
        length_m: arc.total_m(),
        skipped_points,
        position_m: ErrorStats::from_values(points.iter().map(|p| p.position_error_m)),
        heading_rad: ErrorStats::from_values(points.iter().map(|p| p.heading_error_rad)),
        lateral_m: ErrorStats::from_values(points.iter().map(|p| p.lateral_error_m)),
        longitudinal_m: ErrorStats::from_values(points.iter().map(|p| p.longitudinal_error_m)),
        divergence: divergence(&points, config.divergence_threshold_m),
        points,
    })
}

fn divergence(points: &[EvaluationPoint], threshold_m: f64) -> DivergenceSummary {
    let mut episodes = 0;
    let mut was_diverged = false;
    let mut first_divergence_secs = None;
    let (mut diverged_time, mut total_time) = (0.0, 0.0);
    for (i, p) in points.iter().enumerate() {
        let diverged = p.position_error_m > threshold_m;
        if diverged && !was_diverged {
            episodes += 1;
            first_divergence_secs.get_or_insert(p.stamp_secs);
        }
        was_diverged = diverged;
        // Each point stands for half the time to either neighbour.
        let previous = i.checked_sub(1).and_then(|j| points.get(j));
        let weight = (points.get(i + 1).map_or(p.stamp_secs, |q| q.stamp_secs)
            - previous.map_or(p.stamp_secs, |q| q.stamp_secs))
            / 2.0;
        total_time += weight;
        if diverged {
            diverged_time += weight;
        }
    }
    let fraction_of_time = if total_time > 0.0 {
        diverged_time / total_time
    } else if points.is_empty() {
        0.0
    } else {
        // A single point (or all at one time): the fraction of diverged points.
        points
            .iter()
            .filter(|p| p.position_error_m > threshold_m)
            .count() as f64
            / points.len() as f64
    };
    DivergenceSummary {
        threshold_m,
        episodes,
        fraction_of_time,
        first_divergence_secs,
    }
}
