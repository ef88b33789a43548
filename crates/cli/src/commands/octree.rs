//! `raypath octree`: the Rtree variable-resolution occupancy grid (Khan 2017, ch. 2) built
//! from a scan graph, a 3-D sequence or a single `x y z` scan.
//!
//! Inputs: an OctoMap ScanGraph (`.graph`, points in the sensor frame with a pose per scan),
//! a sequence read through `raypath_io::sequence::SweepSequence` — a KITTI odometry sequence
//! directory (velodyne scans, poses and `calib.txt`; the world frame is the velodyne frame of
//! the first scan, REP-103 axes), an NCLT session directory, or a rosbag2 bag's PointCloud2
//! topic (its directory with `metadata.yaml`, or its `.mcap` file) — at its reference poses,
//! else its odometry, or a point list (`x y z` per line, optionally compressed, sensor at the
//! origin — OctoMap's `scan.dat`).
//!
//! Prints nodes, leaves, bytes and times; `--json` prints one object with the keys
//! `input`, `scans`, `points`, `resolution_m`, `model`, `fusion`, `seeds`,
//! `fusion_interval_scans`, `max_entries`, `min_entries`,
//! `nodes`, `leaves`, `occupied_leaves`, `fused_leaves`, `height`, `base_cubes`, `bytes`,
//! `insert_secs`, `insert_us_per_point`, `access_secs`, `out`.
//! `--fusion clamped` (default) is the thesis' rule: only clamped cells fuse. `--fusion equal`
//! is our extension: cells with bit-equal log-odds fuse (OctoMap's pruning rule, with
//! cuboids), and fused cells are split where a scan changes part of them, so the map equals
//! an unfused grid at every base cube.
//! `--seeds samples` (default) starts fusions from the thesis' selection (end points plus
//! cells sampled along the beams); `--seeds all` from every updated cell: more fusion, and
//! with `--fusion equal --fusion-interval 10` the fastest of the variants measured in
//! `docs/results/octomap.md`.
//! `--out FILE` writes the map: `.bt` as an OctoMap tree at the base resolution, `.ply` as a
//! mesh of the occupied cuboids.
//!
//! `--record OUT.mcap` writes a Foxglove recording (see `record`): `/tf` `map → base_link` at
//! each scan's pose and time (sequences: their scan times; scan graphs and point files: the
//! scan index as seconds), the sensor `/trajectory`, the centres of all occupied leaves as the
//! PointCloud `/map_points` (intensity: occupancy probability), and the occupied leaves as
//! cubes on `/octree` — at most [`MAX_CUBES`], the largest first (a cube is about 200 bytes of
//! JSON). The scans themselves are not recorded.

use std::path::{Path, PathBuf};
use std::time::Instant;

use nalgebra::Point3;
use raypath_geometry::{PointCloud, Pose3};
use raypath_io::foxglove::{frame, topic};
use raypath_io::octomap::read_graph;
use raypath_rtree_grid::{Cuboid, FusionRule, GridConfig, RtreeGrid, Selection, SensorModel};
use serde_json::json;

use super::Failure;
use super::record::{RecordArgs, Recording, cube_entities};
use super::source_args::{SourceArgs, is_bag, sweep_poses};

/// `--model`: the inverse sensor model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ModelArg {
    /// Beam-based: the cells a beam traverses are updated as free, its end cell as occupied.
    Beam,
    /// Beam-end-point: only the end cell is updated (occupied); free space is not modelled.
    Endpoint,
}

/// `--fusion`: which cells fuse.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FusionArg {
    /// The thesis: only clamped cells fuse.
    Clamped,
    /// Ours: cells with equal log-odds fuse, split again on partial updates; the map stays
    /// exact.
    Equal,
}

/// `--seeds`: which cells start fusions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SeedsArg {
    /// The thesis: end-point cells plus cells sampled along the beams (one per 10 cubes).
    Samples,
    /// Every cell a scan updated.
    All,
}

