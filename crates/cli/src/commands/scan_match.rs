//! `raypath scan-match`: Hector-style multi-resolution scan matching (Khan 2017 ch. 3) of the
//! front-laser scans of a CARMEN log, with the occupancy, reflectivity or combined residual.
//!
//! Outputs: `--out FILE` the trajectory in TUM format (`t x y z qx qy qz qw`, t = each scan's
//! IPC timestamp, the first timestamp of its CARMEN line; poses of the sensor in the map
//! frame, which starts at the first scan); `--map PREFIX` the finest occupancy level as
//! `PREFIX.pgm` + `PREFIX.yaml` (ROS map_server) and, when the map has reflectivity,
//! `PREFIX-reflectivity.png`; `--ground-truth LOG` scores the trajectory against a
//! corrected log (scans paired by identical readings): relative-motion error over consecutive
//! reference scans (Kümmerle et al. 2009) and the error after rigid alignment;
//! `--corrected-log FILE` a copy of the log whose matched laser messages carry the estimated
//! poses (messages after `--scans` keep theirs).
//!
//! `--json` prints `{"scans", "time_s", "scans_per_s", "mode", "map_updates", "beams",
//! "errors"}` (`errors` only with `--ground-truth`: `pairs`, `relative`, `aligned`).

use std::path::PathBuf;
use std::time::Instant;

use raypath_geometry::Pose2;
use raypath_io::carmen::{CarmenReader, CarmenWriter, Record};
use raypath_reflectivity::benchmark::{
    LogScan, aligned_errors, consecutive_relations, pair_by_ranges, read_laser_log,
    relative_errors, run_matcher,
};
use raypath_reflectivity::export::{tum_lines, write_occupancy_map, write_reflectivity_png};
use raypath_reflectivity::{
    IntensityCorrection, MapConfig, MatcherConfig, PointFilter, ResidualMode,
};
use serde_json::json;

use super::Failure;

/// Arguments of `raypath scan-match`.
#[derive(clap::Args)]
pub struct Args {
    /// A CARMEN log (plain, .gz or .bz2); FLASER scans, or ROBOTLASER1 with remissions.
    pub log: PathBuf,
    /// Residual: occupancy (plain Hector), reflectivity (Khan) or combined.
    #[arg(long, default_value = "occupancy", value_name = "MODE")]
    pub mode: String,
    /// Intensity model JSON from `raypath calibrate-intensity` (needed by reflectivity and
    /// combined).
    #[arg(long, value_name = "FILE")]
    pub lut: Option<PathBuf>,
    /// Write the trajectory in TUM format.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Write the map as PREFIX.pgm + PREFIX.yaml (+ PREFIX-reflectivity.png).
    #[arg(long, value_name = "PREFIX")]
    pub map: Option<PathBuf>,
    /// A corrected log of the same run: report the errors against its poses.
    #[arg(long, value_name = "LOG")]
    pub ground_truth: Option<PathBuf>,
    /// Use the logged odometry as the initial guess of each match.
    #[arg(long)]
    pub odometry: bool,
    /// Also use odometry as a prior with these σ: x m, y m, θ rad (implies --odometry).
    #[arg(long, value_delimiter = ',', num_args = 3, value_name = "SX,SY,STH")]
    pub odometry_prior: Option<Vec<f64>>,
    /// Finest cell size, metres.
    #[arg(long, default_value_t = 0.05, value_name = "M")]
    pub resolution: f64,
    /// Number of map levels.
    #[arg(long, default_value_t = 3, value_name = "N")]
    pub levels: usize,
    /// Side of the mapped square, metres (centred on the first scan).
    #[arg(long, default_value_t = 160.0, value_name = "M")]
    pub size: f64,
    /// Readings at or above this range are not used, metres.
    #[arg(long, default_value_t = 30.0, value_name = "M")]
    pub max_range: f64,
    /// Write a copy of the log whose laser poses (and robot poses) are the estimates.
    #[arg(long, value_name = "FILE")]
    pub corrected_log: Option<PathBuf>,
    /// Process only the first N scans.
    #[arg(long, value_name = "N")]
    pub scans: Option<usize>,
    /// Print one JSON document on standard output.
    #[arg(long)]
    pub json: bool,
}

