//! What a planar localization run reports: [`LocalizeReport`], the JSON object of
//! `raypath localize --json` (the keys are a contract).

use serde::Serialize;

use super::PlanarTrack;
use crate::eval::TrajectoryEvaluation;

/// The errors of a run against the ground truth (a summary of [`TrajectoryEvaluation`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TrajectoryErrorReport {
    /// Evaluation points.
    pub evaluated_points: usize,
    /// Ground-truth arc length, metres.
    pub length_m: f64,
    /// Mean position error, metres.
    pub position_mean_m: f64,
    /// RMS position error, metres.
    pub position_rmse_m: f64,
    /// Mean heading error, radians.
    pub heading_mean_rad: f64,
    /// RMS heading error, radians.
    pub heading_rmse_rad: f64,
    /// RMS lateral error, metres.
    pub lateral_rmse_m: f64,
    /// RMS longitudinal error, metres.
    pub longitudinal_rmse_m: f64,
    /// Whether the run diverged at least once.
    pub diverged: bool,
    /// Divergence episodes.
    pub divergence_episodes: usize,
    /// Fraction of the time diverged.
    pub divergence_fraction: f64,
}

impl From<&TrajectoryEvaluation> for TrajectoryErrorReport {
    fn from(e: &TrajectoryEvaluation) -> Self {
        Self {
            evaluated_points: e.points.len(),
            length_m: e.length_m,
            position_mean_m: e.position_m.mean_abs,
            position_rmse_m: e.position_m.rmse,
            heading_mean_rad: e.heading_rad.mean_abs,
            heading_rmse_rad: e.heading_rad.rmse,
            lateral_rmse_m: e.lateral_m.rmse,
            longitudinal_rmse_m: e.longitudinal_m.rmse,
            diverged: e.divergence.diverged(),
            divergence_episodes: e.divergence.episodes,
            divergence_fraction: e.divergence.fraction_of_time,
        }
    }
}

/// A planar localization run ([`super::track_planar`]) with its inputs' names.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LocalizeReport {
    /// The map's name.
    pub map: String,
    /// The log's name.
    pub log: String,
    /// The measurement model ([`super::ModelSpec::label`]).
    pub model: String,
    /// Particles.
    pub particles: usize,
    /// Random seed.
    pub seed: u64,
    /// Scans in the log.
    pub scans: usize,
    /// [`PlanarTrack::updates`].
    pub updates: usize,
    /// [`PlanarTrack::failed_updates`].
    pub failed_updates: usize,
    /// [`PlanarTrack::resamplings`].
    pub resamplings: usize,
    /// The last estimate `[x, y, θ]`.
    pub final_pose: Option<[f64; 3]>,
    /// The errors against the ground truth, when there is one.
    pub error: Option<TrajectoryErrorReport>,
}

impl LocalizeReport {
    /// The report of `track` over `scans` scans; the names and settings are the caller's.
    pub fn new(
        names: (String, String, String),
        particles: usize,
        seed: u64,
        scans: usize,
        track: &PlanarTrack,
        evaluation: Option<&TrajectoryEvaluation>,
    ) -> Self {
        let (map, log, model) = names;
        Self {
            map,
            log,
            model,
            particles,
            seed,
            scans,
            updates: track.updates,
            failed_updates: track.failed_updates,
            resamplings: track.resamplings,
            final_pose: track
                .estimates
                .last()
                .map(|(_, s)| [s.pose.x(), s.pose.y(), s.pose.theta()]),
            error: evaluation.map(TrajectoryErrorReport::from),
        }
    }
}
