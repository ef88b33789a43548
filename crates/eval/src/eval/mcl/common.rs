//! Shared pieces of the MCL evaluation: per-run results and their summary over seeds.

use raypath_localizer::eval::TrajectoryEvaluation;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use crate::eval::stages::float;
use crate::table::fmt_num;

/// One filter run, summarized.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct RunResult {
    /// Mean position error over the evaluation points, metres.
    #[serde(with = "float")]
    pub position_m: f64,
    /// Mean absolute heading error, radians.
    #[serde(with = "float")]
    pub heading_rad: f64,
    /// Whether the run diverged (error above 5 m at some point after the first 10 %).
    pub diverged: bool,
    /// Filter updates per second of wall time.
    #[serde(with = "float")]
    pub updates_per_s: f64,
}

impl RunResult {
    /// From a trajectory evaluation and the run's update rate.
    pub fn from_evaluation(evaluation: &TrajectoryEvaluation, updates_per_s: f64) -> Self {
        // The first stretch is the convergence from the deliberately poor start; divergence
        // counts only after it.
        let skip = evaluation.points.len() / 10;
        let diverged = evaluation
            .points
            .iter()
            .skip(skip)
            .any(|p| p.position_error_m > evaluation.config.divergence_threshold_m);
        Self {
            position_m: evaluation.position_m.mean_abs,
            heading_rad: evaluation.heading_rad.mean_abs,
            diverged,
            updates_per_s,
        }
    }
}

/// Mean and sample standard deviation.
pub fn mean_std(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    if values.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mean = values.iter().sum::<f64>() / n;
    let var = if values.len() > 1 {
        values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)
    } else {
        0.0
    };
    (mean, var.sqrt())
}

/// The results of one model on one data set over all seeds.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Cell {
    /// Data set name.
    pub dataset: String,
    /// Model label.
    pub model: String,
    /// One result per seed.
    pub runs: Vec<RunResult>,
}

impl Cell {
    /// `mean ± std` of the mean position error.
    pub fn position_text(&self) -> String {
        let v: Vec<f64> = self.runs.iter().map(|r| r.position_m).collect();
        let (m, s) = mean_std(&v);
        format!("{} ± {}", fmt_num(m, 3), fmt_num(s, 3))
    }

    /// `mean ± std` of the mean heading error in degrees.
    pub fn heading_text(&self) -> String {
        let v: Vec<f64> = self
            .runs
            .iter()
            .map(|r| r.heading_rad.to_degrees())
            .collect();
        let (m, s) = mean_std(&v);
        format!("{} ± {}", fmt_num(m, 2), fmt_num(s, 2))
    }

    /// Diverged runs out of all.
    pub fn divergence_text(&self) -> String {
        let d = self.runs.iter().filter(|r| r.diverged).count();
        format!("{d}/{}", self.runs.len())
    }

    /// Mean position error over the runs that did not diverge (NaN when all diverged).
    pub fn converged_position(&self) -> f64 {
        let v: Vec<f64> = self
            .runs
            .iter()
            .filter(|r| !r.diverged)
            .map(|r| r.position_m)
            .collect();
        mean_std(&v).0
    }

    /// `mean ± std` of the mean position error over the runs that did not diverge.
    pub fn converged_text(&self) -> String {
        let v: Vec<f64> = self
            .runs
            .iter()
            .filter(|r| !r.diverged)
            .map(|r| r.position_m)
            .collect();
        if v.is_empty() {
            return "–".to_owned();
        }
        let (m, s) = mean_std(&v);
        format!("{} ± {}", fmt_num(m, 3), fmt_num(s, 3))
    }

    /// Mean update rate.
    pub fn updates_per_s(&self) -> f64 {
        let v: Vec<f64> = self.runs.iter().map(|r| r.updates_per_s).collect();
        mean_std(&v).0
    }

    /// JSON.
    pub fn json(&self) -> Value {
        let pos: Vec<f64> = self.runs.iter().map(|r| r.position_m).collect();
        let head: Vec<f64> = self.runs.iter().map(|r| r.heading_rad).collect();
        let (pm, ps) = mean_std(&pos);
        let (hm, hs) = mean_std(&head);
        json!({
            "dataset": self.dataset,
            "model": self.model,
            "runs": self.runs.len(),
            "position_error_m": {"mean": pm, "std": ps, "per_run": pos},
            "heading_error_rad": {"mean": hm, "std": hs, "per_run": head},
            "diverged_runs": self.runs.iter().filter(|r| r.diverged).count(),
            "converged_position_error_m": self.converged_position(),
            "updates_per_s": self.updates_per_s(),
        })
    }
}
