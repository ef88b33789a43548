//! `cargo xtask eval sensor-models`: sensor models scored at the true pose and by inverse KL
//! (Schaefer 2020, Tables 7.3, 8.2, 8.3) on real and simulated data.
//!
//! Each data set is split into disjoint mapping and test scans (alternate scans: even scans
//! build the map with their reference poses, odd scans are scored), and
//! [`raypath_sensor_models::scoring`] scores every model variant: `D'` (Eq. 7.28), the
//! inverse KL over 50 positions in a 2.5 m disc (Eq. 7.29) and the ground-truth KL
//! (Eq. 8.24). Data sets:
//!
//! * **real 2-D**: every corrected Radish log in `$RAYPATH_DATA/carmen/corrected/`
//!   (0.1 m cells, `r_max` = the no-return threshold inferred by `raypath-io`);
//! * **simulated 2-D**: the corrected logs of the generated indoor worlds;
//! * **simulated 3-D**: a section of the generated urban drive (HDL-64E, KITTI layout) at
//!   0.5 m voxels, as the thesis.

mod data;
mod report;

use std::time::Instant;

use anyhow::{Context, Result};
use raypath_geometry::{Pose3, Ray3};
use raypath_sensor_models::scoring::{ScoreReport, ScoringConfig, score_log, score_spatial};
use serde_json::json;

use super::{EvalContext, EvalReport};
use crate::generate;

/// How much work a run does.
#[derive(Clone, Copy, Debug)]
struct Plan {
    /// Real logs scored (`None`: all); quick mode takes these names.
    real_logs: Option<&'static [&'static str]>,
    /// Simulated indoor worlds scored (`None`: all).
    sim_logs: Option<&'static [&'static str]>,
    /// At most this many test scans per 2-D log (evenly spaced).
    max_test_scans_2d: Option<usize>,
    /// Every k-th beam of a 2-D test scan.
    beam_step_2d: usize,
    /// Frames of the urban drive used (the first ones).
    frames_3d: usize,
    /// Every k-th point of a 3-D mapping scan.
    map_ray_step_3d: usize,
    /// Every k-th point of a 3-D test scan.
    test_ray_step_3d: usize,
    /// At most this many 3-D test scans.
    max_test_scans_3d: usize,
}

const QUICK: Plan = Plan {
    real_logs: Some(&["intel", "aces", "freiburg-101"]),
    sim_logs: Some(&["office"]),
    max_test_scans_2d: Some(40),
    beam_step_2d: 2,
    frames_3d: 40,
    map_ray_step_3d: 4,
    test_ray_step_3d: 32,
    max_test_scans_3d: 4,
};

const FULL: Plan = Plan {
    real_logs: None,
    sim_logs: None,
    max_test_scans_2d: Some(300),
    beam_step_2d: 1,
    frames_3d: 200,
    map_ray_step_3d: 1,
    test_ray_step_3d: 8,
    max_test_scans_3d: 20,
};

/// 3-D cell edge (the thesis's voxels).
const VOXEL_M: f64 = 0.5;
/// The real 2-D logs are scored a second time at the thesis's voxel edge (section (e)).
const COARSE_CELL_M: f64 = 0.5;
/// 3-D range limit: returns beyond count as no-returns (keeps the map box of the drive
/// section small; the HDL-64E's nominal range is about 120 m).
const MAX_RANGE_3D_M: f64 = 50.0;
/// Seed of the pose samples.
const SEED: u64 = 2020;

/// What kind of data a row is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A real Radish log.
    Real,
    /// A simulated indoor world (2-D).
    Sim2,
    /// A simulated urban drive (3-D).
    Sim3,
}

impl Kind {
    fn label(self) -> &'static str {
        match self {
            Kind::Real => "real 2-D",
            Kind::Sim2 => "simulated 2-D",
            Kind::Sim3 => "simulated 3-D",
        }
    }
}

/// The scores of one data set.
pub struct DataSet {
    /// Short name.
    pub name: String,
    /// Real or simulated.
    pub kind: Kind,
    /// Scans in the data set (or the section used).
    pub scans: usize,
    /// The scores.
    pub report: ScoreReport,
}

