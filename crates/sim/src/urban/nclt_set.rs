//! NCLT-style sessions: several drives through one street world months apart (with the
//! changes of [`sessions`](super::sessions)), scanned with an HDL-32E at 10 Hz and written in
//! the NCLT layout:
//!
//! ```text
//! <out>/poles.csv                                    poles of the first (mapping) session
//! <out>/<date>/poles.csv                             poles of this session
//! <out>/<date>/velodyne_data/<date>_vel/velodyne_sync/<utime>.bin
//! <out>/<date>/ground_truth/groundtruth_<date>.csv   at the scan times
//! <out>/<date>/ground_truth_cov/cov_<date>.csv       constant (2 cm, 0.1°)²
//! <out>/<date>/sensor_data/<date>_sen/odometry_mu_100hz.csv   integrated noisy odometry
//! <out>/<date>/sensor_data/<date>_sen/odometry_mu.csv         increments between scans
//! <out>/<date>/sensor_data/<date>_sen/odometry_cov.csv        their covariances
//! ```
//!
//! **Frames.** The world frame of the poles and of the ground truth read back with
//! `NcltPose::world_from_body` is the simulator's world frame (REP-103, x east, y north, z
//! up); the files store it the NCLT way (NED, body x forward, y right, z down). The body
//! frame is the velodyne frame (the ground-truth pose is the sensor pose), and the points are
//! stored like NCLT's, z down: read them with `raypath_io::nclt::flu_from_frd` to get
//! REP-103 points. Intensities are the simulated `[0, 1]` values × 255, laser ids the HDL-32E
//! hardware ids. The odometry frame starts at the identity at the first sample (100 Hz);
//! increments are in the stored body axes (`NcltPose::from_increment`).
//!
//! The HDL-32E range is limited to 95 m here: NCLT's `u16` encoding (0.005 m steps from
//! −100 m) cannot store coordinates below −100 m.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use nalgebra::{Matrix6, Point2};
use rand::Rng;
use rayon::prelude::*;
use raypath_geometry::{Pose2, Pose3};
use raypath_io::nclt::{self, CovarianceRecord, NcltLayout, NcltPose};

use super::kitti_set::{plan_drive, poles_near, start_node};
use super::odometry::{self, OdometryNoise};
use super::output::{
    ScanStats, list_files, parse_date, pole_counts_json, remove_stale, write_poles_csv,
};
use super::route::{self, BodyMotion, DriveConfig};
use super::sessions::{SessionChanges, session_worlds};
use super::streets::{StreetConfig, StreetGrid, generate_layout};
use crate::error::{Result, SimError};
use crate::lidar3::Lidar3;
use crate::rng;
use crate::{GeneratedSet, Progress};

const DOMAIN_ROUTE: u64 = 0x5552_424e_524f_5554;
const DOMAIN_BODY: u64 = 0x5552_424e_424f_4459;
const DOMAIN_ODOMETRY: u64 = 0x5552_424e_4f44_4f4d;
const DOMAIN_LIDAR: u64 = 0x5552_424e_4c49_4441;

/// Odometry samples per scan (100 Hz odometry, 10 Hz scans).
const ODOMETRY_PER_SCAN: usize = 10;
/// Largest range of the simulated HDL-32E in this layout (see the module documentation).
pub const NCLT_MAX_RANGE_M: f64 = 95.0;

/// Configuration of NCLT-style sessions.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct UrbanNcltConfig {
    /// The street world.
    pub streets: StreetConfig,
    /// How the vehicle drives (sensor 1.5 m above the road, 5–8 m/s).
    pub drive: DriveConfig,
    /// Session dates, `YYYY-MM-DD`, in order (the month sets the foliage).
    pub sessions: Vec<String>,
    /// Scans per session (10 Hz).
    pub scans_per_session: usize,
    /// What changes between sessions.
    pub changes: SessionChanges,
    /// Noise of the wheel odometry.
    pub odometry: OdometryNoise,
    /// Firings per revolution of the HDL-32E (2170 at 10 Hz).
    pub firings: usize,
}

impl Default for UrbanNcltConfig {
    /// Four sessions over 13 months (winter, spring, summer, and the winter of the moved
    /// barrels, 2013-02-23) of 600 scans each in a 5 × 4 block world.
    fn default() -> Self {
        Self {
            streets: StreetConfig::default(),
            drive: DriveConfig {
                speed_m_s: (5.0, 8.0),
                turn_radius_m: 7.0,
                sensor_height_m: 1.5,
                ..DriveConfig::default()
            },
            sessions: ["2012-01-08", "2012-05-26", "2012-08-20", "2013-02-23"]
                .map(String::from)
                .to_vec(),
            scans_per_session: 600,
            changes: SessionChanges::default(),
            odometry: OdometryNoise::default(),
            firings: crate::lidar3::HDL32E_FIRINGS_10HZ,
        }
    }
}

impl UrbanNcltConfig {
    /// Two sessions (winter and summer) of 120 scans in a 3 × 3 block world.
    pub fn quick() -> Self {
        Self {
            streets: StreetConfig::quick(),
            sessions: ["2012-01-08", "2012-08-20"].map(String::from).to_vec(),
            scans_per_session: 120,
            ..Self::default()
        }
    }
}

