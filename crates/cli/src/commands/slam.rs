//! `raypath slam`: 2-D lidar SLAM (`raypath_slam`) on a raw CARMEN log or a rosbag2 bag's
//! LaserScan topic — Hector-style submap front-end, branch-and-bound loop closure, robust
//! sparse pose graph.
//!
//! ```text
//! raypath slam <log-or-bag> --out DIR [--resolution R] [--ground-truth CORRECTED]
//!              [--relations FILE.relations] [--json]
//!              [--model decay-rate|reflection|log-odds] [--no-loops] [--no-odometry]
//!              [--mode occupancy|reflectivity|combined --lut FILE] [--max-range M] [--scans N]
//!              [--laser …] [--scan-topic T] [--odom-topic T] [--record OUT.mcap]
//! ```
//!
//! Writes into `DIR`: `trajectory.txt` (TUM `t x y z qx qy qz qw`, the laser pose of every
//! scan in the optimised map frame, which starts at the first scan, at the scan's own sensor
//! time stamp: the CARMEN ipc time stamp — the one the SLAM benchmark's relation files use —
//! or a bag message's header stamp, so `evo` and relation files join on it), `corrected.log` (the
//! scans as a CARMEN corrected log with the optimised poses), the map rebuilt from the
//! optimised poses with the sensor model `--model` (`map.pgm` + `map.yaml`, `map.png`,
//! `map.rpmap`: as `raypath map` writes them) and `loop_closures.csv` (one accepted loop
//! closure per line).
//!
//! `--json` prints `{"scans", "nodes", "submaps", "loop_closures", "rejected_loop_closures",
//! "seconds", "scans_per_second", "timing", "outputs", "map"}` and, with `--ground-truth`,
//! `"summary": {"trans_error_m", "trans_error_std_m", "rot_error_deg", "rot_error_std_deg",
//! "relations"}` over the relations between consecutive referenced scans (Kümmerle et al.
//! 2009; scans paired with the corrected log by identical readings), `"random_pairs"` (the
//! same over 1000 seeded random pairs) and `"wrong_loop_closures"` (accepted loop closures
//! whose association error is above 0.3 m or 3°, `raypath_slam::benchmark::check_loops`, of
//! `"loop_closures_checked"`: the loop's scan against the node of the matched submap whose
//! scan overlaps it most at the reference poses; `"wrong_loop_closures_nearest_node"` counts
//! the same against the node nearest to where the loop placed the scan;
//! `"wrong_loop_closures_reference_disputed"` counts those wrong ones where the corrected log
//! disagrees with its own scans, `LoopCheck::reference_disputed`).
//! `"scan_refined": {"summary", "dropped", "reference_moved_m"}` scores the consecutive
//! relations refined by aligning their two scans and kept where that alignment is unique and
//! well constrained (`raypath_slam::benchmark::refine_relations`; `dropped` counts the others
//! by reason, `reference_moved_m` is the mean correction of the corrected log's relations).
//! With `--relations` (the SLAM benchmark's own relation file of the log, e.g.
//! `intel.relations`, whose scans are named by the CARMEN ipc time stamps), `"relations_file":
//! {"path", "summary", "unmatched"}` scores the trajectory by the benchmark's protocol: the
//! figure the published results (Cartographer, graph mapping, GMapping) are given in.
//!
//! `--record OUT.mcap`: every scan at its optimised pose (`/tf`, `/scan`), the `/trajectory`,
//! the rebuilt map as `/map` and the loop closures as lines (`/loops`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use nalgebra::Point3;
use raypath_io::foxglove::{frame, topic};
use raypath_io::relations::read_relations;
use raypath_io::sequence::{PlanarFrame, pair_reference};
use raypath_reflectivity::ResidualMode;
use raypath_sensor_models::export::{MapFile, MapReport, StoredStats, write_map_files};
use raypath_slam::benchmark::{
    ErrorSummary, ReferenceScore, RelationFileScore, match_relation_file, score_reference,
};
use raypath_slam::{MapSettings, Slam, SlamConfig, SlamOutput, SlamReport};