/// Runs the evaluation.
pub fn run(ctx: &EvalContext) -> Result<EvalReport> {
    let plan = if ctx.quick { QUICK } else { FULL };
    let started = Instant::now();
    let mut sets = Vec::new();
    let mut notes = Vec::new();

    // Real and simulated 2-D logs.
    let real_dir = ctx.data("carmen/corrected");
    let mut logs: Vec<(Kind, std::path::PathBuf)> =
        data::files_ending(&real_dir, &["-corrected.log.gz"])
            .into_iter()
            .filter(|p| {
                plan.real_logs
                    .is_none_or(|names| names.contains(&data::log_name(p).as_str()))
            })
            .map(|p| (Kind::Real, p))
            .collect();
    if logs.is_empty() {
        notes.push(format!(
            "No corrected CARMEN logs in `{}` (set RAYPATH_DATA): the real rows are missing.",
            real_dir.display()
        ));
    }
    match generate::ensure("indoor", ctx.quick) {
        Ok(dir) => logs.extend(
            data::files_ending(
                &dir,
                &["-corrected.log", "-corrected.log.gz", "-corrected.log.bz2"],
            )
            .into_iter()
            .filter(|p| {
                plan.sim_logs
                    .is_none_or(|names| names.contains(&data::log_name(p).as_str()))
            })
            .map(|p| (Kind::Sim2, p)),
        ),
        Err(e) => notes.push(format!("Simulated indoor worlds unavailable: {e:#}.")),
    }
    let config_2d = ScoringConfig {
        seed: SEED,
        beam_step: plan.beam_step_2d,
        max_test_scans: plan.max_test_scans_2d,
        ..ScoringConfig::default()
    };
    // The real logs once more at the thesis's cell size (section (e)).
    let config_coarse = ScoringConfig {
        resolution_m: COARSE_CELL_M,
        ..config_2d
    };
    let mut coarse = Vec::new();
    let bar = ctx.progress(logs.len() as u64 + 1, "2-D logs");
    for (kind, path) in &logs {
        let name = data::log_name(path);
        bar.set_message(name.clone());
        let scans =
            data::carmen_scans(path).with_context(|| format!("reading {}", path.display()))?;
        let report =
            score_log(&scans, &config_2d).with_context(|| format!("scoring {}", path.display()))?;
        if *kind == Kind::Real {
            let report = score_log(&scans, &config_coarse)
                .with_context(|| format!("scoring {} at {COARSE_CELL_M} m", path.display()))?;
            coarse.push(DataSet {
                name: name.clone(),
                kind: *kind,
                scans: scans.len(),
                report,
            });
        }
        sets.push(DataSet {
            name,
            kind: *kind,
            scans: scans.len(),
            report,
        });
        bar.inc(1);
    }
    bar.finish_and_clear();

    // Simulated 3-D urban drive.
    match generate::ensure("urban-kitti", ctx.quick) {
        Ok(dir) => {
            let sequence = dir.join("sequences/00");
            let bar = ctx.progress(plan.frames_3d as u64, "urban scans");
            let scans = data::kitti_scans(
                &sequence,
                plan.frames_3d,
                |frame| {
                    if frame % 2 == 0 {
                        plan.map_ray_step_3d
                    } else {
                        plan.test_ray_step_3d
                    }
                },
                || bar.inc(1),
            )
            .with_context(|| format!("reading {}", sequence.display()))?;
            bar.finish_and_clear();
            let map: Vec<(Pose3, &[Ray3])> = scans
                .iter()
                .step_by(2)
                .map(|s| (s.pose, s.rays.as_slice()))
                .collect();
            let test: Vec<(Pose3, &[Ray3])> = scans
                .iter()
                .skip(1)
                .step_by(2)
                .map(|s| (s.pose, s.rays.as_slice()))
                .collect();
            let config_3d = ScoringConfig {
                resolution_m: VOXEL_M,
                max_range_m: Some(MAX_RANGE_3D_M),
                seed: SEED,
                beam_step: 1,
                max_test_scans: Some(plan.max_test_scans_3d),
                ..ScoringConfig::default()
            };
            let spinner = ctx.progress(1, "urban scoring");
            let report = score_spatial(&map, &test, &config_3d).context("scoring urban-kitti")?;
            spinner.finish_and_clear();
            sets.push(DataSet {
                name: "urban-kitti".into(),
                kind: Kind::Sim3,
                scans: scans.len(),
                report,
            });
        }
        Err(e) => notes.push(format!("Simulated urban drive unavailable: {e:#}.")),
    }

    let seconds = started.elapsed().as_secs_f64();
    let mut markdown = report::markdown(&sets, &plan_text(&plan, ctx.quick), &notes)?;
    markdown.push_str(&report::coarse_section(&coarse, COARSE_CELL_M)?);
    let json = json!({
        "quick": ctx.quick,
        "seed": SEED,
        "seconds": seconds,
        "plan": plan_text(&plan, ctx.quick),
        "notes": notes,
        "data_sets": sets.iter().map(|s| json!({
            "name": s.name,
            "kind": s.kind.label(),
            "scans": s.scans,
            "report": s.report,
        })).collect::<Vec<_>>(),
        "agreement": report::agreement_json(&sets),
        "real_2d_at_0_5_m": {
            "cell_m": COARSE_CELL_M,
            "data_sets": coarse.iter().map(|s| json!({
                "name": s.name,
                "scans": s.scans,
                "report": s.report,
            })).collect::<Vec<_>>(),
            "agreement": report::agreement_json(&coarse),
        },
    });
    Ok(EvalReport {
        name: "sensor-models",
        title: "Sensor models: likelihood at the true pose and inverse KL (Tables 7.3, 8.2, 8.3)"
            .to_owned(),
        markdown,
        json,
        headline: None,
    })
}

fn plan_text(plan: &Plan, quick: bool) -> String {
    let real = plan
        .real_logs
        .map_or("every corrected log".to_owned(), |n| n.join(", "));
    let sim = plan
        .sim_logs
        .map_or("every indoor world".to_owned(), |n| n.join(", "));
    format!(
        "{} run. 2-D ({real}; simulated: {sim}): 0.1 m cells, alternate split (even scans map, \
         odd scans are scored), at most {} evenly spaced test scans per log, {}. \
         3-D (urban-kitti, frames 0–{}): {VOXEL_M} m voxels, r_max {MAX_RANGE_3D_M} m, even \
         frames map ({}), at most {} odd frames scored ({}). 50 poses \
         in a 2.5 m disc per test scan, σ = 0.05 m, seed {SEED}.",
        if quick { "Quick" } else { "Full" },
        plan.max_test_scans_2d
            .map_or("all".to_owned(), |n| n.to_string()),
        every(plan.beam_step_2d, "beam"),
        plan.frames_3d.saturating_sub(1),
        every(plan.map_ray_step_3d, "point"),
        plan.max_test_scans_3d,
        every(plan.test_ray_step_3d, "point"),
    )
}

/// "every beam", "every 2nd beam", "every 8th point", …
fn every(k: usize, noun: &str) -> String {
    match k {
        0 | 1 => format!("every {noun}"),
        2 => format!("every 2nd {noun}"),
        3 => format!("every 3rd {noun}"),
        k => format!("every {k}th {noun}"),
    }
}
