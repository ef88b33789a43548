//! `raypath poles extract|map|localize`: pole extraction, pole maps and pole-based
//! localization (Schaefer 2020, ch. 12) on a sequence in KITTI or NCLT layout, or a rosbag2
//! bag's PointCloud2 topic (its directory with `metadata.yaml`, or its `.mcap` file; topics by
//! `--cloud-topic`, `--odom-topic`, `--reference-topic`, `--frame`), read through
//! `raypath_poles::Drive` on `raypath_io::sequence::SweepSequence` (a bag follows KITTI's
//! conventions: the kitti preset, odometry noise as for KITTI when it has no odometry).
//!
//! * `extract <sequence>`: the poles of one local map built from the registered scans of the
//!   first trajectory segment from `--from` (ground-truth poses; odometry when the sequence
//!   has none), in the world frame.
//! * `map <sequence> --out map.csv`: local maps along the whole drive (ground-truth poses),
//!   merged into a reference map (`x,y,width,height,score`).
//! * `localize --map map.csv <sequence>`: particle-filter runs with online poles from local
//!   maps along the odometry (KITTI: ground-truth increments corrupted by 2 % noise); the
//!   error summary every 1 m against the ground truth. Particles start around the ground truth
//!   of the first scan or around `--start x,y,theta`; without ground truth only the final
//!   estimates are printed (`"summary": null`).
//!
//! `--sweep-timing auto|origin|kitti` says where rays start when local maps are traced:
//! real KITTI scans are de-skewed sweeps, so by default (`auto`) every ray of a KITTI
//! sequence starts where the sensor was when it fired it; scans simulated by
//! `raypath simulate` and bag sweeps start at the scan origin.
//!
//! `--json` prints one document (each also with `"sweep_timing"`): `extract`/`map` →
//! `{"sequence", "preset", "scans",
//! "local_maps", "poles": [{x, y, width, height, score}], "points_per_sec"}`; `localize` →
//! `{"sequence", "preset", "runs", "summary": {mean_pos_m, rmse_pos_m, mean_lat_m,
//! mean_lon_m, mean_ang_deg, rmse_ang_deg, diverged_runs}, "per_run": […]}`.
//!
//! `--record OUT.mcap` writes a Foxglove recording (see `record`): `extract`/`map` — each scan
//! used at its mapping pose and time (`/tf` `map → base_link`, its points on `/points`, thinned
//! by `record::sweep_points`), the mapping `/trajectory` and the poles as cylinders on
//! `/poles`; `localize` — the map's poles on `/poles`, each scan at its estimate in the first
//! run (`/tf`, `/points`), that run's `/trajectory` and the ground truth as `/ground_truth`.

mod record;

use std::path::PathBuf;

use raypath_geometry::{Pose2, Pose3};
use raypath_io::poles_csv::{PoleRecord, read_pole_csv, write_pole_csv};
use raypath_localizer::PoseTrack;
use raypath_localizer::eval::{EvaluationConfig, evaluate_trajectory};
use raypath_poles::report::{
    FinalPose, LocalizationSummary, PoleLocalizeReport, PoleMapReport, PoleReport, RunReport,
};
use raypath_poles::{
    Drive, DriveFormat, OdometryNoise, Pole, Preset, RunResult, filter_run, local_maps,
    online_poles, reference_map,
};

use super::Failure;
use super::record::{RecordArgs, Recording};
use super::source_args::SourceArgs;

/// Arguments of `raypath poles`.
#[derive(clap::Args)]
pub struct Args {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(clap::Subcommand)]
pub enum Command {
    /// Poles of one local map (the first trajectory segment from `--from`).
    Extract(ExtractArgs),
    /// A reference pole map from local maps along the whole drive.
    Map(MapArgs),
    /// Particle-filter localization on a pole map, evaluated against the ground truth.
    Localize(LocalizeArgs),
}