use super::Failure;
use super::map::Model;
use super::record::{RecordArgs, Recording, loop_lines};
use super::source_args::SourceArgs;

/// Arguments of `raypath slam`.
#[derive(clap::Args)]
pub struct Args {
    /// A raw CARMEN log with odometry (plain, .gz or .bz2) or a rosbag2 bag (directory with
    /// metadata.yaml, or .mcap file) with a LaserScan topic (and odometry or /tf).
    pub log: PathBuf,
    /// Output directory (created): trajectory.txt, corrected.log, map.*, loop_closures.csv.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Finest cell of the submaps and cell of the rebuilt map, metres.
    #[arg(long, default_value_t = 0.05, value_name = "M")]
    pub resolution: f64,
    /// A corrected log (or a bag with reference poses) of the same run: report the relation
    /// errors of Kümmerle et al. (2009) against it.
    #[arg(long, value_name = "LOG")]
    pub ground_truth: Option<PathBuf>,
    /// The SLAM benchmark's relation file of this log (`t1 t2 x y z roll pitch yaw`, scans
    /// named by their CARMEN ipc time stamps): report the relation errors over it.
    #[arg(long, value_name = "FILE")]
    pub relations: Option<PathBuf>,
    /// The sensor model of the rebuilt map.
    #[arg(long, value_enum, default_value = "reflection")]
    pub model: Model,
    /// Residual of the matcher: occupancy (Hector), reflectivity (Khan) or combined.
    #[arg(long, value_enum, default_value = "occupancy")]
    pub mode: ModeArg,
    /// Intensity model JSON from `raypath calibrate-intensity` (reflectivity and combined).
    #[arg(long, value_name = "FILE")]
    pub lut: Option<PathBuf>,
    /// No loop closure: front-end and sequential pose graph only (an ablation).
    #[arg(long)]
    pub no_loops: bool,
    /// Do not use the logged odometry as the initial guess.
    #[arg(long)]
    pub no_odometry: bool,
    /// Readings at or above this range are not used, metres.
    #[arg(long, default_value_t = 30.0, value_name = "M")]
    pub max_range: f64,
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

/// `--mode` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ModeArg {
    /// Occupancy only (plain Hector).
    Occupancy,
    /// Relative reflectivity only (Khan 2017, eq. 3.6).
    Reflectivity,
    /// Both residuals.
    Combined,
}

impl ModeArg {
    fn residual(self) -> ResidualMode {
        match self {
            ModeArg::Occupancy => ResidualMode::Occupancy,
            ModeArg::Reflectivity => ResidualMode::Reflectivity,
            ModeArg::Combined => ResidualMode::Combined,
        }
    }
}

fn config(args: &Args) -> Result<SlamConfig, Failure> {
    let mut config = SlamConfig::default();
    config.matcher.map.finest_resolution_m = args.resolution;
    config.matcher.mode = args.mode.residual();
    config.filter.max_range_m = args.max_range;
    config.use_odometry = !args.no_odometry;
    if args.no_loops {
        config.loops = None;
    }
    config.validate().map_err(Failure::input)?;
    Ok(config)
}