fn failure(message: impl std::fmt::Display, json: bool) -> Failure {
    Failure {
        message: message.to_string(),
        bad_input: false,
        json,
    }
}

fn config(args: &Args) -> Result<MatcherConfig, Failure> {
    let Some(mode) = ResidualMode::parse(&args.mode) else {
        return Err(Failure::input(
            format!(
                "--mode: expected occupancy, reflectivity or combined, got {:?}",
                args.mode
            ),
            args.json,
        ));
    };
    let odometry_sigma = match args.odometry_prior.as_deref() {
        None => None,
        Some(&[a, b, c]) => Some([a, b, c]),
        Some(_) => {
            return Err(Failure::input(
                "--odometry-prior: expected three values",
                args.json,
            ));
        }
    };
    let config = MatcherConfig {
        mode,
        odometry_sigma,
        map: MapConfig {
            finest_resolution_m: args.resolution,
            levels: args.levels,
            size_m: args.size,
            ..MapConfig::default()
        },
        ..MatcherConfig::default()
    };
    config
        .validate()
        .map_err(|e| Failure::input(e, args.json))?;
    Ok(config)
}

fn read_lut(args: &Args, mode: ResidualMode) -> Result<Option<IntensityCorrection>, Failure> {
    let Some(path) = &args.lut else {
        if mode != ResidualMode::Occupancy {
            return Err(Failure::input(
                format!(
                    "--mode {}: needs --lut (from raypath calibrate-intensity)",
                    mode.name()
                ),
                args.json,
            ));
        }
        return Ok(None);
    };
    let text = std::fs::read_to_string(path)
        .map_err(|e| Failure::input(format!("{}: {e}", path.display()), args.json))?;
    let model: IntensityCorrection = serde_json::from_str(&text)
        .map_err(|e| Failure::input(format!("{}:{}: {e}", path.display(), e.line()), args.json))?;
    if let IntensityCorrection::Lut(lut) = &model {
        lut.validate()
            .map_err(|e| Failure::input(format!("{}: {e}", path.display()), args.json))?;
    }
    Ok(Some(model))
}

/// Copies the log with the estimated poses in the laser messages that were matched (the
/// first `poses.len()` messages of the matched kind); other lines are re-written as read.
fn write_corrected_log(
    args: &Args,
    path: &std::path::Path,
    scans: &[LogScan],
    poses: &[Pose2],
) -> Result<(), Failure> {
    let kind = scans.first().map(|s| s.kind);
    let reader = CarmenReader::open(&args.log).map_err(|e| Failure::input(e, args.json))?;
    let mut writer = CarmenWriter::create(path).map_err(|e| failure(e, args.json))?;
    let mut k = 0;
    for record in reader {
        let mut record = record.map_err(|e| Failure::input(e, args.json))?;
        if let Record::Laser(m) = &mut record
            && Some(m.kind) == kind
        {
            if let Some(pose) = poses.get(k) {
                // The estimate is the laser's pose; keep the logged laser-on-robot offset.
                let robot_from_laser = m.world_from_robot.inverse() * m.world_from_laser;
                m.world_from_laser = *pose;
                m.world_from_robot = *pose * robot_from_laser.inverse();
            }
            k += 1;
        }
        writer.record(&record).map_err(|e| failure(e, args.json))?;
    }
    writer.finish().map_err(|e| failure(e, args.json))?;
    Ok(())
}

