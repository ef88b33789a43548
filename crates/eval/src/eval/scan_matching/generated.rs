//! The generated indoor world `lab` (raypath-sim: 360° laser at 0.5° with remissions from the
//! same intensity model, noisy wheel odometry): all three residuals, with and without
//! odometry as the initial guess, against its ground truth. One unit; it fits the simulated
//! calibration's LUT itself ([`super::simulated_lut`]).

use std::fmt::Write;
use std::time::Instant;

use anyhow::Result;
use raypath_geometry::Pose2;
use raypath_reflectivity::benchmark::{
    aligned_errors, consecutive_relations, relative_errors, run_matcher,
};
use raypath_reflectivity::{MatcherConfig, PointFilter, ResidualMode};
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use super::real_logs::{front_laser, paired, real_config};
use super::{at, error_cells, reference_count, simulated_lut};
use crate::eval::EvalContext;
use crate::table::{Table, fmt_num};

/// Scans with `--quick`.
const QUICK_SCANS: usize = 300;

/// The unit's result when the generated logs are there.
#[derive(Debug, Serialize, Deserialize)]
pub(super) struct LabUnit {
    /// Raw scans matched.
    pub scans: usize,
    /// Of them, paired with the corrected log.
    pub pairs: usize,
    /// The page's JSON rows (`mode`, `odometry`, `relative`, `aligned`, `scans_per_s`): the
    /// odometry, then each residual without and with odometry as the initial guess.
    pub rows: Vec<Value>,
}

/// Matches the generated world (the unit `generated-lab`).
pub(super) fn measure(ctx: &EvalContext) -> Result<Option<LabUnit>> {
    let Some((raw_file, ref_file)) = crate::generate::indoor_logs("lab", ctx.quick)? else {
        return Ok(None);
    };
    let lut = simulated_lut(reference_count(ctx.quick))?;
    let mut raw = front_laser(&raw_file)?;
    if ctx.quick {
        raw.truncate(QUICK_SCANS);
    }
    let (pairs, truth) = paired(&mut raw, &ref_file)?;
    let relations = consecutive_relations(truth.len());
    let row = |mode: &str, odometry: &str, est: &[Pose2], sps: f64| {
        json!({
            "mode": mode, "odometry": odometry,
            "relative": relative_errors(&truth, est, &relations),
            "aligned": aligned_errors(&truth, est), "scans_per_s": sps,
        })
    };
    let odometry: Vec<Pose2> = pairs
        .iter()
        .filter_map(|&i| raw.get(i).map(|s| s.world_from_laser))
        .collect();
    let mut rows = vec![row("—", "odometry only", &odometry, f64::NAN)];
    for guess in [false, true] {
        for mode in [
            ResidualMode::Occupancy,
            ResidualMode::Reflectivity,
            ResidualMode::Combined,
        ] {
            let config = MatcherConfig {
                mode,
                ..real_config()
            };
            let t = Instant::now();
            let (_, results) =
                run_matcher(&raw, config, &PointFilter::default(), Some(&lut), guess)?;
            let sps = raw.len() as f64 / t.elapsed().as_secs_f64();
            let est: Vec<Pose2> = pairs
                .iter()
                .filter_map(|&i| results.get(i).map(|r| r.world_from_sensor))
                .collect();
            let odometry = if guess { "initial guess" } else { "none" };
            rows.push(row(mode.name(), odometry, &est, sps));
        }
    }
    Ok(Some(LabUnit {
        scans: raw.len(),
        pairs: pairs.len(),
        rows,
    }))
}

/// The section's text and table (or why there is none).
pub(super) fn markdown(unit: Option<&LabUnit>) -> Result<String> {
    let mut md = String::new();
    let Some(unit) = unit else {
        let _ = writeln!(
            md,
            "* the generated `indoor/lab` logs are missing: skipped.\n"
        );
        return Ok(md);
    };
    let mut table = Table::new([
        "residual",
        "odometry",
        "rel. transl. mm (mean ± std)",
        "rel. rot. ° (mean ± std)",
        "ATE RMSE m",
        "ATE max m",
        "scans/s",
    ]);
    for row in &unit.rows {
        let [transl, rot, rmse, max] = error_cells(row, 1000.0, 1, 3);
        let text = |key: &str| row[key].as_str().unwrap_or_default().to_owned();
        table.row([
            text("mode"),
            text("odometry"),
            transl,
            rot,
            rmse,
            max,
            fmt_num(at(row, "/scans_per_s"), 0),
        ]);
    }
    let _ = writeln!(
        md,
        "`datasets/generated/indoor/lab` (raypath-sim: offices and crossing corridors with glass, \
         furniture and posters; {} ROBOTLASER1 scans of 720 beams over 360° with remissions from \
         the same intensity model as above; noisy wheel odometry), scored against its corrected \
         log ({} pairs, relations between consecutive scans). ϱ̄ from the LUT above.\n",
        unit.scans, unit.pairs
    );
    let _ = writeln!(md, "{}", table.to_markdown()?);
    Ok(md)
}

/// The section's JSON as the page writes it (`null` when the logs are missing).
pub(super) fn json(unit: Option<&LabUnit>) -> Value {
    unit.map_or(Value::Null, |u| Value::Array(u.rows.clone()))
}