/// Options shared by the subcommands.
#[derive(clap::Args)]
pub struct Common {
    /// A KITTI sequence directory, an NCLT session directory or a rosbag2 bag (directory with
    /// metadata.yaml, or .mcap file) with PointCloud2.
    pub sequence: PathBuf,
    /// Parameter preset (default: from the layout).
    #[arg(long, value_enum, value_name = "NAME")]
    pub preset: Option<PresetArg>,
    /// Use at most this many scans (from `--from`).
    #[arg(long, value_name = "N")]
    pub max_scans: Option<usize>,
    /// First scan used.
    #[arg(long, default_value_t = 0, value_name = "I")]
    pub from: usize,
    /// Where each ray of a scan starts: `kitti` — where the sensor was when it fired the
    /// ray (KITTI's scans are de-skewed sweeps of a moving, clockwise-turning sensor, cut
    /// behind it; the motion is taken from the neighbouring poses); `origin` — the scan's
    /// origin (scans measured from one pose). `auto`: `kitti` for a KITTI sequence, except
    /// one written by `raypath simulate` (a `set.json` beside `sequences/`), whose scans are
    /// measured from one pose; `origin` otherwise.
    #[arg(long, value_enum, default_value_t = SweepTimingArg::Auto)]
    pub sweep_timing: SweepTimingArg,
    /// How to read a bag.
    #[command(flatten)]
    pub source: SourceArgs,
    /// A Foxglove recording of the run.
    #[command(flatten)]
    pub record: RecordArgs,
}

/// Values of `--sweep-timing`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SweepTimingArg {
    /// `kitti` for real KITTI sequences, `origin` otherwise.
    Auto,
    /// Rays from the scan's origin.
    Origin,
    /// Rays from the sensor's position at each firing, KITTI's sweep timing.
    Kitti,
}

/// Values of `--preset`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PresetArg {
    /// The NCLT settings (Schaefer 2020, §12.5.1): 0.2 m voxels.
    Nclt,
    /// The KITTI settings (Schaefer 2020, §12.5.2): 0.1 m voxels.
    Kitti,
}

/// Arguments of `raypath poles extract`.
#[derive(clap::Args)]
pub struct ExtractArgs {
    /// Common options.
    #[command(flatten)]
    pub common: Common,
    /// Write the poles as CSV.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

/// Arguments of `raypath poles map`.
#[derive(clap::Args)]
pub struct MapArgs {
    /// Common options.
    #[command(flatten)]
    pub common: Common,
    /// The pole map CSV to write.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

/// Arguments of `raypath poles localize`.
#[derive(clap::Args)]
pub struct LocalizeArgs {
    /// Common options.
    #[command(flatten)]
    pub common: Common,
    /// The reference pole map (CSV with x, y columns).
    #[arg(long, value_name = "FILE")]
    pub map: PathBuf,
    /// Number of runs (different seeds).
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub runs: usize,
    /// Particles (default: the preset's).
    #[arg(long, value_name = "N")]
    pub particles: Option<usize>,
    /// Seed of the first run.
    #[arg(long, default_value_t = 1, value_name = "S")]
    pub seed: u64,
    /// Initial pose `x,y,theta` (metres, radians, world frame) around which the particles are
    /// drawn; default: the ground truth at the first scan.
    #[arg(
        long,
        value_delimiter = ',',
        num_args = 3,
        value_name = "X,Y,THETA",
        allow_hyphen_values = true
    )]
    pub start: Option<Vec<f64>>,
}

/// Runs the subcommand.
pub fn run(args: &Args) -> Result<(), Failure> {
    match &args.command {
        Command::Extract(a) => extract(a),
        Command::Map(a) => map(a),
        Command::Localize(a) => localize(a),
    }
}

fn open(common: &Common) -> Result<(Drive, Preset, std::ops::Range<usize>), Failure> {
    let sweeps = common
        .source
        .open_sweeps(&common.sequence)
        .map_err(Failure::input)?;
    let mut drive = Drive::new(sweeps).map_err(Failure::input)?;
    let kitti_timing = match common.sweep_timing {
        SweepTimingArg::Kitti => true,
        SweepTimingArg::Origin => false,
        SweepTimingArg::Auto => {
            drive.format() == DriveFormat::Kitti && !raypath_sim::in_generated_set(&common.sequence)
        }
    };
    drive.sweep_timing = kitti_timing.then(raypath_poles::SweepTiming::kitti);
    let preset = match common.preset {
        Some(PresetArg::Nclt) => Preset::nclt(),
        Some(PresetArg::Kitti) => Preset::kitti(),
        None => match drive.format() {
            DriveFormat::Kitti => Preset::kitti(),
            DriveFormat::Nclt => Preset::nclt(),
        },
    };
    if common.from >= drive.len() {
        return Err(Failure::input(format!(
            "{}: --from {} but the sequence has {} scan(s)",
            common.sequence.display(),
            common.from,
            drive.len()
        )));
    }
    let end = common
        .max_scans
        .map_or(drive.len(), |m| (common.from + m).min(drive.len()));
    Ok((drive, preset, common.from..end))
}

fn preset_name(common: &Common, drive: &Drive) -> &'static str {
    match (common.preset, drive.format()) {
        (Some(PresetArg::Nclt), _) | (None, DriveFormat::Nclt) => "nclt",
        _ => "kitti",
    }
}

