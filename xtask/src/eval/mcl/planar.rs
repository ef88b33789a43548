//! 2-D MCL on CARMEN logs: raw log (odometry + scans) against a map and ground truth from the
//! corrected log (real Radish logs and the simulated indoor worlds).

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use nalgebra::{Point2, Vector2};
use raypath_geometry::{Aabb2, Grid2, Pose2, Scan2};
use raypath_io::carmen::CarmenReader;
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
/// Largest gap between a corrected and a raw logger timestamp that still pairs them, seconds
/// (the corrected logs print the raw stamp with fewer digits).
const MATCH_TOLERANCE_SECS: f64 = 2e-3;

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

fn read_scans(path: &Path) -> Result<Vec<(f64, Pose2, Pose2, Scan2)>> {
    let reader = CarmenReader::open(path).with_context(|| format!("opening {}", path.display()))?;
    let mut out = Vec::new();
    for m in reader.front_lasers() {
        let m = m?;
        out.push((
            m.logger_timestamp_secs,
            m.world_from_robot,
            m.world_from_laser,
            m.scan,
        ));
    }
    Ok(out)
}

/// Loads `raw` and `corrected`, builds the map from the corrected scans and pairs the
/// ground truth; `max_gt_scans` limits the stretch (quick mode).
pub fn load(
    name: &str,
    raw: &Path,
    corrected: &Path,
    max_gt_scans: Option<usize>,
) -> Result<PlanarProblem> {
    let raw_scans = read_scans(raw)?;
    let corrected_scans = read_scans(corrected)?;
    if raw_scans.is_empty() || corrected_scans.is_empty() {
        bail!("{name}: no laser scans");
    }
    let robot_from_laser = raw_scans[0].1.inverse() * raw_scans[0].2;

    // Map from all corrected scans at their corrected laser poses.
    let mut bounds = Aabb2::empty();
    let mapping = MappingConfig::default();
    for (_, _, pose, scan) in &corrected_scans {
        bounds.extend(&Point2::new(pose.x(), pose.y()));
        for (i, p) in scan.points(*pose).enumerate() {
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
    let refs: Vec<(Pose2, &Scan2)> = corrected_scans.iter().map(|(_, _, p, s)| (*p, s)).collect();
    stats.insert_scans_par(&refs, &mapping);

    // Pair corrected scans with raw scans by logger timestamp.
    let raw_stamps: Vec<f64> = raw_scans.iter().map(|s| s.0).collect();
    let mut matched: Vec<(usize, Pose2)> = Vec::new();
    for (stamp, _, world_from_laser, _) in &corrected_scans {
        let i = raw_stamps.partition_point(|t| t < stamp);
        let best = [i.wrapping_sub(1), i]
            .into_iter()
            .filter_map(|j| raw_stamps.get(j).map(|t| (j, (t - stamp).abs())))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((j, gap)) = best
            && gap <= MATCH_TOLERANCE_SECS
        {
            matched.push((j, *world_from_laser * robot_from_laser.inverse()));
        }
    }
    matched.sort_by_key(|m| m.0);
    matched.dedup_by_key(|m| m.0);
    // Keep strictly increasing times (raw logs repeat a logger stamp now and then).
    let mut last_stamp = f64::NEG_INFINITY;
    matched.retain(|(j, _)| {
        let t = raw_stamps.get(*j).copied().unwrap_or(f64::NAN);
        let keep = t > last_stamp;
        if keep {
            last_stamp = t;
        }
        keep
    });
    if matched.len() < 2 {
        bail!(
            "{name}: only {} corrected scans matched raw scans",
            matched.len()
        );
    }
    if let Some(limit) = max_gt_scans {
        matched.truncate(limit.max(2));
    }
    let first = matched[0].0;
    let last = matched[matched.len() - 1].0;
    let forced: std::collections::HashSet<usize> = matched.iter().map(|m| m.0).collect();
    let steps: Vec<PlanarStep> = raw_scans[first..=last]
        .iter()
        .enumerate()
        .map(|(k, (stamp, odom, _, scan))| PlanarStep {
            stamp_secs: *stamp,
            odom_from_robot: *odom,
            scan: scan.clone(),
            force_update: forced.contains(&(first + k)),
        })
        .collect();
    let ground_truth = PoseTrack::new(
        matched
            .iter()
            .filter_map(|(j, pose)| raw_scans.get(*j).map(|s| Stamped::new(s.0, *pose))),
    )?;
    Ok(PlanarProblem {
        name: name.to_owned(),
        stats,
        mapping,
        steps,
        robot_from_laser,
        ground_truth,
        corrected_scans: corrected_scans.len(),
    })
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
