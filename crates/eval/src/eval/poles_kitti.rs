//! `cargo xtask eval poles-kitti`: pole extraction on real KITTI scans against SemanticKITTI
//! poles beside the same local maps simulated ([`real`], in the quick run too), and pole
//! extraction, mapping and localization on semi-synthetic KITTI drives (Schaefer 2020, §12.5,
//! Table 12.2).
//!
//! * Real: the ten real HDL-64E frames of `RAYPATH_DATA/kitti/sequences/{00,01,04,07}` with
//!   their SemanticKITTI labels (see [`real`]).
//!
//! * Data: the **real** trajectories and **real** pole maps of KITTI odometry sequences
//!   00–07 (`RAYPATH_DATA/kitti-poles/NN`; missing ones are skipped with a note). Each drive
//!   is simulated in memory
//!   ([`SemiKittiDrive`](raypath_sim::semi_kitti::SemiKittiDrive): the street world built
//!   around the drive, HDL-64E scans produced on demand while the local maps are built) and
//!   streamed through
//!   [`SweepSequence::from_fn`](raypath_io::sequence::SweepSequence::from_fn); nothing is
//!   written to disk. `POLES_KITTI_SEQUENCES=00,07` restricts the run to the listed
//!   sequences (`none`: the real section alone).
//! * Same-drive protocol (as the thesis, `kittipoles.py`): local maps every 3 m over 5 m of
//!   trajectory with the ground-truth poses, merged into the reference map; localization on
//!   the same drive with 2000 particles, 3 m / ±5° initial spread, increments corrupted by
//!   `N(0, diag((0.02 χ)²))`, errors every 1 m of ground-truth arc length; 50 runs per
//!   sequence up to [`FULL_RUNS_MAX_SCANS`] scans, [`LONG_RUNS`] on the longer ones (00, 02,
//!   05) to fit the time budget.
//! * Later-pass protocol, where a trajectory revisits (found from the ground truth alone,
//!   [`revisits`]): a stretch whose positions come within 3 m of the path driven ≥ 100 m of
//!   arc length earlier, merged across gaps < 10 m, at least 50 m long. Its map is the
//!   reference map of the local maps made only of scans ≥ 30 m of arc before the stretch
//!   starts (the earlier pass(es); ground-truth local maps as above); the stretch is cut
//!   where it leaves the reach (3 m) of that earlier path. A run localizes the stretch alone
//!   with the same filter settings, starting from the same 3 m / ±5° spread around the
//!   ground truth at its first scan, evaluated every 1 m; for comparison the same stretch is
//!   also localized on the same-drive map.
//! * Online poles come from the same ground-truth local maps (registered with the
//!   ground-truth relative motion inside each 5 m segment, not with the noisy odometry of
//!   each run) through the 2-of-3 filter; they are transformed into the robot frame with the
//!   ground-truth motion since the segment's end. Never ground-truth poles.
//! * Detection quality of the map against the simulated poles within 12 m of the drive.
//! * `--quick` (CI): sequence 07, every 10th frame, the first [`QUICK_SCANS`] of those scans,
//!   3 runs; and the later-pass protocol on sequence 06 every 10th frame, cut to the first
//!
//! In stages (`--shard i/n`, `merge`): the units are the real section ([`REAL_UNIT`]) and one
//! unit per semi-synthetic sequence ([`drive`] measures, [`page`] reports).

mod drive;
mod page;
mod real;
mod revisits;

use std::path::Path;

use anyhow::{Context, Result, bail};
use nalgebra::Point2;
use raypath_geometry::Pose3;
use raypath_io::poles_csv::read_pole_csv;
use raypath_poles::{ExtractionTotals, Pole, Preset, RunResult};
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use super::stages::{self, Staged, UnitResults};
use super::{EvalContext, EvalReport};
use crate::table::fmt_num;

const NAME: &str = "poles-kitti";

/// The sequences of `RAYPATH_DATA/kitti-poles`.
const SEQUENCES: [&str; 8] = ["00", "01", "02", "03", "04", "05", "06", "07"];

/// Sequences up to this many scans get the thesis's 50 runs.
const FULL_RUNS_MAX_SCANS: usize = 1200;
/// Runs on the longer sequences (time budget).
const LONG_RUNS: usize = 20;
/// Quick: scans of sequence 07 (every 10th frame) for the same-drive protocol.
const QUICK_SCANS: usize = 30;
/// Quick: scans of the revisit of sequence 06 (every 10th frame) for the later-pass protocol.
const QUICK_WINDOW_SCANS: usize = 8;
/// Shortest revisiting stretch evaluated, metres of arc length.
const MIN_REVISIT_M: f64 = 50.0;

