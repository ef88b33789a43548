//! Writing a simulated world: the corrected and raw CARMEN logs, the world JSON, the
//! ground-truth pose CSV, and the statistics.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use raypath_geometry::{Pose2, Scan2, wrap_angle};
use raypath_io::carmen::{
    CarmenWriter, FanConvention, LaserKind, LaserMessage, OdometryMessage, RobotLaserInfo,
    Velocities,
};
use serde::Serialize;

use super::floorplan::{Door, Material, Space, SurfaceClass, WorldSegment};
use super::laser::NoReturn;
use super::{Compression, WorldConfig, WorldRun};
use crate::error::{Result, SimError};
use crate::out2d;

const HOST: &str = "raypath-sim";

/// Whether the reader places the beams of an `n`-beam `FLASER` scan with this resolution
/// where the laser has them.
fn flaser_expresses(config: &WorldConfig) -> bool {
    let l = &config.laser;
    let (min, inc) = FanConvention::Auto.layout(l.beams, l.fov_rad(), Some(l.angle_increment_rad));
    (min - l.angle_min_rad).abs() < 1e-9 && (inc - l.angle_increment_rad).abs() < 1e-12
}

fn params(w: &mut CarmenWriter<Vec<u8>>, config: &WorldConfig) -> raypath_io::Result<()> {
    let l = &config.laser;
    w.param("robot_frontlaser_offset", &format!("{}", l.mount[0]))?;
    w.param(
        "laser_front_laser_fov",
        &format!("{}", l.fov_rad().to_degrees()),
    )?;
    w.param(
        "laser_front_laser_resolution",
        &format!("{}", l.angle_increment_rad.to_degrees()),
    )?;
    w.param("robot_front_laser_max", &format!("{}", l.max_range_m))
}

fn laser_message(
    config: &WorldConfig,
    kind: LaserKind,
    scan: &super::SimulatedScan,
    world_from_laser: Pose2,
    world_from_robot: Pose2,
    velocities: Velocities,
    t: f64,
) -> LaserMessage {
    let l = &config.laser;
    let robot_laser = kind == LaserKind::RobotLaser1;
    LaserMessage {
        kind,
        scan: Scan2 {
            angle_min_rad: l.angle_min_rad,
            angle_increment_rad: l.angle_increment_rad,
            max_range_m: l.max_range_m,
            ranges: scan.ranges.clone(),
            intensities: if robot_laser {
                scan.intensities.clone()
            } else {
                None
            },
        },
        world_from_laser,
        world_from_robot,
        velocities: robot_laser.then_some(velocities),
        robot_laser: robot_laser.then_some(RobotLaserInfo {
            laser_type: l.laser_type,
            fov_rad: l.fov_rad(),
            stated_max_range_m: l.max_range_m,
            accuracy_m: l.range_sigma_m,
            remission_mode: i64::from(scan.intensities.is_some()),
            forward_safety_m: 0.0,
            side_safety_m: 0.0,
            turn_axis: 0.0,
        }),
        ipc_timestamp_secs: config.start_unix_secs + t,
        hostname: HOST.into(),
        logger_timestamp_secs: t,
        line: 0,
    }
}

fn odometry_message(
    config: &WorldConfig,
    pose: Pose2,
    velocities: Velocities,
    t: f64,
) -> OdometryMessage {
    OdometryMessage {
        world_from_robot: pose,
        velocities,
        accel_mps2: 0.0,
        ipc_timestamp_secs: config.start_unix_secs + t,
        hostname: HOST.into(),
        logger_timestamp_secs: t,
        line: 0,
    }
}

