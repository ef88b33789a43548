//! A KITTI-style drive through a procedural street world (HDL-64E, 10 Hz), written in the
//! KITTI odometry layout (see [`kitti_out`](super::kitti_out) for the files and frames).

use std::path::Path;
use std::time::Instant;

use nalgebra::Point2;
use rand::Rng;
use raypath_geometry::Pose3;
use raypath_io::kitti::KittiLayout;

use super::kinds::Pole;
use super::kitti_out::{KITTI_PERIOD_S, KittiSequenceFiles, write_sequence};
use super::output::{list_files, pole_counts_json, write_poles_csv};
use super::route::{self, BodyMotion, DriveConfig, PlanarState};
use super::sessions::{SessionChanges, session_worlds};
use super::streets::{StreetConfig, StreetGrid, generate_layout};
use crate::error::{Result, SimError};
use crate::lidar3::Lidar3;
use crate::rng::{self, SimRng};
use crate::{GeneratedSet, Progress};

const DOMAIN_ROUTE: u64 = 0x5552_424b_524f_5554;
const DOMAIN_BODY: u64 = 0x5552_424b_424f_4459;
const DOMAIN_LIDAR: u64 = 0x5552_424b_4c49_4441;

/// Configuration of a KITTI-style urban sequence.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct UrbanKittiConfig {
    /// The street world.
    pub streets: StreetConfig,
    /// How the car drives (sensor 1.73 m above the road, 8–12 m/s).
    pub drive: DriveConfig,
    /// Month of the recording (foliage; KITTI was recorded in September).
    pub month: u32,
    /// Parked cars and barrels (only the parking occupancy matters for one session).
    pub changes: SessionChanges,
    /// Number of scans (10 Hz).
    pub scans: usize,
    /// Sequence name (directory under `sequences/`).
    pub sequence: String,
    /// Firings per revolution of the HDL-64E (2083 at 10 Hz; fewer for faster tests).
    pub firings: usize,
    /// Also write SemanticKITTI labels (`labels/FFFFFF.label`).
    pub labels: bool,
}

impl Default for UrbanKittiConfig {
    /// 1000 scans (100 s, about 1 km) through a 5 × 4 block world.
    fn default() -> Self {
        Self {
            streets: StreetConfig::default(),
            drive: DriveConfig::default(),
            month: 9,
            changes: SessionChanges::default(),
            scans: 1000,
            sequence: "00".into(),
            firings: crate::lidar3::HDL64E_FIRINGS_10HZ,
            labels: true,
        }
    }
}

impl UrbanKittiConfig {
    /// 150 scans through a 3 × 3 block world.
    pub fn quick() -> Self {
        Self {
            streets: StreetConfig::quick(),
            scans: 150,
            ..Self::default()
        }
    }
}

/// Plans a drive of `count` samples every `period_s` seconds from intersection `start`:
/// random routes of growing length until the drive is long enough.
pub(crate) fn plan_drive(
    grid: &StreetGrid,
    start: (usize, usize),
    drive: &DriveConfig,
    count: usize,
    period_s: f64,
    rng: &mut SimRng,
) -> Result<(Vec<PlanarState>, f64)> {
    let needed_s = count.saturating_sub(1) as f64 * period_s;
    let mut min_length = needed_s * drive.speed_m_s.1 * 1.2 + 100.0;
    for _ in 0..8 {
        let nodes = route::random_route(grid, start, min_length, rng);
        let path = route::lane_path(grid, &nodes, drive, rng)?;
        let profile = route::SpeedProfile::new(&path, drive);
        if profile.duration_s() >= needed_s {
            let states = route::sample_states(&path, &profile, period_s, count);
            let (s_end, _) = profile.at_time(needed_s);
            return Ok((states, s_end));
        }
        min_length *= 2.0;
    }
    Err(SimError::InvalidParameter {
        name: "scans",
        reason: format!("could not plan a drive of {needed_s} s"),
    })
}

/// Random intersection away from the border (when there is one).
pub(crate) fn start_node(grid: &StreetGrid, rng: &mut SimRng) -> (usize, usize) {
    let pick = |n: usize, rng: &mut SimRng| {
        if n > 2 { rng.random_range(1..n - 1) } else { 0 }
    };
    (pick(grid.xs.len(), rng), pick(grid.ys.len(), rng))
}

/// Poles within `radius_m` of any of the positions.
pub(crate) fn poles_near(poles: &[Pole], positions: &[Point2<f64>], radius_m: f64) -> Vec<Pole> {
    poles
        .iter()
        .filter(|p| {
            let q = Point2::new(p.x, p.y);
            positions.iter().any(|t| (t - q).norm() <= radius_m)
        })
        .copied()
        .collect()
}