fn timing_name(drive: &Drive) -> &'static str {
    if drive.sweep_timing.is_some() {
        "kitti"
    } else {
        "origin"
    }
}

fn pole_reports(poles: &[Pole]) -> Vec<PoleReport> {
    poles.iter().map(PoleReport::from).collect()
}

/// The rows of a pole-map CSV.
fn records(poles: &[Pole]) -> Vec<PoleRecord> {
    poles.iter().map(PoleRecord::from).collect()
}

fn print_poles(poles: &[Pole]) {
    println!(
        "{:>10} {:>10} {:>8} {:>8} {:>6}",
        "x", "y", "width", "height", "score"
    );
    for p in poles {
        println!(
            "{:>10.3} {:>10.3} {:>8.3} {:>8.2} {:>6.3}",
            p.x,
            p.y,
            p.width,
            p.height(),
            p.score
        );
    }
}

fn mapping_track(drive: &Drive) -> Vec<Pose3> {
    drive
        .sweeps
        .reference
        .clone()
        .unwrap_or_else(|| drive.odometry().to_vec())
}

fn extract(args: &ExtractArgs) -> Result<(), Failure> {
    let c = &args.common;
    let (drive, preset, range) = open(c)?;
    let mut recording = Recording::open(&c.record)?;
    let track = mapping_track(&drive);
    let (maps, totals) =
        local_maps(&drive, &track, range.clone(), &preset, |_, _| {}).map_err(Failure::input)?;
    let poles = maps.first().map(|m| m.poles.clone()).unwrap_or_default();
    let scans = maps.first().map_or(0, |m| m.scans.len());
    if let Some(out) = &args.out {
        write_pole_csv(out, &records(&poles)).map_err(Failure::input)?;
    }
    if let Some(recording) = &mut recording {
        let used = maps.first().map(|m| m.scans.clone()).unwrap_or_default();
        record::mapping(recording, &drive, &track, &used, &poles)?;
    }
    if super::console::json() {
        let mut doc = super::to_json(&PoleMapReport {
            sequence: c.sequence.display().to_string(),
            preset: preset_name(c, &drive),
            sweep_timing: timing_name(&drive),
            scans,
            local_maps: maps.len().min(1),
            poles: pole_reports(&poles),
            points_per_sec: totals.points_per_sec(),
            out: None,
        })?;
        super::record::finish(recording, Some(&mut doc))?;
        println!("{doc}");
    } else {
        println!(
            "{}: {} poles from {scans} scans ({:.2} M points/s)",
            c.sequence.display(),
            poles.len(),
            totals.points_per_sec() / 1e6
        );
        print_poles(&poles);
        super::record::finish(recording, None)?;
    }
    Ok(())
}

fn map(args: &MapArgs) -> Result<(), Failure> {
    let c = &args.common;
    let (drive, preset, range) = open(c)?;
    let mut recording = Recording::open(&c.record)?;
    let track = mapping_track(&drive);
    let scans = range.len();
    let (maps, totals) =
        local_maps(&drive, &track, range.clone(), &preset, |_, _| {}).map_err(Failure::input)?;
    let poles = reference_map(&maps, &preset);
    write_pole_csv(&args.out, &records(&poles)).map_err(Failure::input)?;
    if let Some(recording) = &mut recording {
        let used: Vec<usize> = range.collect();
        record::mapping(recording, &drive, &track, &used, &poles)?;
    }
    if super::console::json() {
        let mut doc = super::to_json(&PoleMapReport {
            sequence: c.sequence.display().to_string(),
            preset: preset_name(c, &drive),
            sweep_timing: timing_name(&drive),
            scans,
            local_maps: maps.len(),
            poles: pole_reports(&poles),
            points_per_sec: totals.points_per_sec(),
            out: Some(args.out.display().to_string()),
        })?;
        super::record::finish(recording, Some(&mut doc))?;
        println!("{doc}");
    } else {
        println!(
            "{}: {} map poles from {} local maps over {scans} scans ({:.2} M points/s) → {}",
            c.sequence.display(),
            poles.len(),
            maps.len(),
            totals.points_per_sec() / 1e6,
            args.out.display()
        );
        super::record::finish(recording, None)?;
    }
    Ok(())
}

