//! Procedurally generated 2-D indoor worlds driven by a simulated robot with a 2-D laser and
//! wheel odometry, written as CARMEN logs like the Radish logs.
//!
//! * **World** ([`floorplan`]): rooms along corridors, doors, windows, glass partitions,
//!   furniture, posters and columns, as line segments with surfaces (label, reflectivity,
//!   glass transmission).
//! * **Robot** ([`trajectory`], planner): laps from the west end of the main corridor through
//!   the rooms (counter-clockwise around the building, then clockwise, …) and back to the start
//!   (A* on a clearance grid, string pulling, fillets, speed limits 0.45 m/s and 0.6 rad/s by
//!   default; at each room goal the robot may look around and pauses). A lap that does not fit
//!   into the remaining time visits every other room (repeatedly), so logs close their loop;
//!   laps repeat until the requested number of scans is reached.
//! * **Laser** ([`laser`]): 181 beams over 180° or 720 beams over 360°, Gaussian range noise,
//!   no-returns beyond the maximum range and through glass, written with the no-return code;
//!   optional intensities ([`intensity`]).
//! * **Odometry** ([`odometry`]): the odometry motion model of *Probabilistic Robotics* §5.4.
//!
//! # Output per world `<name>`
//!
//! * `<name>-corrected.log` — like the Radish `*-corrected.log` files: `FLASER` lines whose
//!   laser pose (and odometry fields) are the **ground truth**, and `ODOM` lines with the
//!   ground-truth robot pose and velocities at the odometry rate.
//! * `<name>.clf` — the raw log: `ODOM` lines with the **noisy odometry** at the odometry
//!   rate, and `FLASER` (or `ROBOTLASER1`, with remissions when intensities are on) lines
//!   whose poses are the odometry poses at the scan time.
//! * `<name>-world.json` — the world (spaces, doors, surfaces, segments, table footprints),
//!   the configuration and the world seed.
//! * `<name>-poses.csv` — per scan the ground-truth laser pose `x,y,theta`, the logger time
//!   `stamp_secs`, and the odometry laser pose `odom_x,odom_y,odom_theta` (a point CSV).
//!
//! Logs may be gzip- or bzip2-compressed (`.gz`, `.bz2` appended). Both logs carry `PARAM`
//! lines for the laser's field of view and resolution (degrees) and maximum range, so
//! `FLASER` beams are placed by the reader's rule (−90° + i·1° for 181 beams, −180° + i·0.5°
//! for 720). Times: scan `k` at `k / rate` seconds (periods rounded to 0.1 ms), `ODOM` at the
//! odometry rate; the IPC timestamp is `start_unix_secs` + that time, the logger timestamp
//! the time itself.

pub mod floorplan;
mod furniture;
pub mod intensity;
pub mod laser;
pub mod odometry;
mod output;
mod planner;
mod tour;
pub mod trajectory;
mod walls;

use std::path::Path;

use nalgebra::Point2;
use rand::Rng;
use rayon::prelude::*;
use raypath_geometry::Pose2;
use serde::Serialize;

pub use floorplan::{FloorPlanConfig, SurfaceClass, World, generate_world};
pub use intensity::IntensityModel;
pub use laser::{Laser2Config, NoReturn, SimulatedScan};
pub use odometry::OdometryConfig;
pub use trajectory::{RobotConfig, State, Trajectory};

use crate::dataset::{GeneratedSet, Progress};
use crate::error::{Result, SimError};
use crate::out2d;
use crate::rng::stream;

/// Random-stream domains of the indoor generator.
mod domains {
    pub const WORLD_SEED: u64 = 0x696e_646f_6f72_0001;
    pub const PLAN: u64 = 0x696e_646f_6f72_0002;
    pub const PATH: u64 = 0x696e_646f_6f72_0003;
    pub const ODOMETRY: u64 = 0x696e_646f_6f72_0004;
    pub const LASER: u64 = 0x696e_646f_6f72_0005;
}