/// Writes one log: the header, `PARAM`s, then `ODOM` and laser messages in time order
/// (`ODOM` first at equal times). `laser_at(k)` and `odom_at(j)` build the messages.
fn write_log(
    config: &WorldConfig,
    run: &WorldRun,
    path: &Path,
    comment: &str,
    odom_at: &dyn Fn(usize) -> OdometryMessage,
    laser_at: &dyn Fn(usize) -> LaserMessage,
) -> Result<Vec<u8>> {
    let mut w = CarmenWriter::new(Vec::new(), path);
    let io = out2d::io_error;
    w.header().map_err(io)?;
    w.comment(comment).map_err(io)?;
    params(&mut w, config).map_err(io)?;
    let (mut j, mut k) = (0, 0);
    let (n_odom, n_scan) = (run.odometry_times.len(), run.scan_times.len());
    while j < n_odom || k < n_scan {
        let odom_next =
            j < n_odom && (k >= n_scan || run.odometry_times.get(j) <= run.scan_times.get(k));
        if odom_next {
            w.odometry(&odom_at(j)).map_err(io)?;
            j += 1;
        } else {
            w.laser(&laser_at(k)).map_err(io)?;
            k += 1;
        }
    }
    w.finish().map_err(io)
}

fn compress(bytes: Vec<u8>, compression: Compression, path: &Path) -> Result<Vec<u8>> {
    let err = |source: std::io::Error| SimError::File {
        path: path.to_path_buf(),
        source,
    };
    match compression {
        Compression::None => Ok(bytes),
        Compression::Gzip => {
            let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
            e.write_all(&bytes).map_err(err)?;
            e.finish().map_err(err)
        }
        Compression::Bzip2 => {
            let mut e = bzip2::write::BzEncoder::new(Vec::new(), bzip2::Compression::default());
            e.write_all(&bytes).map_err(err)?;
            e.finish().map_err(err)
        }
    }
}

/// Odometry velocities from consecutive odometry poses `dt` seconds apart.
fn odometry_velocities(prev: Option<&Pose2>, pose: &Pose2, dt: f64) -> Velocities {
    match prev {
        Some(p) if dt > 0.0 => {
            let d = pose.translation() - p.translation();
            let forward = d.x * p.theta().cos() + d.y * p.theta().sin();
            Velocities {
                tv_mps: forward / dt,
                rv_radps: wrap_angle(pose.theta() - p.theta()) / dt,
            }
        }
        _ => Velocities {
            tv_mps: 0.0,
            rv_radps: 0.0,
        },
    }
}

#[derive(Serialize)]
struct WorldFile<'a> {
    generator: &'static str,
    world_seed: u64,
    config: &'a WorldConfig,
    bounds: [[f64; 2]; 2],
    spaces: &'a [Space],
    doors: &'a [Door],
    windows: usize,
    surfaces: Vec<SurfaceEntry<'a>>,
    segments: &'a [WorldSegment],
    footprints: &'a [Vec<[f64; 2]>],
    goals: Vec<[f64; 2]>,
}

#[derive(Serialize)]
struct SurfaceEntry<'a> {
    id: usize,
    #[serde(flatten)]
    material: &'a Material,
}

