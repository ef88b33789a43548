//! `raypath scan-match`: Hector-style multi-resolution scan matching (Khan 2017 ch. 3) of the
//! scans of a CARMEN log (the laser `--laser`, front by default) or of a rosbag2 bag's
//! LaserScan topic, with the occupancy, reflectivity or combined residual. The scans and
//! their logged poses (the odometry of `--odometry`) are read through `raypath_io::sequence`.
//!
//! Outputs: `--out FILE` the trajectory in TUM format (`t x y z qx qy qz qw`, t = each scan's
//! IPC timestamp, the first timestamp of its CARMEN line, or a bag message's header stamp;
//! poses of the sensor in the map frame, which starts at the first scan); `--map PREFIX` the
//! finest occupancy level as `PREFIX.pgm` + `PREFIX.yaml` (ROS map_server) and, when the map
//! has reflectivity, `PREFIX-reflectivity.png`; `--ground-truth LOG` scores the trajectory
//! against a corrected log or a bag with reference poses (scans paired by identical readings
//! with `raypath_io::sequence::pair_by_ranges`): relative-motion error over consecutive
//! reference scans (Kümmerle et al. 2009) and the error after rigid alignment;
//! `--corrected-log FILE` (CARMEN input) a copy of the log whose matched laser messages carry
//! the estimated poses (messages after `--scans` keep theirs).
//!
//! `--json` prints `{"scans", "time_s", "scans_per_s", "mode", "map_updates", "beams",
//! "errors"}` (`errors` only with `--ground-truth`: `pairs`, `relative`, `aligned`).
//!
//! `--record OUT.mcap` writes a Foxglove recording (see `record` and `scan_match::record`):
//! every scan at its estimated pose (`/tf`, `/scan`), the estimated `/trajectory`, and the
//! finest map level as the Grids `/map` (occupancy probability) and `/reflectivity`.

mod record;

use std::collections::HashMap;
use std::path::PathBuf;
use std::time::Instant;

use raypath_geometry::{Pose2, Scan2};
use raypath_io::carmen::{CarmenReader, CarmenWriter, Record};
use raypath_io::sequence::{Origin, PlanarFrame, pair_by_ranges};
use raypath_reflectivity::benchmark::{
    aligned_errors, consecutive_relations, relative_errors, run_matcher,
};
use raypath_reflectivity::export::{write_occupancy_map, write_reflectivity_png};
use raypath_reflectivity::{
    IntensityCorrection, MapConfig, MatcherConfig, PointFilter, ResidualMode,
};
use serde_json::json;

use super::Failure;
use super::record::{RecordArgs, Recording};
use super::source_args::{SourceArgs, reference_track};

/// `--mode`: the residual of the matcher.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ModeArg {
    /// Occupancy only: plain Hector.
    Occupancy,
    /// Relative reflectivity only: Khan's intensity-based Hector (needs --lut).
    Reflectivity,
    /// Both residuals (needs --lut).
    Combined,
}

impl From<ModeArg> for ResidualMode {
    fn from(mode: ModeArg) -> Self {
        match mode {
            ModeArg::Occupancy => ResidualMode::Occupancy,
            ModeArg::Reflectivity => ResidualMode::Reflectivity,
            ModeArg::Combined => ResidualMode::Combined,
        }
    }
}

/// Arguments of `raypath scan-match`.
#[derive(clap::Args)]
pub struct Args {
    /// A CARMEN log (plain, .gz or .bz2): FLASER scans, or ROBOTLASER1 with remissions; or a
    /// rosbag2 bag (directory with metadata.yaml, or .mcap file) with LaserScan.
    pub log: PathBuf,
    /// Residual.
    #[arg(long, value_enum, default_value_t = ModeArg::Occupancy, value_name = "MODE")]
    pub mode: ModeArg,
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
    /// A corrected log of the same run, or a bag with reference poses: report the errors
    /// against its poses.
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
    /// How to read the log and the ground truth.
    #[command(flatten)]
    pub source: SourceArgs,
    /// A Foxglove recording of the run.
    #[command(flatten)]
    pub record: RecordArgs,
}