/// Compression of a written log.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Compression {
    /// Plain text.
    #[default]
    None,
    /// gzip (`.gz`).
    Gzip,
    /// bzip2 (`.bz2`).
    Bzip2,
}

impl Compression {
    /// The file-name suffix: `""`, `".gz"` or `".bz2"`.
    pub fn suffix(self) -> &'static str {
        match self {
            Compression::None => "",
            Compression::Gzip => ".gz",
            Compression::Bzip2 => ".bz2",
        }
    }
}

/// Which message carries the scans of the raw log.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum RawLaserMessage {
    /// `ROBOTLASER1` when the laser has intensities (remissions need it), else `FLASER`.
    #[default]
    Auto,
    /// Always `FLASER`.
    Flaser,
    /// Always `ROBOTLASER1`.
    RobotLaser1,
}

/// One world and the run through it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WorldConfig {
    /// File-name stem of the world's files.
    pub name: String,
    /// The floor plan.
    pub plan: FloorPlanConfig,
    /// The robot's motion.
    pub robot: RobotConfig,
    /// The laser.
    pub laser: Laser2Config,
    /// The odometry.
    pub odometry: OdometryConfig,
    /// Number of scans.
    pub scans: usize,
    /// The message of the raw log's scans.
    pub raw_laser: RawLaserMessage,
    /// Compression of the corrected log.
    pub corrected_compression: Compression,
    /// Compression of the raw log.
    pub raw_compression: Compression,
    /// UNIX time of the start in seconds (the IPC timestamps).
    pub start_unix_secs: f64,
}

impl WorldConfig {
    /// A world named `name` with default parts and `scans` scans.
    pub fn new(name: &str, plan: FloorPlanConfig, laser: Laser2Config, scans: usize) -> Self {
        Self {
            name: name.into(),
            plan,
            robot: RobotConfig::default(),
            laser,
            odometry: OdometryConfig::default(),
            scans,
            raw_laser: RawLaserMessage::Auto,
            corrected_compression: Compression::None,
            raw_compression: Compression::None,
            start_unix_secs: 1_262_304_000.0,
        }
    }

    /// Checks every part.
    pub fn validate(&self) -> Result<()> {
        if self.name.is_empty() || self.name.contains(['/', '\\', ' ']) {
            return Err(SimError::InvalidParameter {
                name: "name",
                reason: format!("{:?} is not a plain file-name stem", self.name),
            });
        }
        if self.scans == 0 {
            return Err(SimError::InvalidParameter {
                name: "scans",
                reason: "at least one scan".into(),
            });
        }
        self.plan.validate()?;
        self.laser.validate()?;
        self.odometry.validate()
    }

    /// Whether the raw log uses `ROBOTLASER1`.
    pub fn raw_uses_robot_laser(&self) -> bool {
        match self.raw_laser {
            RawLaserMessage::Auto => self.laser.intensity.is_some(),
            RawLaserMessage::Flaser => false,
            RawLaserMessage::RobotLaser1 => true,
        }
    }
}

/// The indoor data set: several worlds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct IndoorConfig {
    /// The worlds, each written under its own name.
    pub worlds: Vec<WorldConfig>,
}

impl Default for IndoorConfig {
    /// Three worlds: `office` (30 × 20 m, one corridor, 181-beam laser, 1000 scans, logs
    /// compressed like the Radish files), `lab` (24 × 18 m, crossing corridors, glass
    /// partitions, 360° laser at 0.5° with intensities, 800 scans) and `hall` (40 × 25 m, a
    /// wide corridor with columns, 20 m laser range, 1000 scans).
    fn default() -> Self {
        let mut office = WorldConfig::new(
            "office",
            FloorPlanConfig::default(),
            Laser2Config::sick_180(),
            1000,
        );
        office.corrected_compression = Compression::Gzip;
        office.raw_compression = Compression::Bzip2;
        let lab = WorldConfig::new(
            "lab",
            FloorPlanConfig {
                width_m: 24.0,
                height_m: 18.0,
                cross_corridor: true,
                glass_partition_probability: 0.35,
                ..FloorPlanConfig::default()
            },
            Laser2Config::full_360().with_intensities(),
            800,
        );
        let hall = WorldConfig::new(
            "hall",
            FloorPlanConfig {
                width_m: 40.0,
                height_m: 25.0,
                corridor_width_m: [4.0, 5.0],
                room_width_m: [4.0, 7.0],
                column_spacing_m: 4.0,
                corridor_cabinets: 5,
                ..FloorPlanConfig::default()
            },
            Laser2Config {
                max_range_m: 20.0,
                ..Laser2Config::sick_180()
            },
            1000,
        );
        Self {
            worlds: vec![office, lab, hall],
        }
    }
}

