//! Typed reports of pole extraction, pole maps and pole localization: the JSON documents of
//! `raypath poles extract|map|localize --json` (the keys are a contract).

use serde::Serialize;

use crate::{Pole, RunResult};

/// One pole.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PoleReport {
    /// Centre x, metres (world frame).
    pub x: f64,
    /// Centre y, metres.
    pub y: f64,
    /// Width, metres.
    pub width: f64,
    /// Height, metres ([`Pole::height`]).
    pub height: f64,
    /// Score.
    pub score: f64,
}

impl From<&Pole> for PoleReport {
    fn from(p: &Pole) -> Self {
        Self {
            x: p.x,
            y: p.y,
            width: p.width,
            height: p.height(),
            score: p.score,
        }
    }
}

/// The poles of a drive (`extract`: one local map; `map`: the merged reference map).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoleMapReport {
    /// The sequence's name.
    pub sequence: String,
    /// The preset's name (`kitti`, `nclt`).
    pub preset: &'static str,
    /// Where rays start (`kitti`, `origin`).
    pub sweep_timing: &'static str,
    /// Scans used.
    pub scans: usize,
    /// Local maps built.
    pub local_maps: usize,
    /// The poles.
    pub poles: Vec<PoleReport>,
    /// Points per second of extraction.
    pub points_per_sec: f64,
    /// The pole map written (`map`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub out: Option<String>,
}

/// Means over localization runs.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LocalizationSummary {
    /// Mean position error, metres.
    pub mean_pos_m: f64,
    /// RMS position error, metres.
    pub rmse_pos_m: f64,
    /// Mean lateral error, metres.
    pub mean_lat_m: f64,
    /// Mean longitudinal error, metres.
    pub mean_lon_m: f64,
    /// Mean heading error, degrees.
    pub mean_ang_deg: f64,
    /// RMS heading error, degrees.
    pub rmse_ang_deg: f64,
    /// Runs that diverged at least once.
    pub diverged_runs: usize,
}

impl LocalizationSummary {
    /// The means over `runs` (the errors of each run against the ground truth).
    pub fn of(runs: &[RunResult]) -> Self {
        let n = runs.len().max(1) as f64;
        let mean = |f: &dyn Fn(&RunResult) -> f64| runs.iter().map(f).sum::<f64>() / n;
        let deg = 180.0 / std::f64::consts::PI;
        Self {
            mean_pos_m: mean(&|r| r.evaluation.position_m.mean_abs),
            rmse_pos_m: mean(&|r| r.evaluation.position_m.rmse),
            mean_lat_m: mean(&|r| r.evaluation.lateral_m.mean_abs),
            mean_lon_m: mean(&|r| r.evaluation.longitudinal_m.mean_abs),
            mean_ang_deg: mean(&|r| r.evaluation.heading_rad.mean_abs * deg),
            rmse_ang_deg: mean(&|r| r.evaluation.heading_rad.rmse * deg),
            diverged_runs: runs
                .iter()
                .filter(|r| r.evaluation.divergence.diverged())
                .count(),
        }
    }
}

/// One localization run against the ground truth.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RunReport {
    /// Mean position error, metres.
    pub mean_pos_m: f64,
    /// RMS position error, metres.
    pub rmse_pos_m: f64,
    /// Measurement updates.
    pub updates: usize,
    /// Whether it diverged.
    pub diverged: bool,
}

impl From<&RunResult> for RunReport {
    fn from(r: &RunResult) -> Self {
        Self {
            mean_pos_m: r.evaluation.position_m.mean_abs,
            rmse_pos_m: r.evaluation.position_m.rmse,
            updates: r.updates,
            diverged: r.evaluation.divergence.diverged(),
        }
    }
}

/// The last estimate of a run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FinalPose {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Heading, radians.
    pub theta: f64,
}

/// Localization runs on a pole map.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoleLocalizeReport {
    /// The sequence's name.
    pub sequence: String,
    /// The pole map's name.
    pub map: String,
    /// The preset's name.
    pub preset: &'static str,
    /// Where rays start.
    pub sweep_timing: &'static str,
    /// Runs.
    pub runs: usize,
    /// Means over the runs (`None` without ground truth).
    pub summary: Option<LocalizationSummary>,
    /// Each run (with ground truth).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub per_run: Option<Vec<RunReport>>,
    /// The final estimates (without ground truth).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub final_poses: Option<Vec<FinalPose>>,
}