/// What to simulate of one sequence.
struct SequencePlan {
    sequence: &'static str,
    stride: usize,
    max_scans: Option<usize>,
    /// Run the same-drive protocol.
    same_drive: bool,
    /// Run the later-pass protocol.
    later_pass: bool,
    /// Quick: extract only this many scans of the first revisit and of the earlier pass
    /// around them (instead of the whole drive).
    window_scans: Option<usize>,
}

fn plans(quick: bool) -> Vec<SequencePlan> {
    if quick {
        return vec![
            SequencePlan {
                sequence: "07",
                stride: 10,
                max_scans: Some(QUICK_SCANS),
                same_drive: true,
                later_pass: false,
                window_scans: None,
            },
            SequencePlan {
                sequence: "06",
                stride: 10,
                max_scans: None,
                same_drive: false,
                later_pass: true,
                window_scans: Some(QUICK_WINDOW_SCANS),
            },
        ];
    }
    let only: Option<Vec<String>> = std::env::var("POLES_KITTI_SEQUENCES")
        .ok()
        .map(|v| v.split(',').map(|s| s.trim().to_owned()).collect());
    SEQUENCES
        .iter()
        .filter(|s| only.as_ref().is_none_or(|o| o.iter().any(|x| x == *s)))
        .map(|&sequence| SequencePlan {
            sequence,
            stride: 1,
            max_scans: None,
            same_drive: true,
            later_pass: true,
            window_scans: None,
        })
        .collect()
}

/// The unit of the real section (the real KITTI frames of four sequences).
const REAL_UNIT: &str = "real";

/// The stages of `eval poles-kitti`.
pub const STAGED: Staged = Staged {
    name: NAME,
    units,
    run_unit,
    report,
};

/// The real section, then the planned sequences (`POLES_KITTI_SEQUENCES` may select).
fn units(ctx: &EvalContext) -> Result<Vec<String>> {
    let mut units = vec![REAL_UNIT.to_owned()];
    let mut planned: Vec<String> = plans(ctx.quick)
        .iter()
        .map(|p| format!("semi-kitti-{}", p.sequence))
        .collect();
    planned.dedup();
    units.append(&mut planned);
    Ok(units)
}

/// Measures the real section or one sequence.
fn run_unit(ctx: &EvalContext, unit: &str) -> Result<Value> {
    let preset = Preset::kitti();
    if unit == REAL_UNIT {
        let section = real::section(ctx, &preset.extraction)?;
        return Ok(json!({
            "markdown": section.markdown,
            "json": section.json,
            "realism": section.realism,
            "headline": section.headline,
            "gap_note": super::sim::gap_note(ctx)?,
        }));
    }
    let Some(plan) = unit
        .strip_prefix("semi-kitti-")
        .and_then(|s| plans(ctx.quick).into_iter().find(|p| p.sequence == s))
    else {
        bail!("{unit:?} is not a unit of {NAME}");
    };
    drive::measure(ctx, &plan, &preset)
}

/// The report from the unit results.
fn report(ctx: &EvalContext, results: &UnitResults) -> Result<EvalReport> {
    page::report(ctx, results).context("drawing the poles-kitti page")
}

/// The items whose ground-plane position `xy` lies within `radius` of any of the poses.
fn within<T: Copy>(
    items: &[T],
    poses: &[Pose3],
    radius: f64,
    xy: impl Fn(&T) -> (f64, f64),
) -> Vec<T> {
    items
        .iter()
        .filter(|item| {
            let (x, y) = xy(item);
            poses.iter().any(|q| {
                let t = q.translation();
                (t.x - x).powi(2) + (t.y - y).powi(2) <= radius * radius
            })
        })
        .copied()
        .collect()
}

/// Ground-truth pole positions within `radius` of any of the poses.
pub(super) fn truth_near(path: &Path, poses: &[Pose3], radius: f64) -> Result<Vec<Point2<f64>>> {
    let poles: Vec<Point2<f64>> = read_pole_csv(path)?
        .iter()
        .map(|p| Point2::new(p.x, p.y))
        .collect();
    Ok(points_near(&poles, poses, radius))
}

/// The points within `radius` of any of the poses.
pub(super) fn points_near(
    points: &[Point2<f64>],
    poses: &[Pose3],
    radius: f64,
) -> Vec<Point2<f64>> {
    within(points, poses, radius, |p| (p.x, p.y))
}

/// The poles within `radius` of any of the poses.
pub(super) fn near(poles: &[Pole], poses: &[Pose3], radius: f64) -> Vec<Pole> {
    within(poles, poses, radius, |p| (p.x, p.y))
}