/// Arguments of `raypath octree`.
#[derive(clap::Args)]
pub struct Args {
    /// A `.graph` scan graph, a KITTI sequence or NCLT session directory, a rosbag2 bag
    /// (directory with metadata.yaml, or .mcap file) with PointCloud2, or an `x y z` point
    /// file.
    pub input: PathBuf,
    /// Base resolution r, metres.
    #[arg(long, value_name = "R")]
    pub resolution: f64,
    /// Inverse sensor model.
    #[arg(long, value_enum, default_value_t = ModelArg::Beam, value_name = "NAME")]
    pub model: ModelArg,
    /// M: most entries per R-tree node (d = ⌈0.4·M⌉).
    #[arg(long, default_value_t = 8, value_name = "M")]
    pub max_entries: usize,
    /// Cut beams longer than this, metres (their ends are not marked occupied).
    #[arg(long, value_name = "M")]
    pub max_range: Option<f64>,
    /// Use at most this many scans.
    #[arg(long, value_name = "N")]
    pub scans: Option<usize>,
    /// Fusion rule.
    #[arg(long, value_enum, default_value_t = FusionArg::Clamped, value_name = "RULE")]
    pub fusion: FusionArg,
    /// Which cells start fusions.
    #[arg(long, value_enum, default_value_t = SeedsArg::Samples, value_name = "WHICH")]
    pub seeds: SeedsArg,
    /// Fuse after every this many scans (1: the thesis; larger: fewer splits of fused cells
    /// on a moving sensor; pending fusions run after the last scan).
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub fusion_interval: u32,
    /// Disable cell fusion (a plain grid in the R-tree).
    #[arg(long)]
    pub no_fusion: bool,
    /// Write the map: `.bt` (OctoMap tree) or `.ply` (occupied cuboids).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// How to read a bag.
    #[command(flatten)]
    pub source: SourceArgs,
    /// A Foxglove recording of the run.
    #[command(flatten)]
    pub record: RecordArgs,
}

/// Most occupied leaves recorded as cubes on `/octree` (the largest first).
pub const MAX_CUBES: usize = 20_000;

/// Scans as `(world_from_sensor, points in the sensor frame)`.
type Scans = Vec<(Pose3, PointCloud)>;

/// The scans with their times: a sequence's scan times, else the scan index as seconds.
fn load(args: &Args) -> Result<(Scans, Vec<f64>), Failure> {
    let bad = |e: raypath_io::Error| Failure::input(e);
    let path = &args.input;
    let limit = args.scans.unwrap_or(usize::MAX);
    let indices = |n: usize| (0..n).map(|i| i as f64).collect();
    if path.is_dir() || is_bag(path) {
        let sequence = args.source.open_sweeps(path).map_err(bad)?;
        let Some((poses, _)) = sweep_poses(&sequence) else {
            return Err(Failure::input(format!(
                "{}: no sensor poses (reference or odometry)",
                sequence.name.display()
            )));
        };
        let mut scans = Vec::new();
        for (i, pose) in poses.iter().enumerate().take(limit) {
            scans.push((*pose, sequence.sweep(i).map_err(bad)?));
        }
        let mut stamps: Vec<f64> = indices(scans.len());
        for (stamp, t) in stamps.iter_mut().zip(&sequence.stamps_secs) {
            *stamp = *t;
        }
        return Ok((scans, stamps));
    }
    let name = path.to_string_lossy();
    let scans: Scans = if name.ends_with(".graph")
        || name.ends_with(".graph.gz")
        || name.ends_with(".graph.bz2")
    {
        let graph = read_graph(path).map_err(bad)?;
        graph
            .nodes
            .into_iter()
            .take(limit)
            .map(|n| (n.world_from_sensor, n.points))
            .collect()
    } else {
        let cloud = raypath_io::xyz::read_xyz(path).map_err(bad)?;
        vec![(Pose3::identity(), cloud)]
    };
    let stamps = indices(scans.len());
    Ok((scans, stamps))
}

