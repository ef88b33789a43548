//! The units: one data set each, listed cheaply and scored.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use raypath_geometry::{Pose3, Ray3};
use raypath_sensor_models::scoring::{ScoringConfig, score_log, score_spatial};
use raypath_sim::indoor::IndoorConfig;

use super::{
    COARSE_CELL_M, DataSet, Kind, MAX_RANGE_3D_M, Plan, SEED, Scored, UnitResult, VOXEL_M, data,
};
use crate::eval::EvalContext;
use crate::generate;

/// The file names of the real corrected logs end so.
const REAL_SUFFIX: &str = "-corrected.log.gz";
/// The file names of the simulated corrected logs end so.
const SIM_SUFFIXES: [&str; 3] = ["-corrected.log", "-corrected.log.gz", "-corrected.log.bz2"];

/// The directory of the real corrected logs.
pub fn real_dir(ctx: &EvalContext) -> PathBuf {
    ctx.data("carmen/corrected")
}

/// The real logs of this run, sorted.
pub fn real_logs(ctx: &EvalContext, plan: &Plan) -> Vec<String> {
    data::files_ending(&real_dir(ctx), &[REAL_SUFFIX])
        .iter()
        .map(|p| data::log_name(p))
        .filter(|name| {
            plan.real_logs
                .is_none_or(|names| names.contains(&name.as_str()))
        })
        .collect()
}

/// The indoor worlds of this run, sorted (the generated set's world names; quick: the plan's).
pub fn indoor_worlds(plan: &Plan) -> Vec<String> {
    let mut worlds: Vec<String> = match plan.sim_logs {
        Some(names) => names.iter().map(|n| (*n).to_owned()).collect(),
        None => IndoorConfig::default()
            .worlds
            .into_iter()
            .map(|w| w.name)
            .collect(),
    };
    worlds.sort();
    worlds
}

/// The 2-D scoring of this run (`resolution_m`: the cell edge).
fn config_2d(plan: &Plan) -> ScoringConfig {
    ScoringConfig {
        seed: SEED,
        beam_step: plan.beam_step_2d,
        max_test_scans: plan.max_test_scans_2d,
        ..ScoringConfig::default()
    }
}

/// Scores a 2-D log; a real one also at [`COARSE_CELL_M`].
fn score_planar(path: &Path, kind: Kind, plan: &Plan) -> Result<UnitResult> {
    let started = Instant::now();
    let scans = data::carmen_scans(path).with_context(|| format!("reading {}", path.display()))?;
    let config = config_2d(plan);
    let report =
        score_log(&scans, &config).with_context(|| format!("scoring {}", path.display()))?;
    let coarse = match kind {
        Kind::Real => {
            let config = ScoringConfig {
                resolution_m: COARSE_CELL_M,
                ..config
            };
            Some(
                score_log(&scans, &config)
                    .with_context(|| format!("scoring {} at {COARSE_CELL_M} m", path.display()))?,
            )
        }
        _ => None,
    };
    Ok(UnitResult::Scored(Box::new(Scored {
        set: DataSet {
            name: data::log_name(path),
            kind,
            scans: scans.len(),
            report,
        },
        coarse,
        seconds: started.elapsed().as_secs_f64(),
    })))
}

/// The unit of real log `name`.
pub fn real_log(ctx: &EvalContext, plan: &Plan, name: &str) -> Result<UnitResult> {
    let path = real_dir(ctx).join(format!("{name}{REAL_SUFFIX}"));
    if !path.exists() {
        return Ok(UnitResult::Absent);
    }
    score_planar(&path, Kind::Real, plan)
}

/// The unit of indoor world `world` (generating the indoor set first when it is missing).
pub fn indoor_world(ctx: &EvalContext, plan: &Plan, world: &str) -> Result<UnitResult> {
    let dir = match generate::ensure("indoor", ctx.quick) {
        Ok(dir) => dir,
        Err(e) => {
            return Ok(UnitResult::Unavailable(format!(
                "Simulated indoor worlds unavailable: {e:#}."
            )));
        }
    };
    let file = data::files_ending(&dir, &SIM_SUFFIXES)
        .into_iter()
        .find(|p| data::log_name(p) == world);
    match file {
        Some(path) => score_planar(&path, Kind::Sim2, plan),
        None => Ok(UnitResult::Absent),
    }
}

/// The unit of the simulated urban drive (generated first when it is missing).
pub fn urban(ctx: &EvalContext, plan: &Plan) -> Result<UnitResult> {
    let dir = match generate::ensure("urban-kitti", ctx.quick) {
        Ok(dir) => dir,
        Err(e) => {
            return Ok(UnitResult::Unavailable(format!(
                "Simulated urban drive unavailable: {e:#}."
            )));
        }
    };
    let started = Instant::now();
    let sequence = dir.join("sequences/00");
    let bar = ctx.progress(plan.frames_3d as u64, "urban scans");
    let ray_step = |frame: usize| {
        if frame % 2 == 0 {
            plan.map_ray_step_3d
        } else {
            plan.test_ray_step_3d
        }
    };
    let scans = data::kitti_scans(&sequence, plan.frames_3d, ray_step, || bar.inc(1))
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
    let spinner = ctx.progress(1, "urban scoring");
    let report = score_spatial(&map, &test, &config_3d(plan)).context("scoring urban-kitti")?;
    spinner.finish_and_clear();
    Ok(UnitResult::Scored(Box::new(Scored {
        set: DataSet {
            name: "urban-kitti".into(),
            kind: Kind::Sim3,
            scans: scans.len(),
            report,
        },
        coarse: None,
        seconds: started.elapsed().as_secs_f64(),
    })))
}

/// The 3-D scoring of this run.
fn config_3d(plan: &Plan) -> ScoringConfig {
    ScoringConfig {
        resolution_m: VOXEL_M,
        max_range_m: Some(MAX_RANGE_3D_M),
        seed: SEED,
        beam_step: 1,
        max_test_scans: Some(plan.max_test_scans_3d),
        ..ScoringConfig::default()
    }
}