/// Generates the sessions under `out_dir`. Deterministic by seed.
pub fn generate_nclt(
    config: &UrbanNcltConfig,
    seed: u64,
    out_dir: &Path,
    progress: Progress,
) -> Result<GeneratedSet> {
    if config.scans_per_session == 0 || config.sessions.is_empty() {
        return Err(SimError::InvalidParameter {
            name: "sessions/scans_per_session",
            reason: "at least one session of one scan".into(),
        });
    }
    let mut months = Vec::with_capacity(config.sessions.len());
    for date in &config.sessions {
        months.push(parse_date(date)?.1);
    }
    let started = Instant::now();
    let layout = generate_layout(&config.streets, seed)?;
    let worlds = session_worlds(&layout, &months, &config.changes, seed);
    let start = start_node(&layout.grid, &mut rng::stream(seed, DOMAIN_ROUTE, u64::MAX));
    let mut lidar = Lidar3::hdl32e().with_firings(config.firings)?;
    lidar.max_range_m = lidar.max_range_m.min(NCLT_MAX_RANGE_M);
    let total = (config.sessions.len() * config.scans_per_session) as u64;
    let done = AtomicU64::new(0);
    let report = |_: u64, _: u64| progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
    progress(0, total);
    let mut session_stats = Vec::new();
    let mut first_positions: Vec<Point2<f64>> = Vec::new();
    let mut all = ScanStats::default();
    for (k, (date, (world, log))) in config.sessions.iter().zip(&worlds).enumerate() {
        let session = write_session(
            config,
            &lidar,
            &layout.grid,
            date,
            k as u64,
            world,
            start,
            seed,
            out_dir,
            &report,
        )?;
        let poles = world.pole_list();
        write_poles_csv(
            &out_dir.join(date).join("poles.csv"),
            &poles,
            &Pose3::identity(),
        )?;
        if k == 0 {
            write_poles_csv(&out_dir.join("poles.csv"), &poles, &Pose3::identity())?;
            first_positions.clone_from(&session.positions);
        }
        let overlap = session
            .positions
            .iter()
            .filter(|p| first_positions.iter().any(|q| (*p - q).norm() < 5.0))
            .count() as f64
            / session.positions.len().max(1) as f64;
        all.merge(&session.scans);
        session_stats.push(serde_json::json!({
            "date": date,
            "scans": session.scans.to_json(),
            "trajectory_length_m": session.length_m,
            "odometry_final_error_m": session.odometry_error_m,
            "fraction_of_poses_within_5m_of_the_first_session": overlap,
            "poles": pole_counts_json(&poles),
            "poles_within_30m_of_trajectory": pole_counts_json(&poles_near(&poles, &session.positions, 30.0)),
            "changes": {
                "removed": log.removed.len(),
                "moved": log.moved.len(),
                "added": log.added.len(),
                "parked_cars": log.parked_cars,
                "barrel_shifts_m": log.barrel_shifts_m,
                "foliage": log.foliage,
            },
        }));
    }
    let elapsed = started.elapsed().as_secs_f64();
    let stats = serde_json::json!({
        "lidar": lidar.name,
        "rays_per_scan": lidar.num_rays(),
        "sessions": session_stats,
        "scans": all.to_json(),
        "world": {
            "blocks": [config.streets.blocks_x, config.streets.blocks_y],
            "buildings": layout.world.buildings.len(),
            "fences": layout.world.fences.len(),
            "parking_slots": layout.parking.len(),
            "construction_zones": layout.construction.len(),
        },
        "elapsed_s": elapsed,
        "rays_per_s": all.rays as f64 / elapsed.max(1e-9),
    });
    Ok(GeneratedSet {
        name: "urban-nclt".into(),
        description: "Sessions months apart through one procedural street world with changes, \
                      driven with a simulated HDL-32E at 10 Hz (NCLT layout with ground truth, \
                      noisy odometry and the pole ground truth per session)"
            .into(),
        files: list_files(out_dir)?,
        stats,
    })
}

/// What one session produced.
struct SessionOutput {
    scans: ScanStats,
    positions: Vec<Point2<f64>>,
    length_m: f64,
    odometry_error_m: f64,
}