fn config(args: &Args) -> Result<MatcherConfig, Failure> {
    let mode = ResidualMode::from(args.mode);
    let odometry_sigma = match args.odometry_prior.as_deref() {
        None => None,
        Some(&[a, b, c]) => Some([a, b, c]),
        Some(_) => {
            return Err(Failure::input("--odometry-prior: expected three values"));
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
    config.validate().map_err(Failure::input)?;
    Ok(config)
}

/// The intensity model of `--lut` (JSON from `raypath calibrate-intensity`, validated); an
/// error when the residual `mode` needs one and none is given. Shared with `raypath slam`.
pub(crate) fn read_correction(
    lut: Option<&std::path::Path>,
    mode: ResidualMode,
) -> Result<Option<IntensityCorrection>, Failure> {
    let Some(path) = lut else {
        if mode != ResidualMode::Occupancy {
            return Err(Failure::input(format!(
                "--mode {}: needs --lut (from raypath calibrate-intensity)",
                mode.name()
            )));
        }
        return Ok(None);
    };
    let text = std::fs::read_to_string(path)
        .map_err(|e| Failure::input(format!("{}: {e}", path.display())))?;
    let model: IntensityCorrection = serde_json::from_str(&text)
        .map_err(|e| Failure::input(format!("{}:{}: {e}", path.display(), e.line())))?;
    if let IntensityCorrection::Lut(lut) = &model {
        lut.validate()
            .map_err(|e| Failure::input(format!("{}: {e}", path.display())))?;
    }
    Ok(Some(model))
}

/// The scans of the log for the matcher (the logged `world_from_laser` is the odometry).
fn read_scans(args: &Args) -> Result<Vec<PlanarFrame>, Failure> {
    let frames = args.source.read_frames(&args.log).map_err(Failure::input)?;
    if frames.is_empty() {
        return Err(Failure::input(format!(
            "{}: no laser scans ({})",
            args.log.display(),
            args.source.laser_lines()
        )));
    }
    Ok(frames)
}

/// The lines of a CARMEN log's laser messages the scans came from; `None` for other sources.
fn carmen_lines(scans: &[PlanarFrame]) -> Option<Vec<u64>> {
    scans
        .iter()
        .map(|f| match f.origin {
            Origin::Line(line) => Some(line),
            Origin::LogTimeNs(_) => None,
        })
        .collect()
}

/// The TUM times of the scans: a CARMEN log's IPC timestamps (the first timestamp of each
/// line; the sources keep the logger timestamp), else the frames' stamps.
fn ipc_stamps(args: &Args, scans: &[PlanarFrame]) -> Result<Vec<f64>, Failure> {
    let Some(lines) = carmen_lines(scans) else {
        return Ok(scans.iter().map(|s| s.stamp_secs).collect());
    };
    let reader = CarmenReader::open(&args.log).map_err(Failure::input)?;
    let mut ipc: HashMap<u64, f64> = lines.iter().map(|&line| (line, f64::NAN)).collect();
    for record in reader {
        if let Record::Laser(m) = record.map_err(Failure::input)?
            && let Some(t) = ipc.get_mut(&m.line)
        {
            *t = m.ipc_timestamp_secs;
        }
    }
    Ok(lines
        .iter()
        .map(|line| ipc.get(line).copied().unwrap_or(f64::NAN))
        .collect())
}

fn not_carmen(args: &Args) -> Failure {
    Failure::input(format!(
        "--corrected-log: {} is not a CARMEN log; a corrected copy is written for CARMEN \
             logs only",
        args.log.display()
    ))
}

/// Copies the log with the estimated poses in the laser messages that were matched (by line);
/// other lines are re-written as read.
fn write_corrected_log(
    args: &Args,
    path: &std::path::Path,
    scans: &[PlanarFrame],
    poses: &[Pose2],
) -> Result<(), Failure> {
    let Some(lines) = carmen_lines(scans) else {
        return Err(not_carmen(args));
    };
    let estimate: HashMap<u64, Pose2> = lines.into_iter().zip(poses.iter().copied()).collect();
    let reader = CarmenReader::open(&args.log).map_err(Failure::input)?;
    let mut writer = CarmenWriter::create(path).map_err(Failure::internal)?;
    for record in reader {
        let mut record = record.map_err(Failure::input)?;
        if let Record::Laser(m) = &mut record
            && let Some(pose) = estimate.get(&m.line)
        {
            // The estimate is the laser's pose; keep the logged laser-on-robot offset.
            let robot_from_laser = m.world_from_robot.inverse() * m.world_from_laser;
            m.world_from_laser = *pose;
            m.world_from_robot = *pose * robot_from_laser.inverse();
        }
        writer.record(&record).map_err(Failure::internal)?;
    }
    writer.finish().map_err(Failure::internal)?;
    Ok(())
}

/// The scans of the ground truth with their reference poses.
fn read_reference(args: &Args, path: &std::path::Path) -> Result<Vec<(Scan2, Pose2)>, Failure> {
    let frames = args.source.read_frames(path).map_err(Failure::input)?;
    let track = reference_track(&frames);
    Ok(frames
        .into_iter()
        .zip(track)
        .filter_map(|(f, pose)| Some((f.scan, pose?)))
        .collect())
}

/// Runs the subcommand.
pub fn run(args: &Args) -> Result<(), Failure> {
    let config = config(args)?;
    if !(args.max_range.is_finite() && args.max_range > 0.0) {
        return Err(Failure::input("--max-range: must be positive"));
    }
    let lut = read_correction(args.lut.as_deref(), config.mode)?;
    let mut recording = Recording::open(&args.record)?;
    let mut scans = read_scans(args)?;
    if args.corrected_log.is_some() && carmen_lines(&scans).is_none() {
        return Err(not_carmen(args));
    }
    if let Some(n) = args.scans {
        scans.truncate(n.max(1));
    }
    if config.mode != ResidualMode::Occupancy && !scans.iter().any(|s| s.scan.intensities.is_some())
    {
        return Err(Failure::input(format!(
            "{}: --mode {} needs remissions (ROBOTLASER1 lines with intensities)",
            args.log.display(),
            config.mode.name()
        )));
    }
    let filter = PointFilter {
        max_range_m: args.max_range,
        ..PointFilter::default()
    };
    let use_odometry = args.odometry || args.odometry_prior.is_some();
    let start = Instant::now();
    let spinner = super::console::spinner("scan matching");
    let (matcher, results) = run_matcher(&scans, config, &filter, lut.as_ref(), use_odometry)
        .map_err(Failure::internal)?;
    spinner.finish_and_clear();
    super::console::stage("scan matching", start);
    let time_s = start.elapsed().as_secs_f64();
    let poses: Vec<Pose2> = results.iter().map(|r| r.world_from_sensor).collect();
    if let Some(out) = &args.out {
        let stamps = ipc_stamps(args, &scans)?;
        raypath_io::tum::write_planar_tum(out, None, stamps.into_iter().zip(poses.iter().copied()))
            .map_err(Failure::internal)?;
    }
    if let Some(path) = &args.corrected_log {
        write_corrected_log(args, path, &scans, &poses)?;
    }
    let mut reflectivity_png = None;
    if let Some(prefix) = &args.map {
        if let Some(level) = matcher.map().levels().first() {
            write_occupancy_map(level, prefix).map_err(Failure::internal)?;
            let png = PathBuf::from(format!("{}-reflectivity.png", prefix.display()));
            if write_reflectivity_png(level, &png).map_err(Failure::internal)? {
                reflectivity_png = Some(png);
            }
        }
    }
    if let Some(recording) = &mut recording {
        record::record(recording, &scans, &poses, matcher.map().levels().first())?;
    }
    let errors = match &args.ground_truth {
        None => None,
        Some(path) => {
            let reference = read_reference(args, path)?;
            let pairs = pair_by_ranges(
                scans.iter().map(|s| &s.scan),
                reference.iter().map(|(scan, _)| scan),
            );
            if pairs.len() < 2 {
                return Err(Failure::input(format!(
                    "{}: fewer than two scans pair with {} (identical readings)",
                    path.display(),
                    args.log.display()
                )));
            }
            let truth: Vec<Pose2> = pairs
                .iter()
                .filter_map(|&(_, j)| reference.get(j).map(|(_, pose)| *pose))
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
    if super::console::json() {
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
        super::record::finish(recording, Some(&mut doc))?;
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
        super::record::finish(recording, None)?;
    }
    Ok(())
}
