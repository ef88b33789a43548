//! `raypath octree`: the Rtree variable-resolution occupancy grid (Khan 2017, ch. 2) built
//! from a scan graph, a KITTI sequence or a single `x y z` scan.
//!
//! Inputs: an OctoMap ScanGraph (`.graph`, points in the sensor frame with a pose per scan),
//! a KITTI odometry sequence directory (velodyne scans, poses and `calib.txt`; poses are
//! turned into a REP-103 world frame), or a point list (`x y z` per line, optionally
//! compressed, sensor at the origin — OctoMap's `scan.dat`).
//!
//! Prints nodes, leaves, bytes and times; `--json` prints one object with the keys
//! `input`, `scans`, `points`, `resolution_m`, `model`, `fusion`, `fusion_interval_scans`,
//! `max_entries`, `min_entries`,
//! `nodes`, `leaves`, `occupied_leaves`, `fused_leaves`, `height`, `base_cubes`, `bytes`,
//! `insert_secs`, `insert_us_per_point`, `access_secs`, `out`.
//! `--fusion clamped` (default) is the thesis' rule: only clamped cells fuse. `--fusion equal`
//! is our extension: cells with bit-equal log-odds fuse (OctoMap's pruning rule, with
//! cuboids), and fused cells are split where a scan changes part of them, so the map equals
//! an unfused grid at every base cube.
//! `--out FILE` writes the map: `.bt` as an OctoMap tree at the base resolution, `.ply` as a
//! mesh of the occupied cuboids.

use std::path::{Path, PathBuf};
use std::time::Instant;

use raypath_geometry::{PointCloud, Pose3};
use raypath_io::kitti::KittiSequence;
use raypath_io::octomap::read_graph;
use raypath_rtree_grid::{FusionRule, GridConfig, RtreeGrid, SensorModel};
use serde_json::json;

use super::Failure;

/// Arguments of `raypath octree`.
#[derive(clap::Args)]
pub struct Args {
    /// A `.graph` scan graph, a KITTI sequence directory or an `x y z` point file.
    pub input: PathBuf,
    /// Base resolution r, metres.
    #[arg(long, value_name = "R")]
    pub resolution: f64,
    /// Inverse sensor model: beam (beam-based) or endpoint (beam-end-point).
    #[arg(long, default_value = "beam", value_name = "NAME")]
    pub model: String,
    /// M: most entries per R-tree node (d = ⌈0.4·M⌉).
    #[arg(long, default_value_t = 8, value_name = "M")]
    pub max_entries: usize,
    /// Cut beams longer than this, metres (their ends are not marked occupied).
    #[arg(long, value_name = "M")]
    pub max_range: Option<f64>,
    /// Use at most this many scans.
    #[arg(long, value_name = "N")]
    pub scans: Option<usize>,
    /// Fusion rule: clamped (the thesis: only clamped cells fuse) or equal (ours: cells with
    /// equal log-odds fuse, split again on partial updates; the map stays exact).
    #[arg(long, default_value = "clamped", value_name = "RULE")]
    pub fusion: String,
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
    /// Print one JSON document on standard output.
    #[arg(long)]
    pub json: bool,
}

/// The scans as `(world_from_sensor, points in the sensor frame)`.
fn load(args: &Args) -> Result<Vec<(Pose3, PointCloud)>, Failure> {
    let bad = |e: raypath_io::Error| Failure::input(e, args.json);
    let path = &args.input;
    let limit = args.scans.unwrap_or(usize::MAX);
    if path.is_dir() {
        let sequence = KittiSequence::open(path).map_err(bad)?;
        let poses = sequence.poses().map_err(bad)?;
        let calib = sequence.calib().map_err(bad)?.ok_or_else(|| {
            Failure::input(
                format!("{}: the KITTI sequence has no calib.txt", path.display()),
                args.json,
            )
        })?;
        let cam0_from_velo = calib.cam0_from_velo().ok_or_else(|| {
            Failure::input(
                format!(
                    "{}: calib.txt has no Tr (velodyne to camera)",
                    path.display()
                ),
                args.json,
            )
        })?;
        let flu = raypath_io::kitti::flu_from_camera();
        let mut scans = Vec::new();
        for file in sequence.scan_files.iter().take(limit) {
            let pose = poses.get(file.frame as usize).ok_or_else(|| {
                Failure::input(
                    format!("{}: no pose for frame {}", path.display(), file.frame),
                    args.json,
                )
            })?;
            let cloud = raypath_io::kitti::read_velodyne(&file.path).map_err(bad)?;
            scans.push((flu * *pose * cam0_from_velo, cloud));
        }
        return Ok(scans);
    }
    let name = path.to_string_lossy();
    if name.ends_with(".graph") || name.ends_with(".graph.gz") || name.ends_with(".graph.bz2") {
        let graph = read_graph(path).map_err(bad)?;
        return Ok(graph
            .nodes
            .into_iter()
            .take(limit)
            .map(|n| (n.world_from_sensor, n.points))
            .collect());
    }
    let cloud = raypath_io::xyz::read_xyz(path).map_err(bad)?;
    Ok(vec![(Pose3::identity(), cloud)])
}

