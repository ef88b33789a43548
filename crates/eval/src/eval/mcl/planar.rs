//! 2-D MCL on CARMEN logs: raw log (odometry + scans) against a map and ground truth from the
//! corrected log (real Radish logs and the simulated indoor worlds), read and paired through
//! `raypath_io::sequence` (front laser; raw and corrected scans paired by identical readings).

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use nalgebra::{Point2, Vector2};
use raypath_geometry::{Aabb2, Grid2, Pose2, Scan2};
use raypath_io::sequence::{LaserChoice, PlanarFrame, PlanarOptions, pair_reference, read_planar};
use raypath_localizer::eval::{EvaluationConfig, evaluate_trajectory};
use raypath_localizer::init::{GaussianInit, Initializer};
use raypath_localizer::lidar::{
    LidarConfig, ModelSpec, PlanarStep, Scan2Measurement, TrackConfig, track_planar,
};
use raypath_localizer::{ParticleRng, PoseTrack, Stamped};
use raypath_sensor_models::{DenseStats2, MappingConfig};

use super::common::{Cell, RunResult};

/// Map cell size for the 2-D maps, metres.
pub const CELL_M: f64 = 0.1;

/// A 2-D localization problem: map statistics, the raw steps, and the ground truth.
pub struct PlanarProblem {
    /// Name for tables.
    pub name: String,
    /// Map statistics built from the corrected log.
    pub stats: DenseStats2,
    /// The mapping configuration (range limits).
    pub mapping: MappingConfig,
    /// The raw steps from the first one with ground truth on.
    pub steps: Vec<PlanarStep>,
    /// Laser mounting from the raw log.
    pub robot_from_laser: Pose2,
    /// Ground truth `world_from_robot` at the matched steps.
    pub ground_truth: PoseTrack<Pose2>,
    /// Number of corrected scans and how many matched a raw scan.
    pub corrected_scans: usize,
}

fn read_scans(path: &Path) -> Result<Vec<PlanarFrame>> {
    let options = PlanarOptions {
        laser: LaserChoice::Front,
        ..PlanarOptions::default()
    };
    read_planar(path, &options).with_context(|| format!("reading {}", path.display()))
}

/// Loads `raw` and `corrected`, builds the map from the corrected scans and pairs the
/// ground truth; `max_gt_scans` limits the stretch (quick mode).
pub fn load(
    name: &str,
    raw: &Path,
    corrected: &Path,
    max_gt_scans: Option<usize>,
) -> Result<PlanarProblem> {
    let mut raw_scans = read_scans(raw)?;
    let corrected_scans = read_scans(corrected)?;
    let robot_from_laser = raw_scans[0].robot_from_laser();
    let (stats, mapping) = build_map(&corrected_scans)?;
    let mut matched = ground_truth(&mut raw_scans, &corrected_scans, robot_from_laser);
    if matched.len() < 2 {
        bail!(
            "{name}: only {} corrected scans matched raw scans",
            matched.len()
        );
    }
    if let Some(limit) = max_gt_scans {
        matched.truncate(limit.max(2));
    }
    let ground_truth = PoseTrack::new(
        matched
            .iter()
            .filter_map(|(j, pose)| raw_scans.get(*j).map(|f| Stamped::new(f.stamp_secs, *pose))),
    )?;
    Ok(PlanarProblem {
        name: name.to_owned(),
        stats,
        mapping,
        steps: steps(&raw_scans, &matched),
        robot_from_laser,
        ground_truth,
        corrected_scans: corrected_scans.len(),
    })
}

/// The map from all corrected scans at their corrected laser poses.
fn build_map(corrected_scans: &[PlanarFrame]) -> Result<(DenseStats2, MappingConfig)> {
    let mut bounds = Aabb2::empty();
    let mapping = MappingConfig::default();
    for frame in corrected_scans {
        let (pose, scan) = (frame.world_from_laser, &frame.scan);
        bounds.extend(&Point2::new(pose.x(), pose.y()));
        for (i, p) in scan.points(pose).enumerate() {
            if let raypath_geometry::Range::Hit(r) = scan.range(i)
                && r < mapping.range.max_range_m
            {
                bounds.extend(&p);
            }
        }
    }
    let margin = Vector2::new(1.0, 1.0);
    let grid = Grid2::covering(
        &Aabb2::new(bounds.min - margin, bounds.max + margin),
        CELL_M,
    )?;
    let mut stats = DenseStats2::new(grid);
    let refs: Vec<(Pose2, &Scan2)> = corrected_scans
        .iter()
        .map(|f| (f.world_from_laser, &f.scan))
        .collect();
    stats.insert_scans_par(&refs, &mapping);
    Ok((stats, mapping))
}