/// Runs the subcommand.
pub fn run(args: &Args) -> Result<(), Failure> {
    let config = config(args)?;
    let lut = super::scan_match::read_correction(args.lut.as_deref(), args.mode.residual())?;
    let mut recording = Recording::open(&args.record)?;
    let mut frames = args.source.read_frames(&args.log).map_err(Failure::input)?;
    if let Some(n) = args.scans {
        frames.truncate(n.max(1));
    }
    if frames.is_empty() {
        return Err(Failure::input(format!(
            "{}: no laser scans",
            args.log.display()
        )));
    }
    std::fs::create_dir_all(&args.out)
        .map_err(|e| Failure::internal(format!("{}: cannot create: {e}", args.out.display())))?;
    let started = Instant::now();
    let mut slam = Slam::new(config).map_err(Failure::input)?;
    if let Some(lut) = lut {
        slam = slam.with_correction(lut);
    }
    let bar = super::console::progress(frames.len(), "slam");
    for (k, frame) in frames.iter().enumerate() {
        slam.process(frame)
            .map_err(|e| Failure::input(format!("{}: scan {k}: {e}", args.log.display())))?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    let output = slam.finish().map_err(Failure::internal)?;
    super::console::stage("slam", started);
    let seconds = started.elapsed().as_secs_f64();
    let files = output
        .write_files(&args.out, &frames)
        .map_err(Failure::internal)?;
    let (map, map_file) = rebuild_map(args, &frames, &output)?;
    let mut report = SlamReport::new(&output, seconds, files, map);
    if let Some(path) = &args.ground_truth {
        report.reference = Some(evaluate(args, path, &mut frames, &output)?);
    }
    if let Some(path) = &args.relations {
        report.relations_file = Some(score_relation_file(args, path, &frames, &output)?);
    }
    if let Some(recording) = &mut recording {
        record(recording, &frames, &output, &map_file, args.model)?;
    }
    if super::console::json() {
        let mut doc = super::to_json(&report)?;
        super::record::finish(recording, Some(&mut doc))?;
        println!("{doc}");
    } else {
        print(&report);
        super::record::finish(recording, None)?;
    }
    Ok(())
}

/// The map of the scans at the optimised poses (`raypath_slam::rebuild_map`), written as
/// `map.*` like `raypath map` writes a map.
fn rebuild_map(
    args: &Args,
    frames: &[PlanarFrame],
    output: &SlamOutput,
) -> Result<(MapReport, MapFile), Failure> {
    let started = Instant::now();
    let settings = MapSettings {
        kind: args.model.kind(),
        resolution_m: args.resolution,
        max_range_m: args.max_range,
    };
    let spinner = super::console::spinner("mapping");
    let file = raypath_slam::rebuild_map(frames, &output.world_from_sensor, &settings)
        .map_err(Failure::input)?;
    spinner.finish_and_clear();
    super::console::stage("mapping", started);
    let mapping_seconds = started.elapsed().as_secs_f64();
    let files = write_map_files(&args.out.join("map"), &file, args.model.picture())
        .map_err(Failure::internal)?;
    let report = MapReport::new(
        &file,
        args.resolution,
        mapping_seconds,
        started.elapsed().as_secs_f64(),
        files,
    );
    Ok((report, file))
}

/// Relation errors against the ground truth and the check of every loop closure.
fn evaluate(
    args: &Args,
    path: &Path,
    frames: &mut [PlanarFrame],
    out: &SlamOutput,
) -> Result<ReferenceScore, Failure> {
    let reference = args.source.read_frames(path).map_err(Failure::input)?;
    let paired = pair_reference(frames, &reference);
    if paired < 2 {
        return Err(Failure::input(format!(
            "{}: fewer than two scans pair with {} (identical readings)",
            path.display(),
            args.log.display()
        )));
    }
    score_reference(frames, paired, out).map_err(Failure::internal)
}

/// Relation errors over the benchmark's relation file `path`, its scans found by ipc time stamp.
fn score_relation_file(
    args: &Args,
    path: &Path,
    frames: &[PlanarFrame],
    out: &SlamOutput,
) -> Result<RelationFileScore, Failure> {
    let relations = read_relations(path).map_err(Failure::input)?;
    let stamps: Vec<_> = frames.iter().map(|f| f.ipc_stamp_secs).collect();
    let matched = match_relation_file(&stamps, &relations);
    if matched.relations.is_empty() {
        return Err(Failure::input(format!(
            "{}: none of its {} relations names two scans of {} by their ipc time stamps \
             (relation files belong to CARMEN logs of the SLAM benchmark)",
            path.display(),
            relations.len(),
            args.log.display()
        )));
    }
    Ok(RelationFileScore::new(path.to_path_buf(), &matched, out))
}

fn print(report: &SlamReport) {
    println!(
        "{} scans, {} nodes, {} submaps, {} loop closures ({} rejected): {:.2} s, {:.0} scans/s",
        report.scans,
        report.nodes,
        report.submaps,
        report.loop_closures,
        report.rejected_loop_closures,
        report.seconds,
        report.scans_per_second,
    );
    println!("trajectory: {}", path(&report.outputs.trajectory));
    println!("corrected log: {}", path(&report.outputs.corrected_log));
    println!("map: {}", path(&report.map.files.png));
    if let Some(r) = report.reference.as_ref().filter(|r| shown(&r.summary)) {
        let s = &r.summary;
        println!(
            "relation error over {} consecutive reference pairs: {:.3} ± {:.3} m, {:.2} ± {:.2}°; \
             {} of {} checked loop closures wrong",
            s.relations,
            s.trans_error_m,
            s.trans_error_std_m,
            s.rot_error_deg,
            s.rot_error_std_deg,
            r.wrong_loop_closures,
            r.loop_closures_checked,
        );
    }
    if let Some(r) = report
        .reference
        .as_ref()
        .filter(|r| shown(&r.scan_refined.summary))
    {
        let s = &r.scan_refined.summary;
        println!(
            "relation error over {} scan-refined consecutive pairs: {:.4} ± {:.4} m, {:.2} ± {:.2}° \
             (the refinement moved the reference by {:.4} m on average)",
            s.relations,
            s.trans_error_m,
            s.trans_error_std_m,
            s.rot_error_deg,
            s.rot_error_std_deg,
            r.scan_refined.reference_moved_m,
        );
    }
    if let Some(f) = report.relations_file.as_ref().filter(|f| shown(&f.summary)) {
        let s = &f.summary;
        println!(
            "relation error over {} relations of {}: {:.4} ± {:.4} m, {:.2} ± {:.2}° ({} not found in the log)",
            s.relations,
            path(&f.path),
            s.trans_error_m,
            s.trans_error_std_m,
            s.rot_error_deg,
            s.rot_error_std_deg,
            f.unmatched,
        );
    }
}

/// Whether a summary line is printed: not when its figures are undefined (no relations; the
/// JSON shows them as null).
fn shown(s: &ErrorSummary) -> bool {
    [
        s.trans_error_m,
        s.trans_error_std_m,
        s.rot_error_deg,
        s.rot_error_std_deg,
    ]
    .iter()
    .all(|v| v.is_finite())
}

/// A path as the JSON report shows it (printed through the JSON value before: `?` when it is
/// not valid UTF-8).
fn path(p: &Path) -> &str {
    p.to_str().unwrap_or("?")
}

/// Scans at the optimised poses, the trajectory, the rebuilt map and the loop closures.
fn record(
    recording: &mut Recording,
    frames: &[PlanarFrame],
    out: &SlamOutput,
    map: &MapFile,
    model: Model,
) -> Result<(), Failure> {
    recording.planar_track(frames, &out.world_from_sensor)?;
    let end = recording.end_stamp();
    if let StoredStats::Planar(stats) = &map.stats {
        super::map::record::grid(recording, end, stats, model.picture())?;
    }
    let at = |node: usize| out.nodes.get(node).map(|p| Point3::new(p.x(), p.y(), 0.0));
    let pairs: Vec<_> = out
        .loop_closures
        .iter()
        .filter_map(|c| Some((at(c.anchor)?, at(c.node)?)))
        .collect();
    recording.scene(topic::LOOPS, end, frame::MAP, &loop_lines(&pairs))
}