fn write_map(grid: &RtreeGrid, out: &Path, json: bool) -> Result<(), Failure> {
    let name = out.to_string_lossy().to_lowercase();
    if name.ends_with(".bt") {
        raypath_io::octomap::write_bt_file(out, &grid.to_octree())
            .map_err(|e| Failure::input(e, json))
    } else if name.ends_with(".ply") {
        let file = std::fs::File::create(out).map_err(|e| Failure {
            message: format!("{}: {e}", out.display()),
            bad_input: false,
            json,
        })?;
        grid.write_occupied_ply(std::io::BufWriter::new(file))
            .map_err(|e| Failure {
                message: format!("{}: {e}", out.display()),
                bad_input: false,
                json,
            })
    } else {
        Err(Failure::input(
            format!("{}: --out must end in .bt or .ply", out.display()),
            json,
        ))
    }
}

/// Runs the subcommand.
pub fn run(args: &Args) -> Result<(), Failure> {
    let model = match args.model.as_str() {
        "beam" => SensorModel::BeamBased,
        "endpoint" => SensorModel::BeamEndPoint,
        other => {
            return Err(Failure::input(
                format!("unknown model {other:?}; choose beam or endpoint"),
                args.json,
            ));
        }
    };
    let fusion_rule = match args.fusion.as_str() {
        "clamped" => FusionRule::Clamped,
        "equal" => FusionRule::EqualValue,
        other => {
            return Err(Failure::input(
                format!("unknown fusion rule {other:?}; choose clamped or equal"),
                args.json,
            ));
        }
    };
    if let Some(out) = &args.out {
        let name = out.to_string_lossy().to_lowercase();
        if !(name.ends_with(".bt") || name.ends_with(".ply")) {
            return Err(Failure::input(
                format!("{}: --out must end in .bt or .ply", out.display()),
                args.json,
            ));
        }
    }
    let mut config = GridConfig::with(args.resolution, args.max_entries, model);
    config.max_range_m = args.max_range;
    config.fusion = !args.no_fusion;
    config.fusion_rule = fusion_rule;
    config.fusion_interval_scans = args.fusion_interval;
    let mut grid = RtreeGrid::new(config).map_err(|e| Failure::input(e, args.json))?;
    let scans = load(args)?;
    let points: usize = scans.iter().map(|(_, c)| c.num_valid()).sum();
    let started = Instant::now();
    for (pose, cloud) in &scans {
        grid.insert_cloud(pose, cloud);
    }
    grid.fuse_pending();
    let insert_secs = started.elapsed().as_secs_f64();
    grid.shrink_to_fit();
    let started = Instant::now();
    grid.for_each_occupied(|b| {
        std::hint::black_box(b);
    });
    let access_secs = started.elapsed().as_secs_f64();
    let stats = grid.stats();
    if let Some(out) = &args.out {
        write_map(&grid, out, args.json)?;
    }
    let per_point_us = insert_secs / points.max(1) as f64 * 1e6;
    if args.json {
        let doc = json!({
            "input": args.input.display().to_string(),
            "scans": scans.len(),
            "points": points,
            "resolution_m": args.resolution,
            "model": args.model,
            "fusion": args.fusion,
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
        println!("{doc}");
    } else {
        println!(
            "{}: {} scans, {points} points, r = {} m, {} model, {} fusion, M = {}",
            args.input.display(),
            scans.len(),
            args.resolution,
            args.model,
            args.fusion,
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
    }
    Ok(())
}