/// The raw scans paired with corrected scans by identical readings: (raw index,
/// `world_from_robot`), times strictly increasing (raw logs repeat a logger stamp now and
/// then).
fn ground_truth(
    raw_scans: &mut [PlanarFrame],
    corrected_scans: &[PlanarFrame],
    robot_from_laser: Pose2,
) -> Vec<(usize, Pose2)> {
    pair_reference(raw_scans, corrected_scans);
    let mut matched: Vec<(usize, Pose2)> = Vec::new();
    let mut last_stamp = f64::NEG_INFINITY;
    for (j, frame) in raw_scans.iter().enumerate() {
        if let Some(world_from_laser) = frame.reference
            && frame.stamp_secs > last_stamp
        {
            last_stamp = frame.stamp_secs;
            matched.push((j, world_from_laser * robot_from_laser.inverse()));
        }
    }
    matched
}

/// The raw steps from the first to the last matched scan, an update forced at each matched
/// one.
fn steps(raw_scans: &[PlanarFrame], matched: &[(usize, Pose2)]) -> Vec<PlanarStep> {
    let first = matched[0].0;
    let last = matched[matched.len() - 1].0;
    let forced: std::collections::HashSet<usize> = matched.iter().map(|m| m.0).collect();
    raw_scans[first..=last]
        .iter()
        .enumerate()
        .map(|(k, frame)| PlanarStep {
            stamp_secs: frame.stamp_secs,
            odom_from_robot: frame.world_from_robot,
            scan: frame.scan.clone(),
            force_update: forced.contains(&(first + k)),
        })
        .collect()
}

/// The 2-D filter settings of the evaluation.
pub fn track_config(particles: usize) -> TrackConfig {
    TrackConfig {
        particles,
        ..TrackConfig::default()
    }
}

/// Runs `seeds` seeded filters with `spec` on `problem`.
pub fn run_model(
    problem: &PlanarProblem,
    spec: &ModelSpec,
    lidar: LidarConfig,
    track: &TrackConfig,
    seeds: &[u64],
    mut on_run: impl FnMut(),
) -> Result<Cell> {
    let model = spec.build(&problem.stats, problem.mapping.range)?;
    let measurement = Scan2Measurement::new(model.as_ref(), problem.robot_from_laser, lidar)?;
    let first_truth = problem.ground_truth.poses()[0];
    let mut runs = Vec::new();
    for &seed in seeds {
        // Thesis ch. 7: the initial mean is itself drawn from the initial distribution
        // around the true start.
        let spread = GaussianInit::new(first_truth);
        let mean = spread.sample(&mut ParticleRng::seed_from_u64(seed ^ 0x5eed_0ff5e7));
        let init = GaussianInit::new(mean);
        let started = Instant::now();
        let result = track_planar(&problem.steps, &measurement, &init, track, seed)?;
        let seconds = started.elapsed().as_secs_f64();
        // Evaluate on the scans with ground truth only: between them both tracks are
        // interpolated linearly over the same stamps (the corrected logs are sparse, so the
        // ground truth between its poses is not known better than that).
        let estimate = PoseTrack::new(
            result
                .estimates
                .iter()
                .filter(|(i, _)| problem.steps.get(*i).is_some_and(|s| s.force_update))
                .map(|(_, s)| *s),
        )?;
        let evaluation = evaluate_trajectory(
            &problem.ground_truth,
            &estimate,
            &EvaluationConfig::default(),
        )?;
        runs.push(RunResult::from_evaluation(
            &evaluation,
            result.updates as f64 / seconds.max(1e-9),
        ));
        on_run();
    }
    Ok(Cell {
        dataset: problem.name.clone(),
        model: spec.label(),
        runs,
    })
}
