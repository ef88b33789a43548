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
use raypath_sensor_models::export::{MapFile, StoredStats};
use raypath_slam::benchmark::{
    LoopPairing, RefineConfig, check_loops, consecutive_relations, explicit_relation_errors,
    file_relation_errors, match_relation_file, random_relations, refine_relations, relation_errors,
};
use raypath_slam::{Slam, SlamConfig, SlamOutput};
use serde_json::{Value, json};

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

/// Loop closures between scans without a reference are checked against the nearest referenced
/// scan at most this many scans away, moved by the front-end's relative motion.
const NEIGHBOUR_GAP: usize = 50;

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
    let outputs = write_outputs(args, &frames, &output)?;
    let map = rebuild_map(args, &outputs.corrected)?;
    let evaluation = match &args.ground_truth {
        Some(path) => Some(evaluate(args, path, &mut frames, &output)?),
        None => None,
    };
    let relation_file = match &args.relations {
        Some(path) => Some(score_relation_file(args, path, &frames, &output)?),
        None => None,
    };
    if let Some(recording) = &mut recording {
        record(recording, &frames, &output, &outputs.map_prefix, args.model)?;
    }
    let mut doc = report(&output, seconds, &outputs, map, evaluation);
    if let (Some(r), Some(obj)) = (relation_file, doc.as_object_mut()) {
        obj.insert("relations_file".into(), r);
    }
    if super::console::json() {
        super::record::finish(recording, Some(&mut doc))?;
        println!("{doc}");
    } else {
        print(&doc);
        super::record::finish(recording, None)?;
    }
    Ok(())
}

struct Outputs {
    trajectory: PathBuf,
    corrected: PathBuf,
    loops: PathBuf,
    map_prefix: PathBuf,
}

fn write_outputs(
    args: &Args,
    frames: &[PlanarFrame],
    out: &SlamOutput,
) -> Result<Outputs, Failure> {
    let trajectory = args.out.join("trajectory.txt");
    out.write_tum(&trajectory).map_err(Failure::internal)?;
    let corrected = args.out.join("corrected.log");
    out.write_corrected_log(frames, &corrected)
        .map_err(Failure::internal)?;
    let loops = args.out.join("loop_closures.csv");
    let mut text = String::from("scan,anchor_scan,node,submap,x,y,theta,score,source\n");
    for c in &out.loop_closures {
        let scan = out.node_scan.get(c.node).copied().unwrap_or(usize::MAX);
        let anchor = out.node_scan.get(c.anchor).copied().unwrap_or(usize::MAX);
        let p = c.submap_from_sensor;
        let source = match c.source {
            raypath_slam::LoopSource::Nearby => "nearby",
            raypath_slam::LoopSource::PlaceRecognition => "place-recognition",
            raypath_slam::LoopSource::Global => "global",
        };
        text.push_str(&format!(
            "{scan},{anchor},{},{},{},{},{},{},{source}\n",
            c.node,
            c.submap,
            p.x(),
            p.y(),
            p.theta(),
            c.score
        ));
    }
    std::fs::write(&loops, text)
        .map_err(|e| Failure::internal(format!("{}: {e}", loops.display())))?;
    Ok(Outputs {
        trajectory,
        corrected,
        loops,
        map_prefix: args.out.join("map"),
    })
}

/// The map of `raypath map` over the corrected log (the optimised poses).
fn rebuild_map(args: &Args, corrected: &Path) -> Result<Value, Failure> {
    let map_args = super::map::Args {
        input: corrected.to_path_buf(),
        model: args.model,
        posterior: false,
        resolution: args.resolution,
        out: args.out.join("map"),
        max_range: args.max_range,
        min_range: 0.0,
        ray_step: 1,
        skip_no_returns: true,
        sparse: false,
        source: SourceArgs::default(),
        record: RecordArgs::default(),
    };
    super::map::build_json(&map_args)
}

/// Relation errors against the ground truth and the check of every loop closure.
fn evaluate(
    args: &Args,
    path: &Path,
    frames: &mut [PlanarFrame],
    out: &SlamOutput,
) -> Result<Value, Failure> {
    let reference = args.source.read_frames(path).map_err(Failure::input)?;
    let paired = pair_reference(frames, &reference);
    if paired < 2 {
        return Err(Failure::input(format!(
            "{}: fewer than two scans pair with {} (identical readings)",
            path.display(),
            args.log.display()
        )));
    }
    let truth: Vec<_> = frames.iter().map(|f| f.reference).collect();
    let referenced: Vec<usize> = (0..frames.len()).filter(|&i| truth[i].is_some()).collect();
    let summary = relation_errors(
        &truth,
        &out.world_from_sensor,
        &consecutive_relations(&referenced),
    );
    let random = relation_errors(
        &truth,
        &out.world_from_sensor,
        &random_relations(&referenced, 1000, 1),
    );
    let scans: Vec<_> = frames.iter().map(|f| &f.scan).collect();
    let (checked, wrong, checks) =
        check_loops(out, &scans, &truth, NEIGHBOUR_GAP, LoopPairing::Overlap);
    let (_, wrong_nearest, _) =
        check_loops(out, &scans, &truth, NEIGHBOUR_GAP, LoopPairing::Nearest);
    let refined = refine_relations(
        &scans,
        &truth,
        &consecutive_relations(&referenced),
        &RefineConfig::default(),
    )
    .map_err(Failure::internal)?;
    let (moved, _) = refined.correction_m();
    let disputed = raypath_slam::benchmark::wrong_at_disputed_reference(&checks, &scans, &truth);
    Ok(json!({
        "paired_scans": paired,
        "summary": summary,
        "random_pairs": random,
        "scan_refined": {
            "summary": explicit_relation_errors(&out.world_from_sensor, &refined.relations),
            "dropped": refined.dropped,
            "reference_moved_m": moved,
        },
        "loop_closures_checked": checked,
        "wrong_loop_closures": wrong,
        "wrong_loop_closures_nearest_node": wrong_nearest,
        "wrong_loop_closures_reference_disputed": disputed,
    }))
}