impl IndoorConfig {
    /// Two small worlds with the names of the default set: `office` (16 × 12 m, 600 scans)
    /// and `lab` (18 × 12 m, crossing corridors, 360° laser with intensities, 500 scans).
    pub fn quick() -> Self {
        let mut office = WorldConfig::new(
            "office",
            FloorPlanConfig {
                width_m: 16.0,
                height_m: 12.0,
                ..FloorPlanConfig::default()
            },
            Laser2Config::sick_180(),
            600,
        );
        office.corrected_compression = Compression::Gzip;
        office.raw_compression = Compression::Bzip2;
        let lab = WorldConfig::new(
            "lab",
            FloorPlanConfig {
                width_m: 18.0,
                height_m: 12.0,
                cross_corridor: true,
                glass_partition_probability: 0.35,
                ..FloorPlanConfig::default()
            },
            Laser2Config::full_360().with_intensities(),
            500,
        );
        Self {
            worlds: vec![office, lab],
        }
    }
}

/// Everything simulated for one world, before writing.
pub struct WorldRun {
    /// The world.
    pub world: World,
    /// The robot's trajectory (ground truth).
    pub trajectory: Trajectory,
    /// Scan times in seconds.
    pub scan_times: Vec<f64>,
    /// Ground-truth laser poses at the scans.
    pub laser_poses: Vec<Pose2>,
    /// Ground-truth robot states at the scans.
    pub scan_states: Vec<State>,
    /// Odometry robot poses at the scans (odometry frame).
    pub scan_odometry: Vec<Pose2>,
    /// The scans.
    pub scans: Vec<SimulatedScan>,
    /// `ODOM` times in seconds.
    pub odometry_times: Vec<f64>,
    /// Ground-truth robot states at the `ODOM` times.
    pub odometry_states: Vec<State>,
    /// Odometry robot poses at the `ODOM` times (odometry frame).
    pub odometry_poses: Vec<Pose2>,
    /// The goals the robot visited, in order.
    pub goals: Vec<Point2<f64>>,
}

/// The seed of world `index` of a data set generated with `seed`.
pub fn world_seed(seed: u64, index: usize) -> u64 {
    stream(seed, domains::WORLD_SEED, index as u64).random()
}

/// Period in units of 0.1 ms.
fn period_ticks(rate_hz: f64) -> u64 {
    (10_000.0 / rate_hz).round().max(1.0) as u64
}