/// Generates a KITTI-style sequence under `out_dir` (see the [module](super::kitti_out) for
/// the layout). Deterministic by seed.
pub fn generate_kitti(
    config: &UrbanKittiConfig,
    seed: u64,
    out_dir: &Path,
    progress: Progress,
) -> Result<GeneratedSet> {
    if config.scans == 0 {
        return Err(SimError::InvalidParameter {
            name: "scans",
            reason: "at least one scan".into(),
        });
    }
    let started = Instant::now();
    let layout = generate_layout(&config.streets, seed)?;
    let (world, log) = session_worlds(&layout, &[config.month], &config.changes, seed)
        .into_iter()
        .next()
        .ok_or_else(|| SimError::InvalidScene {
            reason: "no session".into(),
        })?;
    let scene = world.build_scene()?;
    let mut rng = rng::stream(seed, DOMAIN_ROUTE, 0);
    let start = start_node(&layout.grid, &mut rng);
    let (states, length_m) = plan_drive(
        &layout.grid,
        start,
        &config.drive,
        config.scans,
        KITTI_PERIOD_S,
        &mut rng,
    )?;
    let body = BodyMotion::new(
        config.drive.body_motion_deg,
        &mut rng::stream(seed, DOMAIN_BODY, 0),
    );
    let scene_from_velo: Vec<Pose3> = states
        .iter()
        .map(|s| route::sensor_pose(s, 0.0, config.drive.sensor_height_m, &body))
        .collect();
    let world_from_scene = scene_from_velo
        .first()
        .map_or(Pose3::identity(), |p| p.inverse());
    let world_from_velo: Vec<Pose3> = scene_from_velo
        .iter()
        .map(|p| world_from_scene * *p)
        .collect();
    let times: Vec<f64> = states.iter().map(|s| s.time_s).collect();
    let kitti_layout = KittiLayout::new(out_dir, config.sequence.clone());
    let lidar = Lidar3::hdl64e().with_firings(config.firings)?;
    let scan_stats = write_sequence(
        &KittiSequenceFiles {
            layout: &kitti_layout,
            world_from_velo: &world_from_velo,
            times_s: &times,
            labels: config.labels,
        },
        &scene,
        &lidar,
        &scene_from_velo,
        rng::stream(seed, DOMAIN_LIDAR, 0).random(),
        progress,
    )?;
    let poles = world.pole_list();
    write_poles_csv(
        &kitti_layout.sequence_dir().join("poles.csv"),
        &poles,
        &world_from_scene,
    )?;
    let elapsed = started.elapsed().as_secs_f64();
    let positions: Vec<Point2<f64>> = states
        .iter()
        .map(|s| Point2::new(s.pose.x(), s.pose.y()))
        .collect();
    let speeds: Vec<f64> = states.iter().map(|s| s.speed_m_s).collect();
    let stats = serde_json::json!({
        "sequence": config.sequence,
        "lidar": lidar.name,
        "rays_per_scan": lidar.num_rays(),
        "scans": scan_stats.to_json(),
        "trajectory_length_m": length_m,
        "duration_s": times.last().copied().unwrap_or(0.0),
        "speed_m_s": {
            "mean": speeds.iter().sum::<f64>() / speeds.len().max(1) as f64,
            "min": speeds.iter().copied().fold(f64::INFINITY, f64::min),
            "max": speeds.iter().copied().fold(0.0, f64::max),
        },
        "world": {
            "blocks": [config.streets.blocks_x, config.streets.blocks_y],
            "triangles": scene.num_triangles(),
            "buildings": world.buildings.len(),
            "parked_cars": log.parked_cars,
            "fences": world.fences.len(),
            "barrels": world.barrels.len(),
            "foliage": world.foliage,
        },
        "poles": pole_counts_json(&poles),
        "poles_within_30m_of_trajectory": pole_counts_json(&poles_near(&poles, &positions, 30.0)),
        "elapsed_s": elapsed,
        "rays_per_s": scan_stats.rays as f64 / elapsed.max(1e-9),
    });
    Ok(GeneratedSet {
        name: format!("urban-kitti-{}", config.sequence),
        description: "A procedural street world driven with a simulated HDL-64E at 10 Hz \
                      (KITTI odometry layout with camera poses, calibration, SemanticKITTI-style \
                      labels and the pole ground truth)"
            .into(),
        files: list_files(out_dir)?,
        stats,
    })
}