/// Runs the subcommand.
pub fn run(args: &Args) -> Result<(), Failure> {
    let config = config(args)?;
    if !(args.max_range.is_finite() && args.max_range > 0.0) {
        return Err(Failure::input("--max-range: must be positive", args.json));
    }
    let lut = read_lut(args, config.mode)?;
    let mut scans = read_laser_log(&args.log).map_err(|e| Failure::input(e, args.json))?;
    if let Some(n) = args.scans {
        scans.truncate(n.max(1));
    }
    if config.mode != ResidualMode::Occupancy && !scans.iter().any(|s| s.scan.intensities.is_some())
    {
        return Err(Failure::input(
            format!(
                "{}: --mode {} needs remissions (ROBOTLASER1 lines with intensities)",
                args.log.display(),
                config.mode.name()
            ),
            args.json,
        ));
    }
    let filter = PointFilter {
        max_range_m: args.max_range,
        ..PointFilter::default()
    };
    let use_odometry = args.odometry || args.odometry_prior.is_some();
    let start = Instant::now();
    let (matcher, results) = run_matcher(&scans, config, &filter, lut.as_ref(), use_odometry)
        .map_err(|e| failure(e, args.json))?;
    let time_s = start.elapsed().as_secs_f64();
    let poses: Vec<Pose2> = results.iter().map(|r| r.world_from_sensor).collect();
    if let Some(out) = &args.out {
        let text = tum_lines(
            scans
                .iter()
                .zip(&poses)
                .map(|(s, p)| (s.ipc_timestamp_secs, *p)),
        );
        std::fs::write(out, text)
            .map_err(|e| failure(format!("{}: {e}", out.display()), args.json))?;
    }
    if let Some(path) = &args.corrected_log {
        write_corrected_log(args, path, &scans, &poses)?;
    }
    let mut reflectivity_png = None;
    if let Some(prefix) = &args.map {
        if let Some(level) = matcher.map().levels().first() {
            write_occupancy_map(level, prefix).map_err(|e| failure(e, args.json))?;
            let png = PathBuf::from(format!("{}-reflectivity.png", prefix.display()));
            if write_reflectivity_png(level, &png).map_err(|e| failure(e, args.json))? {
                reflectivity_png = Some(png);
            }
        }
    }
    let errors = match &args.ground_truth {
        None => None,
        Some(path) => {
            let reference = read_laser_log(path).map_err(|e| Failure::input(e, args.json))?;
            let pairs = pair_by_ranges(&scans, &reference);
            if pairs.len() < 2 {
                return Err(Failure::input(
                    format!(
                        "{}: fewer than two scans pair with {} (identical readings)",
                        path.display(),
                        args.log.display()
                    ),
                    args.json,
                ));
            }
            let truth: Vec<Pose2> = pairs
                .iter()
                .filter_map(|&(_, j)| reference.get(j).map(|s| s.world_from_laser))
                .collect();
            let est: Vec<Pose2> = pairs
                .iter()
                .filter_map(|&(i, _)| poses.get(i).copied())
                .collect();
            let relative = relative_errors(&truth, &est, &consecutive_relations(truth.len()));
            let aligned = aligned_errors(&truth, &est);
            Some(json!({ "pairs": pairs.len(), "relative": relative, "aligned": aligned }))
        }
    };
    let scans_per_s = scans.len() as f64 / time_s.max(1e-9);
    let beams = scans.first().map_or(0, |s| s.scan.ranges.len());
    let updates = matcher.map().updates();
    if args.json {
        let mut doc = json!({
            "log": args.log.display().to_string(),
            "mode": config.mode.name(),
            "scans": scans.len(),
            "beams": beams,
            "time_s": time_s,
            "scans_per_s": scans_per_s,
            "map_updates": updates,
        });
        if let (Some(e), Some(obj)) = (errors, doc.as_object_mut()) {
            obj.insert("errors".into(), e);
        }
        println!("{doc}");
    } else {
        println!(
            "{} scans ({} beams), mode {}: {:.2} s, {:.0} scans/s, {} map updates",
            scans.len(),
            beams,
            config.mode.name(),
            time_s,
            scans_per_s,
            updates
        );
        if let Some(e) = errors {
            let r = &e["relative"];
            let a = &e["aligned"];
            println!(
                "relative error over {} pairs: {:.3} ± {:.3} m, {:.2} ± {:.2}°; aligned RMSE {:.3} m",
                e["pairs"],
                r["translation_m"]["mean"].as_f64().unwrap_or(f64::NAN),
                r["translation_m"]["std"].as_f64().unwrap_or(f64::NAN),
                r["rotation_rad"]["mean"]
                    .as_f64()
                    .unwrap_or(f64::NAN)
                    .to_degrees(),
                r["rotation_rad"]["std"]
                    .as_f64()
                    .unwrap_or(f64::NAN)
                    .to_degrees(),
                a["position_m"]["rms"].as_f64().unwrap_or(f64::NAN),
            );
        }
        if let Some(png) = reflectivity_png {
            println!("reflectivity map: {}", png.display());
        }
    }
    Ok(())
}