fn write_map(grid: &RtreeGrid, out: &Path) -> Result<(), Failure> {
    let name = out.to_string_lossy().to_lowercase();
    if name.ends_with(".bt") {
        raypath_io::octomap::write_bt_file(out, &grid.to_octree()).map_err(Failure::input)
    } else if name.ends_with(".ply") {
        let file = std::fs::File::create(out)
            .map_err(|e| Failure::internal(format!("{}: {e}", out.display())))?;
        grid.write_occupied_ply(std::io::BufWriter::new(file))
            .map_err(|e| Failure::internal(format!("{}: {e}", out.display())))
    } else {
        Err(Failure::input(format!(
            "{}: --out must end in .bt or .ply",
            out.display()
        )))
    }
}

/// Runs the subcommand.
pub fn run(args: &Args) -> Result<(), Failure> {
    let model = match args.model {
        ModelArg::Beam => SensorModel::BeamBased,
        ModelArg::Endpoint => SensorModel::BeamEndPoint,
    };
    let fusion_rule = match args.fusion {
        FusionArg::Clamped => FusionRule::Clamped,
        FusionArg::Equal => FusionRule::EqualValue,
    };
    if let Some(out) = &args.out {
        let name = out.to_string_lossy().to_lowercase();
        if !(name.ends_with(".bt") || name.ends_with(".ply")) {
            return Err(Failure::input(format!(
                "{}: --out must end in .bt or .ply",
                out.display()
            )));
        }
    }
    let mut config = GridConfig::with(args.resolution, args.max_entries, model);
    config.max_range_m = args.max_range;
    config.fusion = !args.no_fusion;
    config.fusion_rule = fusion_rule;
    config.fusion_interval_scans = args.fusion_interval;
    if args.seeds == SeedsArg::All {
        config.selection = Selection::UpdatedCells;
    }
    let mut grid = RtreeGrid::new(config).map_err(Failure::input)?;
    let mut recording = Recording::open(&args.record)?;
    let (scans, stamps) = load(args)?;
    check_lattice(args, &scans)?;
    let points: usize = scans.iter().map(|(_, c)| c.num_valid()).sum();
    let started = Instant::now();
    let bar = super::console::progress(scans.len(), "insertion");
    // One batch: fusions at the interval and after the last scan.
    grid.insert_clouds(scans.iter().map(|(pose, cloud)| {
        bar.inc(1);
        (pose, cloud)
    }));
    bar.finish_and_clear();
    super::console::stage("insertion and fusion", started);
    let insert_secs = started.elapsed().as_secs_f64();
    grid.shrink_to_fit();
    let started = Instant::now();
    grid.for_each_occupied(|b| {
        std::hint::black_box(b);
    });
    let access_secs = started.elapsed().as_secs_f64();
    let stats = grid.stats();
    if let Some(out) = &args.out {
        write_map(&grid, out)?;
    }
    if let Some(recording) = &mut recording {
        record(recording, &grid, &scans, &stamps)?;
    }
    let per_point_us = insert_secs / points.max(1) as f64 * 1e6;
    if super::console::json() {
        let mut doc = json!({
            "input": args.input.display().to_string(),
            "scans": scans.len(),
            "points": points,
            "resolution_m": args.resolution,
            "model": super::choice_name(&args.model),
            "fusion": super::choice_name(&args.fusion),
            "seeds": super::choice_name(&args.seeds),
            "fusion_interval_scans": config.fusion_interval_scans,
            "max_entries": config.max_entries,
            "min_entries": config.min_entries,
            "nodes": stats.nodes,
            "leaves": stats.leaves,
            "occupied_leaves": stats.occupied_leaves,
            "fused_leaves": stats.fused_leaves,
            "height": stats.height,
            "base_cubes": stats.base_cubes,
            "bytes": stats.bytes,
            "insert_secs": insert_secs,
            "insert_us_per_point": per_point_us,
            "access_secs": access_secs,
            "out": args.out.as_ref().map(|p| p.display().to_string()),
        });
        super::record::finish(recording, Some(&mut doc))?;
        println!("{doc}");
    } else {
        println!(
            "{}: {} scans, {points} points, r = {} m, {} model, {} fusion, M = {}",
            args.input.display(),
            scans.len(),
            args.resolution,
            super::choice_name(&args.model),
            super::choice_name(&args.fusion),
            config.max_entries
        );
        println!(
            "leaves {} ({} occupied, {} fused), nodes {}, height {}, {} base cubes, {} bytes",
            stats.leaves,
            stats.occupied_leaves,
            stats.fused_leaves,
            stats.nodes,
            stats.height,
            stats.base_cubes,
            stats.bytes
        );
        println!(
            "insertion {insert_secs:.3} s ({per_point_us:.3} µs/point), occupied access {:.3} ms",
            access_secs * 1e3
        );
        if let Some(out) = &args.out {
            println!("wrote {}", out.display());
        }
        super::record::finish(recording, None)?;
    }
    Ok(())
}