fn localize(args: &LocalizeArgs) -> Result<(), Failure> {
    let c = &args.common;
    let json = super::console::json();
    if args.runs == 0 {
        return Err(Failure::input("--runs must be at least 1"));
    }
    let (drive, mut preset, range) = open(c)?;
    if let Some(n) = args.particles {
        preset.filter.particles = n;
    }
    preset.filter.validate().map_err(Failure::input)?;
    let mut recording = Recording::open(&c.record)?;
    let map: Vec<Pole> = read_pole_csv(&args.map)
        .map_err(Failure::input)?
        .into_iter()
        .map(Pole::from)
        .collect();
    if map.is_empty() {
        return Err(Failure::input(format!(
            "{}: the pole map is empty",
            args.map.display()
        )));
    }
    let start = match (&args.start, &drive.sweeps.reference) {
        (Some(v), _) => match v.as_slice() {
            [x, y, theta] if x.is_finite() && y.is_finite() && theta.is_finite() => {
                Pose2::new(*x, *y, *theta)
            }
            _ => {
                return Err(Failure::input(
                    "--start needs three finite numbers x,y,theta",
                ));
            }
        },
        (None, Some(gt)) => gt
            .get(range.start)
            .map(Pose3::to_planar)
            .unwrap_or_default(),
        (None, None) => {
            return Err(Failure::input(format!(
                "{}: no ground-truth poses; give the initial pose with --start x,y,theta",
                c.sequence.display()
            )));
        }
    };
    // Online poles: local maps along the odometry (KITTI: the poses, see the module docs).
    let registration = drive.odometry().to_vec();
    let (maps, _) = local_maps(&drive, &registration, range.clone(), &preset, |_, _| {})
        .map_err(Failure::input)?;
    let online = online_poles(&maps, &preset);
    let noise = match drive.format() {
        DriveFormat::Kitti => OdometryNoise::Relative { fraction: 0.02 },
        DriveFormat::Nclt => OdometryNoise::Recorded {
            std_scale: 2.0,
            fallback: 0.02,
        },
    };
    let mut runs: Vec<RunResult> = Vec::with_capacity(args.runs);
    let mut finals = Vec::with_capacity(args.runs);
    let bar = super::console::progress(args.runs, "localization runs");
    for r in 0..args.runs {
        bar.inc(1);
        let (track, updates, update_secs) = filter_run(
            &drive,
            range.clone(),
            &map,
            &online,
            &registration,
            &preset.filter,
            noise,
            start,
            args.seed + r as u64,
        )
        .map_err(Failure::input)?;
        if r == 0
            && let Some(recording) = &mut recording
        {
            record::localization(recording, &drive, range.clone(), &map, &track)?;
        }
        if let Some(last) = track.poses().last() {
            finals.push(FinalPose {
                x: last.x(),
                y: last.y(),
                theta: last.theta(),
            });
        }
        if let Some(gt) = &drive.sweeps.reference {
            let end = range.end.min(gt.len());
            let gt_track = PoseTrack::from_parts(
                drive.sweeps.stamps_secs[range.start..end].to_vec(),
                gt[range.start..end].iter().map(Pose3::to_planar).collect(),
            )
            .map_err(Failure::input)?;
            let evaluation = evaluate_trajectory(&gt_track, &track, &EvaluationConfig::default())
                .map_err(Failure::input)?;
            runs.push(RunResult {
                evaluation,
                updates,
                update_secs,
            });
        }
    }
    // The keys every answer carries; `summary` is null without ground truth.
    let mut answer = PoleLocalizeReport {
        sequence: c.sequence.display().to_string(),
        map: args.map.display().to_string(),
        preset: preset_name(c, &drive),
        sweep_timing: timing_name(&drive),
        runs: args.runs,
        summary: None,
        per_run: None,
        final_poses: None,
    };
    if runs.is_empty() {
        // No ground truth: report the final estimates only.
        if json {
            answer.final_poses = Some(finals);
            let mut doc = super::to_json(&answer)?;
            super::record::finish(recording, Some(&mut doc))?;
            println!("{doc}");
        } else {
            println!(
                "{}: {} run(s), no ground truth; final poses: {}",
                c.sequence.display(),
                args.runs,
                super::to_json(&finals)?
            );
            super::record::finish(recording, None)?;
        }
        return Ok(());
    }
    let summary = LocalizationSummary::of(&runs);
    if json {
        answer.summary = Some(summary);
        answer.per_run = Some(runs.iter().map(RunReport::from).collect());
        let mut doc = super::to_json(&answer)?;
        super::record::finish(recording, Some(&mut doc))?;
        println!("{doc}");
    } else {
        println!(
            "{}: {} run(s) on {} map poles",
            c.sequence.display(),
            args.runs,
            map.len()
        );
        println!(
            "{}",
            serde_json::to_string_pretty(&super::to_json(&summary)?).unwrap_or_default()
        );
        super::record::finish(recording, None)?;
    }
    Ok(())
}