/// Relation errors over the benchmark's relation file `path`, its scans found by ipc time stamp.
fn score_relation_file(
    args: &Args,
    path: &Path,
    frames: &[PlanarFrame],
    out: &SlamOutput,
) -> Result<Value, Failure> {
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
    Ok(json!({
        "path": path,
        "summary": file_relation_errors(&out.world_from_sensor, &matched),
        "unmatched": matched.unmatched,
    }))
}

fn report(
    out: &SlamOutput,
    seconds: f64,
    outputs: &Outputs,
    map: Value,
    evaluation: Option<Value>,
) -> Value {
    let mut doc = json!({
        "scans": out.scans.len(),
        "nodes": out.nodes.len(),
        "submaps": out.submaps.len(),
        "loop_closures": out.loop_closures.len(),
        "rejected_loop_closures": out.rejected_loop_closures.len(),
        "seconds": seconds,
        "scans_per_second": out.scans.len() as f64 / seconds.max(1e-9),
        "timing": out.stats,
        "outputs": {
            "trajectory": outputs.trajectory,
            "corrected_log": outputs.corrected,
            "loop_closures": outputs.loops,
        },
        "map": map,
    });
    if let (Some(Value::Object(e)), Some(obj)) = (evaluation, doc.as_object_mut()) {
        obj.extend(e);
    }
    doc
}

fn print(doc: &Value) {
    println!(
        "{} scans, {} nodes, {} submaps, {} loop closures ({} rejected): {:.2} s, {:.0} scans/s",
        doc["scans"],
        doc["nodes"],
        doc["submaps"],
        doc["loop_closures"],
        doc["rejected_loop_closures"],
        doc["seconds"].as_f64().unwrap_or(f64::NAN),
        doc["scans_per_second"].as_f64().unwrap_or(f64::NAN),
    );
    println!(
        "trajectory: {}",
        doc["outputs"]["trajectory"].as_str().unwrap_or("?")
    );
    println!(
        "corrected log: {}",
        doc["outputs"]["corrected_log"].as_str().unwrap_or("?")
    );
    println!(
        "map: {}",
        doc["map"]["files"]["png"].as_str().unwrap_or("(see map.*)")
    );
    if let Ok(s) = serde_json::from_value::<SummaryView>(doc["summary"].clone()) {
        println!(
            "relation error over {} consecutive reference pairs: {:.3} ± {:.3} m, {:.2} ± {:.2}°; \
             {} of {} checked loop closures wrong",
            s.relations,
            s.trans_error_m,
            s.trans_error_std_m,
            s.rot_error_deg,
            s.rot_error_std_deg,
            doc["wrong_loop_closures"],
            doc["loop_closures_checked"],
        );
    }
    if let Ok(s) = serde_json::from_value::<SummaryView>(doc["scan_refined"]["summary"].clone()) {
        println!(
            "relation error over {} scan-refined consecutive pairs: {:.4} ± {:.4} m, {:.2} ± {:.2}° \
             (the refinement moved the reference by {:.4} m on average)",
            s.relations,
            s.trans_error_m,
            s.trans_error_std_m,
            s.rot_error_deg,
            s.rot_error_std_deg,
            doc["scan_refined"]["reference_moved_m"]
                .as_f64()
                .unwrap_or(f64::NAN),
        );
    }
    if let Ok(s) = serde_json::from_value::<SummaryView>(doc["relations_file"]["summary"].clone()) {
        println!(
            "relation error over {} relations of {}: {:.4} ± {:.4} m, {:.2} ± {:.2}° ({} not found in the log)",
            s.relations,
            doc["relations_file"]["path"].as_str().unwrap_or("?"),
            s.trans_error_m,
            s.trans_error_std_m,
            s.rot_error_deg,
            s.rot_error_std_deg,
            doc["relations_file"]["unmatched"],
        );
    }
}

/// The `summary` object read back for printing.
#[derive(serde::Deserialize)]
struct SummaryView {
    trans_error_m: f64,
    trans_error_std_m: f64,
    rot_error_deg: f64,
    rot_error_std_deg: f64,
    relations: usize,
}

/// Scans at the optimised poses, the trajectory, the rebuilt map and the loop closures.
fn record(
    recording: &mut Recording,
    frames: &[PlanarFrame],
    out: &SlamOutput,
    map_prefix: &Path,
    model: Model,
) -> Result<(), Failure> {
    recording.planar_track(frames, &out.world_from_sensor)?;
    let end = recording.end_stamp();
    let rpmap = map_prefix.with_extension("rpmap");
    let file = MapFile::read_file(&rpmap).map_err(Failure::internal)?;
    if let StoredStats::Planar(stats) = &file.stats {
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