/// Writes the files of one world; returns their names relative to `out_dir`.
pub(super) fn write_world(
    config: &WorldConfig,
    world_seed: u64,
    run: &WorldRun,
    out_dir: &Path,
) -> Result<Vec<PathBuf>> {
    let name = &config.name;
    let robot_from_laser = config.laser.robot_from_laser();
    let corrected_kind = if flaser_expresses(config) {
        LaserKind::Front
    } else {
        LaserKind::RobotLaser1
    };
    let raw_kind = if config.raw_uses_robot_laser() || corrected_kind == LaserKind::RobotLaser1 {
        LaserKind::RobotLaser1
    } else {
        LaserKind::Front
    };
    let mut files = Vec::new();

    // Corrected log: ground truth.
    let corrected_name = format!(
        "{name}-corrected.log{}",
        config.corrected_compression.suffix()
    );
    let corrected_path = out_dir.join(&corrected_name);
    let velocities = |s: &super::State| Velocities {
        tv_mps: s.v,
        rv_radps: s.omega,
    };
    let bytes = write_log(
        config,
        run,
        &corrected_path,
        &format!(
            "raypath-sim indoor world {name}: ground-truth poses (FLASER x y theta = laser pose, odom fields = robot pose; ODOM = robot pose)"
        ),
        &|j| {
            let s = &run.odometry_states[j];
            odometry_message(config, s.pose(), velocities(s), run.odometry_times[j])
        },
        &|k| {
            let s = &run.scan_states[k];
            laser_message(
                config,
                corrected_kind,
                &run.scans[k],
                run.laser_poses[k],
                s.pose(),
                velocities(s),
                run.scan_times[k],
            )
        },
    )?;
    out2d::write_file(
        &corrected_path,
        &compress(bytes, config.corrected_compression, &corrected_path)?,
    )?;
    files.push(PathBuf::from(corrected_name));

    // Raw log: odometry.
    let raw_name = format!("{name}.clf{}", config.raw_compression.suffix());
    let raw_path = out_dir.join(&raw_name);
    let odom_dt = 1.0 / config.odometry.rate_hz;
    let bytes = write_log(
        config,
        run,
        &raw_path,
        &format!("raypath-sim indoor world {name}: raw log (poses are wheel odometry)"),
        &|j| {
            let pose = run.odometry_poses[j];
            let prev = j.checked_sub(1).and_then(|i| run.odometry_poses.get(i));
            odometry_message(
                config,
                pose,
                odometry_velocities(prev, &pose, odom_dt),
                run.odometry_times[j],
            )
        },
        &|k| {
            let pose = run.scan_odometry[k];
            // Velocities of the last odometry interval before the scan.
            let j = run
                .odometry_times
                .partition_point(|&t| t <= run.scan_times[k] + 1e-9);
            let prev = j.checked_sub(2).and_then(|i| run.odometry_poses.get(i));
            let last = j
                .checked_sub(1)
                .and_then(|i| run.odometry_poses.get(i))
                .copied()
                .unwrap_or(pose);
            laser_message(
                config,
                raw_kind,
                &run.scans[k],
                pose * robot_from_laser,
                pose,
                odometry_velocities(prev, &last, odom_dt),
                run.scan_times[k],
            )
        },
    )?;
    out2d::write_file(
        &raw_path,
        &compress(bytes, config.raw_compression, &raw_path)?,
    )?;
    files.push(PathBuf::from(raw_name));

    // Ground-truth poses.
    let poses_name = format!("{name}-poses.csv");
    let mut csv = String::from("x,y,theta,stamp_secs,odom_x,odom_y,odom_theta\n");
    for k in 0..run.scan_times.len() {
        let (p, o) = (run.laser_poses[k], run.scan_odometry[k] * robot_from_laser);
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{}",
            p.x(),
            p.y(),
            p.theta(),
            run.scan_times[k],
            o.x(),
            o.y(),
            o.theta()
        );
    }
    out2d::write_file(&out_dir.join(&poses_name), csv.as_bytes())?;
    files.push(PathBuf::from(poses_name));

    // The world.
    let world_name = format!("{name}-world.json");
    let w = &run.world;
    out2d::write_json(
        &out_dir.join(&world_name),
        &WorldFile {
            generator: "raypath-sim indoor",
            world_seed,
            config,
            bounds: [[0.0, 0.0], [w.config.width_m, w.config.height_m]],
            spaces: &w.spaces,
            doors: &w.doors,
            windows: w.windows,
            surfaces: w
                .materials
                .iter()
                .enumerate()
                .map(|(id, material)| SurfaceEntry { id, material })
                .collect(),
            segments: &w.segments,
            footprints: &w.footprints,
            goals: run.goals.iter().map(|g| [g.x, g.y]).collect(),
        },
    )?;
    files.push(PathBuf::from(world_name));
    Ok(files)
}