/// Means over runs of the Table 12.2 columns (JSON keys in the units' names).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct RunSummary {
    #[serde(rename = "mean_pos_m")]
    #[serde(with = "stages::float")]
    pub mean_pos: f64,
    #[serde(rename = "rmse_pos_m")]
    #[serde(with = "stages::float")]
    pub rmse_pos: f64,
    #[serde(rename = "mean_lat_m")]
    #[serde(with = "stages::float")]
    pub mean_lat: f64,
    #[serde(rename = "std_lat_m")]
    #[serde(with = "stages::float")]
    pub std_lat: f64,
    #[serde(rename = "mean_lon_m")]
    #[serde(with = "stages::float")]
    pub mean_lon: f64,
    #[serde(rename = "std_lon_m")]
    #[serde(with = "stages::float")]
    pub std_lon: f64,
    #[serde(with = "stages::float")]
    pub mean_ang_deg: f64,
    #[serde(with = "stages::float")]
    pub std_ang_deg: f64,
    #[serde(with = "stages::float")]
    pub rmse_ang_deg: f64,
    #[serde(rename = "diverged_runs")]
    pub diverged: usize,
    pub runs: usize,
}
impl RunSummary {
    pub fn of(runs: &[RunResult]) -> Self {
        let n = runs.len().max(1) as f64;
        let mean = |f: &dyn Fn(&RunResult) -> f64| runs.iter().map(f).sum::<f64>() / n;
        let deg = 180.0 / std::f64::consts::PI;
        Self {
            mean_pos: mean(&|r| r.evaluation.position_m.mean_abs),
            rmse_pos: mean(&|r| r.evaluation.position_m.rmse),
            mean_lat: mean(&|r| r.evaluation.lateral_m.mean_abs),
            std_lat: mean(&|r| r.evaluation.lateral_m.std),
            mean_lon: mean(&|r| r.evaluation.longitudinal_m.mean_abs),
            std_lon: mean(&|r| r.evaluation.longitudinal_m.std),
            mean_ang_deg: mean(&|r| r.evaluation.heading_rad.mean_abs * deg),
            std_ang_deg: mean(&|r| r.evaluation.heading_rad.std * deg),
            rmse_ang_deg: mean(&|r| r.evaluation.heading_rad.rmse * deg),
            diverged: runs
                .iter()
                .filter(|r| r.evaluation.divergence.diverged())
                .count(),
            runs: runs.len(),
        }
    }

    /// The mean of several summaries (diverged and runs: totals).
    pub fn mean(all: &[RunSummary]) -> Self {
        let n = all.len().max(1) as f64;
        let mean = |f: &dyn Fn(&RunSummary) -> f64| all.iter().map(f).sum::<f64>() / n;
        Self {
            mean_pos: mean(&|s| s.mean_pos),
            rmse_pos: mean(&|s| s.rmse_pos),
            mean_lat: mean(&|s| s.mean_lat),
            std_lat: mean(&|s| s.std_lat),
            mean_lon: mean(&|s| s.mean_lon),
            std_lon: mean(&|s| s.std_lon),
            mean_ang_deg: mean(&|s| s.mean_ang_deg),
            std_ang_deg: mean(&|s| s.std_ang_deg),
            rmse_ang_deg: mean(&|s| s.rmse_ang_deg),
            diverged: all.iter().map(|s| s.diverged).sum(),
            runs: all.iter().map(|s| s.runs).sum(),
        }
    }

    pub fn row(&self, label: &str) -> Vec<String> {
        vec![
            label.to_string(),
            fmt_num(self.mean_pos, 3),
            fmt_num(self.rmse_pos, 3),
            fmt_num(self.mean_lat, 3),
            fmt_num(self.std_lat, 3),
            fmt_num(self.mean_lon, 3),
            fmt_num(self.std_lon, 3),
            fmt_num(self.mean_ang_deg, 3),
            fmt_num(self.std_ang_deg, 3),
            fmt_num(self.rmse_ang_deg, 3),
            format!("{} / {}", self.diverged, self.runs),
        ]
    }

    pub fn json(&self) -> Value {
        json!(self)
    }
}

/// Measurement updates and their seconds summed over `runs`.
pub(super) fn update_totals(runs: &[RunResult]) -> (usize, f64) {
    (
        runs.iter().map(|r| r.updates).sum(),
        runs.iter().map(|r| r.update_secs).sum(),
    )
}

/// A speed row: extraction throughput and the rate of `updates` measurement updates taking
/// `update_secs` seconds.
pub(super) fn speed_cells(
    label: &str,
    totals: &ExtractionTotals,
    updates: usize,
    update_secs: f64,
    aim_hz: f64,
) -> Vec<String> {
    vec![
        label.to_string(),
        totals.rays.to_string(),
        fmt_num(totals.trace_secs, 1),
        fmt_num(totals.score_secs, 1),
        format!("{:.2} M", totals.points_per_sec() / 1e6),
        "0.5 M".into(),
        updates.to_string(),
        fmt_num(updates as f64 / update_secs.max(1e-12), 0),
        fmt_num(aim_hz, 0),
    ]
}