/// Simulates world `config` with the world seed `world_seed` (see [`world_seed`]).
pub fn simulate_world(
    config: &WorldConfig,
    world_seed: u64,
    progress: Progress,
) -> Result<WorldRun> {
    config.validate()?;
    let world = generate_world(&config.plan, &mut stream(world_seed, domains::PLAN, 0))?;
    let scan_period = period_ticks(config.laser.rate_hz);
    let odom_period = period_ticks(config.odometry.rate_hz);
    let last_tick = scan_period * (config.scans as u64 - 1);
    let duration = last_tick as f64 * 1e-4;
    let (trajectory, goals) = tour::plan_tour(
        &world,
        &config.robot,
        duration,
        &mut stream(world_seed, domains::PATH, 0),
    )?;

    // Events: ODOM ticks and scan ticks, merged.
    let mut ticks: Vec<u64> = (0..=last_tick / odom_period)
        .map(|k| k * odom_period)
        .chain((0..config.scans as u64).map(|k| k * scan_period))
        .collect();
    ticks.sort_unstable();
    ticks.dedup();
    let states: Vec<State> = ticks
        .iter()
        .map(|&t| trajectory.at(t as f64 * 1e-4))
        .collect();
    let poses: Vec<Pose2> = states.iter().map(State::pose).collect();
    let start = if config.odometry.start_at_origin {
        Pose2::identity()
    } else {
        poses.first().copied().unwrap_or_default()
    };
    let odom = odometry::simulate(
        &config.odometry.alphas,
        &poses,
        start,
        &mut stream(world_seed, domains::ODOMETRY, 0),
    );
    let mut run = WorldRun {
        world,
        trajectory,
        scan_times: Vec::new(),
        laser_poses: Vec::new(),
        scan_states: Vec::new(),
        scan_odometry: Vec::new(),
        scans: Vec::new(),
        odometry_times: Vec::new(),
        odometry_states: Vec::new(),
        odometry_poses: Vec::new(),
        goals,
    };
    let robot_from_laser = config.laser.robot_from_laser();
    for ((&tick, state), odom_pose) in ticks.iter().zip(&states).zip(&odom) {
        let t = tick as f64 * 1e-4;
        if tick % odom_period == 0 {
            run.odometry_times.push(t);
            run.odometry_states.push(*state);
            run.odometry_poses.push(*odom_pose);
        }
        if tick % scan_period == 0 {
            run.scan_times.push(t);
            run.scan_states.push(*state);
            run.laser_poses.push(state.pose() * robot_from_laser);
            run.scan_odometry.push(*odom_pose);
        }
    }
    let counter = out2d::Counter::new(config.scans as u64, progress);
    let world_ref = &run.world;
    run.scans = run
        .laser_poses
        .par_iter()
        .enumerate()
        .map(|(k, pose)| {
            let scan = laser::scan(
                world_ref,
                pose,
                &config.laser,
                &mut stream(world_seed, domains::LASER, k as u64),
            );
            counter.tick();
            scan
        })
        .collect();
    Ok(run)
}

/// Generates the indoor set under `out_dir` (see the module documentation for the files).
pub fn generate(
    config: &IndoorConfig,
    seed: u64,
    out_dir: &Path,
    progress: Progress,
) -> Result<GeneratedSet> {
    if config.worlds.is_empty() {
        return Err(SimError::InvalidParameter {
            name: "worlds",
            reason: "at least one world".into(),
        });
    }
    for w in &config.worlds {
        w.validate()?;
    }
    out2d::create_dir(out_dir)?;
    let total: u64 = config.worlds.iter().map(|w| w.scans as u64).sum();
    let done_before = std::sync::atomic::AtomicU64::new(0);
    let mut files = Vec::new();
    let mut stats = serde_json::Map::new();
    for (i, world_config) in config.worlds.iter().enumerate() {
        let offset = done_before.load(std::sync::atomic::Ordering::Relaxed);
        let report = |done: u64, _total: u64| progress(offset + done, total);
        let seed_i = world_seed(seed, i);
        let run = simulate_world(world_config, seed_i, &report)?;
        let written = output::write_world(world_config, seed_i, &run, out_dir)?;
        stats.insert(
            world_config.name.clone(),
            output::statistics(world_config, &run, &written),
        );
        files.extend(written);
        done_before.fetch_add(
            world_config.scans as u64,
            std::sync::atomic::Ordering::Relaxed,
        );
    }
    Ok(GeneratedSet {
        name: "indoor".into(),
        description:
            "Procedural 2-D indoor worlds (rooms, corridors, doors, glass, furniture) with \
                      a robot's laser scans and noisy odometry, as CARMEN logs (corrected log with \
                      ground-truth poses, raw log with odometry) like the Radish logs"
                .into(),
        files: out2d::sorted(files),
        stats: serde_json::Value::Object(stats),
    })
}