#[allow(clippy::too_many_arguments)]
fn write_session(
    config: &UrbanNcltConfig,
    lidar: &Lidar3,
    grid: &StreetGrid,
    date: &str,
    index: u64,
    world: &super::World,
    start: (usize, usize),
    seed: u64,
    out_dir: &Path,
    report: &(dyn Fn(u64, u64) + Sync),
) -> Result<SessionOutput> {
    let scene = world.build_scene()?;
    let mut rng = rng::stream(seed, DOMAIN_ROUTE, index);
    let samples = (config.scans_per_session - 1) * ODOMETRY_PER_SCAN + 1;
    let period = 0.1 / ODOMETRY_PER_SCAN as f64;
    let (states, length_m) = plan_drive(grid, start, &config.drive, samples, period, &mut rng)?;
    let body = BodyMotion::new(
        config.drive.body_motion_deg,
        &mut rng::stream(seed, DOMAIN_BODY, index),
    );
    let t0 = super::output::date_utime(date, 15)?;
    let utime = |t: f64| t0 + (t * 1e6).round() as u64;
    let scan_states: Vec<_> = states.iter().step_by(ODOMETRY_PER_SCAN).copied().collect();
    let sensor_poses: Vec<Pose3> = scan_states
        .iter()
        .map(|s| route::sensor_pose(s, 0.0, config.drive.sensor_height_m, &body))
        .collect();
    let files = NcltLayout::new(out_dir, date);
    files.create_dirs()?;
    remove_stale(&files.velodyne_sync_dir(), "bin")?;
    // Ground truth and its covariance at the scan times.
    let gt: Vec<NcltPose> = scan_states
        .iter()
        .zip(&sensor_poses)
        .map(|(s, p)| NcltPose::from_world_from_body(utime(s.time_s), p))
        .collect();
    nclt::write_pose_csv(&files.ground_truth_path(), &gt)?;
    let gt_cov = Matrix6::from_diagonal(&nalgebra::Vector6::new(
        4e-4,
        4e-4,
        4e-4,
        0.1f64.to_radians().powi(2),
        0.1f64.to_radians().powi(2),
        0.1f64.to_radians().powi(2),
    ));
    let cov_rows: Vec<CovarianceRecord> = gt
        .iter()
        .map(|g| CovarianceRecord {
            utime: g.utime,
            matrix: gt_cov,
        })
        .collect();
    nclt::write_covariance_csv(&files.ground_truth_cov_path(), &cov_rows)?;
    // Odometry: integrated at 100 Hz, increments between scans.
    let truth: Vec<Pose2> = states.iter().map(|s| s.pose).collect();
    let odo = odometry::simulate(
        &truth,
        &config.odometry,
        &mut rng::stream(seed, DOMAIN_ODOMETRY, index),
    );
    let odo_rows: Vec<NcltPose> = states
        .iter()
        .zip(&odo.poses)
        .map(|(s, p)| NcltPose::from_world_from_body(utime(s.time_s), &p.to_pose3()))
        .collect();
    nclt::write_pose_csv(&files.odometry_path(), &odo_rows)?;
    let mut rel_rows = Vec::with_capacity(scan_states.len());
    let mut rel_cov = Vec::with_capacity(scan_states.len());
    for (k, s) in scan_states.iter().enumerate() {
        let (a, b) = (
            k.saturating_sub(1) * ODOMETRY_PER_SCAN,
            k * ODOMETRY_PER_SCAN,
        );
        let (increment, var) = odo.between(a, b).unwrap_or((Pose2::identity(), [0.0; 3]));
        rel_rows.push(NcltPose::from_increment(
            utime(s.time_s),
            &increment.to_pose3(),
        ));
        let tiny = 1e-8;
        rel_cov.push(CovarianceRecord {
            utime: utime(s.time_s),
            matrix: Matrix6::from_diagonal(&nalgebra::Vector6::new(
                var[0].max(tiny),
                var[1].max(tiny),
                tiny,
                tiny,
                tiny,
                var[2].max(tiny),
            )),
        });
    }
    nclt::write_pose_csv(&files.relative_odometry_path(), &rel_rows)?;
    nclt::write_covariance_csv(&files.relative_odometry_cov_path(), &rel_cov)?;
    let odometry_error_m = match (odo.poses.last(), truth.first(), truth.last()) {
        (Some(o), Some(t0), Some(t1)) => {
            let true_rel = t0.inverse() * *t1;
            (o.translation() - true_rel.translation()).norm()
        }
        _ => 0.0,
    };
    // Scans.
    let lidar_seed: u64 = rng::stream(seed, DOMAIN_LIDAR, index).random();
    let laser_ids = &lidar.laser_ids;
    let cols = lidar.cols();
    let scans = sensor_poses
        .par_iter()
        .zip(&gt)
        .enumerate()
        .map(|(i, (pose, row))| -> Result<ScanStats> {
            let scan = lidar.scan(&scene, pose, lidar_seed, i as u64)?;
            let mut stats = ScanStats::default();
            stats.add(&scan.cloud);
            let mut cloud = scan.cloud;
            nclt::flu_from_frd(&mut cloud);
            if let Some(intensity) = cloud.intensity.as_mut() {
                for v in intensity.iter_mut() {
                    *v = (*v * 255.0).round().clamp(0.0, 255.0);
                }
            }
            cloud.label = Some(
                (0..cloud.len())
                    .map(|p| laser_ids.get(p / cols).copied().unwrap_or(0))
                    .collect(),
            );
            let path: PathBuf = files.scan_path(row.utime);
            nclt::write_velodyne_sync(&path, &cloud)?;
            report(0, 0);
            Ok(stats)
        })
        .try_reduce(ScanStats::default, |mut a, b| {
            a.merge(&b);
            Ok(a)
        })?;
    Ok(SessionOutput {
        scans,
        positions: scan_states
            .iter()
            .map(|s| Point2::new(s.pose.x(), s.pose.y()))
            .collect(),
        length_m,
        odometry_error_m,
    })
}