/// Refuses scans that reach beyond the grid's 16-bit lattice (±32 768 base cubes per axis
/// around the origin, as OctoMap's): such points would be dropped without a trace.
fn check_lattice(args: &Args, scans: &Scans) -> Result<(), Failure> {
    let reach = raypath_rtree_grid::key::lattice_half_extent_m(args.resolution);
    let inside = |p: &[f64; 3]| p.iter().all(|v| v.abs() < reach);
    let mut outside = 0usize;
    let mut total = 0usize;
    let mut first: Option<usize> = None;
    for (i, (pose, cloud)) in scans.iter().enumerate() {
        let mut beyond = !inside(&pose.translation().into());
        for j in (0..cloud.len()).filter(|&j| cloud.is_valid(j)) {
            let p = pose.transform_point(&cloud.point_f64(j));
            total += 1;
            if !inside(&[p.x, p.y, p.z]) {
                outside += 1;
                beyond = true;
            }
        }
        if beyond && first.is_none() {
            first = Some(i);
        }
    }
    let Some(scan) = first else { return Ok(()) };
    Err(Failure::input(format!(
        "{}: {outside} of {total} points (first in scan {scan}) lie beyond the grid's \
             lattice, which reaches ±{reach:.3} m from the origin at --resolution {} m \
             (32768 base cubes per axis); choose a coarser --resolution",
        args.input.display(),
        args.resolution
    )))
}

/// `--record`: the sensor poses (`/tf`, `/trajectory`), the occupied leaves' centres
/// (`/map_points`) and the largest [`MAX_CUBES`] occupied leaves as cubes (`/octree`).
fn record(
    recording: &mut Recording,
    grid: &RtreeGrid,
    scans: &[(Pose3, PointCloud)],
    stamps: &[f64],
) -> Result<(), Failure> {
    for ((pose, _), stamp) in scans.iter().zip(stamps) {
        recording.robot_pose(*stamp, pose)?;
    }
    let end = recording.end_stamp();
    let poses: Vec<Pose3> = scans.iter().map(|(pose, _)| *pose).collect();
    recording.trajectory(topic::TRAJECTORY, end, &poses)?;
    let mut occupied: Vec<Cuboid> = Vec::new();
    grid.for_each_cuboid(|c| {
        if c.occupied {
            occupied.push(*c);
        }
    });
    let center = |c: &Cuboid| {
        let m = |a: usize| ((c.min_m[a] + c.max_m[a]) / 2.0) as f32;
        Point3::new(m(0), m(1), m(2))
    };
    let mut cloud = PointCloud::from_points(occupied.iter().map(center).collect());
    cloud.intensity = Some(occupied.iter().map(|c| c.probability as f32).collect());
    recording.points(topic::MAP_POINTS, end, frame::MAP, &cloud, None)?;
    if occupied.len() > MAX_CUBES {
        super::console::note(format!(
            "--record: {} occupied leaves; /octree holds the {MAX_CUBES} largest as cubes, \
             /map_points the centres of all",
            occupied.len()
        ));
        let volume = |c: &Cuboid| (0..3).map(|a| c.max_m[a] - c.min_m[a]).product::<f64>();
        occupied.sort_by(|a, b| volume(b).total_cmp(&volume(a)));
        occupied.truncate(MAX_CUBES);
    }
    let entities = cube_entities(&occupied, "occupied leaves");
    recording.scene(topic::OCTREE, end, frame::MAP, &entities)
}