/// Statistics of one world for [`crate::GeneratedSet::stats`].
pub(super) fn statistics(
    config: &WorldConfig,
    run: &WorldRun,
    files: &[PathBuf],
) -> serde_json::Value {
    let w = &run.world;
    let (mut returns, mut beyond, mut glass) = (0u64, 0u64, 0u64);
    let mut labels: BTreeMap<String, u64> = BTreeMap::new();
    let (mut rmin, mut rmax, mut rsum) = (f64::INFINITY, 0.0f64, 0.0);
    let (mut imin, mut imax, mut isum, mut icount) = (f64::INFINITY, 0.0f64, 0.0, 0u64);
    let class_of: BTreeMap<u32, SurfaceClass> =
        w.materials.iter().map(|m| (m.label, m.class)).collect();
    for s in &run.scans {
        for (i, nr) in s.no_returns.iter().enumerate() {
            match nr {
                None => {
                    returns += 1;
                    let r = s.ranges[i];
                    rmin = rmin.min(r);
                    rmax = rmax.max(r);
                    rsum += r;
                    let class = class_of
                        .get(&s.labels[i])
                        .map_or("unknown".to_owned(), |c| {
                            serde_json::to_value(c)
                                .ok()
                                .and_then(|v| v.as_str().map(str::to_owned))
                                .unwrap_or_default()
                        });
                    *labels.entry(class).or_insert(0) += 1;
                    if let Some(v) = s.intensities.as_ref().and_then(|v| v.get(i)) {
                        imin = imin.min(*v);
                        imax = imax.max(*v);
                        isum += v;
                        icount += 1;
                    }
                }
                Some(NoReturn::BeyondRange) => beyond += 1,
                Some(NoReturn::ThroughGlass) => glass += 1,
            }
        }
    }
    let beams = returns + beyond + glass;
    // Odometry drift: the odometry trajectory aligned at the start.
    let world_from_odom = match (run.scan_states.first(), run.scan_odometry.first()) {
        (Some(s), Some(o)) => s.pose() * o.inverse(),
        _ => Pose2::identity(),
    };
    let (mut max_err, mut final_err, mut final_heading) = (0.0f64, 0.0, 0.0);
    for (s, o) in run.scan_states.iter().zip(&run.scan_odometry) {
        let aligned = world_from_odom * *o;
        let err = (aligned.translation() - s.pose().translation()).norm();
        max_err = max_err.max(err);
        final_err = err;
        final_heading = wrap_angle(aligned.theta() - s.pose().theta());
    }
    let duration = run.scan_times.last().copied().unwrap_or(0.0);
    let clearance = run
        .trajectory
        .states
        .iter()
        .filter(|s| s.t <= duration)
        .step_by(5)
        .map(|s| w.planning_scene.distance(&s.position()))
        .fold(f64::INFINITY, f64::min);
    let in_log = || run.trajectory.states.iter().filter(|s| s.t <= duration);
    let max_turn = in_log().map(|s| s.omega.abs()).fold(0.0, f64::max);
    let max_speed = in_log().map(|s| s.v).fold(0.0, f64::max);
    let rooms = w
        .spaces
        .iter()
        .filter(|s| s.kind == super::floorplan::SpaceKind::Room)
        .count();
    let length: f64 = run
        .trajectory
        .states
        .windows(2)
        .filter(|w| w[1].t <= duration)
        .map(|w| (w[1].position() - w[0].position()).norm())
        .sum();
    serde_json::json!({
        "files": files,
        "world": {
            "size_m": [w.config.width_m, w.config.height_m],
            "rooms": rooms,
            "corridors": w.spaces.len() - rooms,
            "doors": w.doors.len(),
            "windows": w.windows,
            "segments": w.segments.len(),
            "surfaces": w.materials.len(),
        },
        "scans": run.scans.len(),
        "beams_per_scan": config.laser.beams,
        "odometry_messages": run.odometry_times.len(),
        "duration_s": duration,
        "path_length_m": length,
        "mean_speed_mps": if duration > 0.0 { length / duration } else { 0.0 },
        "max_speed_mps": max_speed,
        "max_turn_rate_radps": max_turn,
        "goals": run.goals.len(),
        "min_clearance_m": clearance,
        "returns": returns,
        "no_returns_beyond_range": beyond,
        "no_returns_through_glass": glass,
        "no_return_fraction": if beams > 0 { (beyond + glass) as f64 / beams as f64 } else { 0.0 },
        "no_return_code_m": config.laser.no_return_code_m,
        "range_m": { "min": rmin, "mean": rsum / returns.max(1) as f64, "max": rmax },
        "returns_per_surface_class": labels,
        "intensity": if icount > 0 {
            serde_json::json!({ "min": imin, "mean": isum / icount as f64, "max": imax })
        } else {
            serde_json::Value::Null
        },
        "odometry_drift": {
            "final_position_error_m": final_err,
            "final_heading_error_rad": final_heading,
            "max_position_error_m": max_err,
            "per_metre": if length > 0.0 { final_err / length } else { 0.0 },
        },
    })
}
