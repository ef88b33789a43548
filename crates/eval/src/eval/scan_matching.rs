//! `cargo xtask eval scan-matching`: intensity calibration and Hector-style scan matching
//! (Khan 2017, ch. 3; spec `khan-2017.md` §3).
//!
//! * **Real logs** (occupancy residual; the raw SLAM-benchmark logs have no remissions):
//!   `carmen/raw/{intel, fr079, mit-csail}` matched scan by scan, scored against the poses
//!   of the corrected logs (scans paired by identical readings): relative-motion error of
//!   Kümmerle et al. (2009) over consecutive reference scans and the absolute error after
//!   rigid alignment. Variants: plain Hector (no odometry), odometry as the initial guess,
//!   odometry as a prior, and the odometry itself ([`real_logs`]).
//! * **Calibration** (simulated, `raypath-sim`'s intensity model): LUT and range-only
//!   polynomial fitted to reference-surface samples; three test surfaces (Khan Fig. 3.4)
//!   corrected by the raw, range-only and LUT models; histogram overlap between surfaces
//!   and per-surface coefficient of variation ([`calibration`]).
//! * **Calibration on real scans**: the same LUT fitted on the road class of the real,
//!   SemanticKITTI-labelled KITTI frames and scored by the coefficient of variation per class
//!   on held-back frames ([`real_calib`]).
//! * **Calibration on real Ouster frames**: the LUT fitted on the ground of the real Ouster
//!   captures, on the raw signal and on the sensor's reflectivity, scored on held-back
//!   columns ([`real_ouster`]).
//! * **Failure case** (simulated, Khan Fig. 3.6): 8.5 m × 5.5 m room with reflectivity
//!   panels, ±60° field of view, stops facing single walls; occupancy, reflectivity and
//!   combined residuals scored against ground truth (and a 180° control) ([`failure`]).
//! * **Generated indoor world** `indoor/lab` with remissions: all three residuals against its
//!   ground truth ([`generated`]).
//! * **Speed**: scans per second of each run (release build, one thread, machine shared).
//!
//! In stages (`--shard i/n`, `merge`), units in report order: one per real log
//! (`real/<log>`; `--quick`: Intel only), the simulated calibration (`calibration`, which also
//! measures the note on how far simulated scans are from real ones), the KITTI calibration
//! (`kitti-calibration`: one unit, as its LUT is fitted on the road samples of every sequence
//! pooled), one per Ouster capture (`ouster/<capture>`: each capture fits its own LUT), the
//! failure case (`failure-case`) and the generated world (`generated-lab`); [`page`] draws
//! the report from their results.
//!
//! Shared state: the failure case and the generated world use the LUT of the simulated
//! calibration. It is seeded and cheap to fit (well under a second), so each of the three
//! units fits it itself from the same reference samples ([`simulated_lut`]) — the same table
//! bit for bit — rather than one unit holding three sections.

mod calibration;
mod failure;
mod generated;
mod page;
mod real_calib;
mod real_logs;
mod real_ouster;
mod sim;
mod stats;

use anyhow::{Result, bail};
use raypath_reflectivity::{IntensityCorrection, IntensityLut, LutConfig};
use raypath_sim::indoor::IntensityModel;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::EvalContext;
use super::stages::{Staged, float};
use crate::table::fmt_num;

const NAME: &str = "scan-matching";
const SEED: u64 = 2017;

/// The evaluation in stages (`--shard i/n` and `eval merge`).
pub const STAGED: Staged = Staged {
    name: NAME,
    units,
    run_unit,
    report: page::report,
};

/// Unit names of the single-unit sections.
const CALIBRATION: &str = "calibration";
const KITTI: &str = "kitti-calibration";
const FAILURE: &str = "failure-case";
const GENERATED: &str = "generated-lab";
/// Prefixes of the units per real log and per Ouster capture.
const REAL: &str = "real/";
const OUSTER: &str = "ouster/";

/// The units in report order.
fn units(ctx: &EvalContext) -> Result<Vec<String>> {
    let mut units: Vec<String> = real_logs::logs(ctx.quick)
        .map(|name| format!("{REAL}{name}"))
        .collect();
    units.extend([CALIBRATION, KITTI].map(String::from));
    units.extend(real_ouster::captures().map(|c| format!("{OUSTER}{c}")));
    units.extend([FAILURE, GENERATED].map(String::from));
    Ok(units)
}

/// Measures one unit.
fn run_unit(ctx: &EvalContext, unit: &str) -> Result<Value> {
    if let Some(log) = unit.strip_prefix(REAL) {
        return Ok(serde_json::to_value(real_logs::measure(ctx, log)?)?);
    }
    if let Some(capture) = unit.strip_prefix(OUSTER) {
        return Ok(serde_json::to_value(real_ouster::measure(ctx, capture)?)?);
    }
    Ok(match unit {
        CALIBRATION => serde_json::to_value(calibration::measure(ctx)?)?,
        KITTI => serde_json::to_value(real_calib::measure(ctx)?)?,
        FAILURE => serde_json::to_value(failure::measure(ctx)?)?,
        GENERATED => serde_json::to_value(generated::measure(ctx)?)?,
        _ => bail!("{NAME} has no unit {unit:?}"),
    })
}

/// The number of reference-surface samples of the simulated calibration.
fn reference_count(quick: bool) -> usize {
    if quick { 4000 } else { 20000 }
}

/// The intensity LUT fitted to `n` reference-surface samples of the simulator's intensity
/// model (the calibration of this evaluation), for other evaluations on the generated worlds
/// and for the units of this one that need it.
pub(super) fn simulated_lut(n: usize) -> Result<IntensityCorrection> {
    let reference = sim::reference_samples(&IntensityModel::default(), n, SEED);
    Ok(IntensityCorrection::Lut(IntensityLut::fit(
        &reference,
        &LutConfig::default(),
    )?))
}

/// An `f64` that survives the unit results when NaN or infinite ([`float`]).
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
struct Num(#[serde(with = "float")] f64);

/// The values of `nums`.
fn values(nums: &[Num]) -> Vec<f64> {
    nums.iter().map(|n| n.0).collect()
}

/// `nums` as [`Num`]s.
fn nums(values: &[f64]) -> Vec<Num> {
    values.iter().map(|&v| Num(v)).collect()
}

/// The number at the JSON pointer `path` of `value`; NaN where JSON holds none (a non-finite
/// figure of the page's JSON is `null`).
fn at(value: &Value, path: &str) -> f64 {
    value
        .pointer(path)
        .and_then(Value::as_f64)
        .unwrap_or(f64::NAN)
}

/// `mean ± std` with `decimals` decimals.
fn pm(mean: f64, std: f64, decimals: usize) -> String {
    format!("{} ± {}", fmt_num(mean, decimals), fmt_num(std, decimals))
}

/// The error cells of a matcher run from its JSON (`relative` and `aligned` under `errors`):
/// relative translation (× `scale`, `t_decimals`), relative rotation in degrees
/// (`r_decimals`), ATE RMSE and ATE max (m).
fn error_cells(errors: &Value, scale: f64, t_decimals: usize, r_decimals: usize) -> [String; 4] {
    let t = |key: &str| scale * at(errors, &format!("/relative/translation_m/{key}"));
    let r = |key: &str| at(errors, &format!("/relative/rotation_rad/{key}")).to_degrees();
    [
        pm(t("mean"), t("std"), t_decimals),
        pm(r("mean"), r("std"), r_decimals),
        fmt_num(at(errors, "/aligned/position_m/rms"), 3),
        fmt_num(at(errors, "/aligned/position_m/max"), 3),
    ]
}
