//! The scans of the comparison, as OctoMap scan graphs (written to `target/eval/octomap/`).

use std::path::PathBuf;

use anyhow::{Context, Result};
use nalgebra::Point3;
use raypath_geometry::{PointCloud, Pose3};
use raypath_io::octomap::{ScanGraph, ScanNode, write_graph_file};
use raypath_io::sequence::{SweepOptions, SweepSequence};

use super::super::EvalContext;

/// One data set: its scans and the graph file holding them.
pub struct Dataset {
    /// Short name.
    pub name: String,
    /// What it is.
    pub about: String,
    /// The scans.
    pub graph: ScanGraph,
    /// The `.graph` file the OctoMap driver reads.
    pub path: PathBuf,
    /// Query points (world frame) for the classification agreement.
    pub queries: Vec<Point3<f64>>,
    /// The query file.
    pub queries_path: PathBuf,
    /// Real data (the headline table) rather than simulated.
    pub real: bool,
    /// Run every resolution and M of the sweep; otherwise r = 0.2 m, M = 8 only (the real
    /// sequences, to keep the run time bounded).
    pub full_sweep: bool,
}

pub(super) fn node(id: u32, world_from_sensor: Pose3, points: Vec<Point3<f32>>) -> ScanNode {
    ScanNode {
        id,
        world_from_sensor,
        points: PointCloud::from_points(points),
    }
}

/// The real `scan.dat` (sensor at the origin), every `stride`-th point, inserted `repeat`
/// times (a static sensor scanning a static scene: cells reach the clamping bounds).
pub fn scan_dat(ctx: &EvalContext, stride: usize, repeat: usize) -> Result<Option<Dataset>> {
    let path = ctx.data("octomap/scan.dat.bz2");
    if !path.exists() {
        eprintln!(
            "octomap: {} is absent, skipping the real scan",
            path.display()
        );
        return Ok(None);
    }
    let cloud = raypath_io::xyz::read_xyz(&path)?;
    let points: Vec<_> = (0..cloud.len())
        .step_by(stride)
        .map(|i| cloud.points[i])
        .collect();
    let n = points.len();
    let graph = ScanGraph {
        nodes: (0..repeat)
            .map(|i| node(i as u32, Pose3::identity(), points.clone()))
            .collect(),
        edges: Vec::new(),
    };
    let name = if repeat == 1 {
        "scan.dat".to_owned()
    } else {
        format!("scan.dat-x{repeat}")
    };
    let mut set = finish(
        ctx,
        &name,
        format!(
            "real OctoMap sample scan, {n} points{}, sensor at the origin{}",
            if stride > 1 {
                format!(" (every {stride}th)")
            } else {
                String::new()
            },
            if repeat > 1 {
                format!(", inserted {repeat} times (static sensor)")
            } else {
                String::new()
            }
        ),
        graph,
    )?;
    set.real = true;
    Ok(Some(set))
}

/// A real 3-D sequence read through [`SweepSequence`] (a KITTI sequence directory, an Ouster
/// pcap with its poses): every `stride`-th valid point of each sweep, at the sequence's
/// reference poses (identity when it has none and holds a single sweep). `None`, with a
/// message, when the data is absent.
pub fn real_sweeps(
    ctx: &EvalContext,
    name: &str,
    relative: &str,
    kind: &str,
    stride: usize,
) -> Result<Option<Dataset>> {
    let path = ctx.data(relative);
    if !path.exists() {
        eprintln!("octomap: {} is absent, skipping {name}", path.display());
        return Ok(None);
    }
    let sequence = SweepSequence::open(&path, &SweepOptions::default())
        .with_context(|| format!("opening {}", path.display()))?;
    let poses = match sequence.require_reference() {
        Ok(poses) => poses.to_vec(),
        Err(_) if sequence.len() == 1 => vec![Pose3::identity()],
        Err(e) => return Err(e.into()),
    };
    let mut nodes = Vec::new();
    for (k, world_from_sensor) in poses.iter().enumerate().take(sequence.len()) {
        let cloud = sequence.sweep(k)?;
        let points: Vec<_> = (0..cloud.len())
            .filter(|&j| cloud.is_valid(j))
            .step_by(stride)
            .map(|j| cloud.points[j])
            .collect();
        nodes.push(node(k as u32, *world_from_sensor, points));
    }
    let graph = ScanGraph {
        nodes,
        edges: Vec::new(),
    };
    let about = format!(
        "real {kind}: {} scans at the sequence's poses, {} points{} (`{relative}`)",
        graph.nodes.len(),
        graph.num_points(),
        if stride > 1 {
            format!(" (every {stride}th valid point)")
        } else {
            String::new()
        }
    );
    let mut set = finish(ctx, name, about, graph)?;
    set.real = true;
    set.full_sweep = false;
    Ok(Some(set))
}

/// A simulated urban drive (HDL-64E, `raypath-sim` urban-kitti set): `scans` scans taken
/// every `frame_step` frames, every `stride`-th point, in the REP-103 world frame of
/// [`SweepSequence`] (the velodyne frame of the first scan).
pub fn urban(
    ctx: &EvalContext,
    scans: usize,
    frame_step: usize,
    stride: usize,
) -> Result<Option<Dataset>> {
    let root = match crate::generate::ensure("urban-kitti", ctx.quick) {
        Ok(root) => root,
        Err(error) => {
            eprintln!("octomap: skipping the urban drive: {error:#}");
            return Ok(None);
        }
    };
    let sequence = SweepSequence::open(&root.join("sequences/00"), &SweepOptions::default())?;
    let poses = sequence.require_reference()?;
    let mut nodes = Vec::new();
    for (i, k) in (0..sequence.len())
        .step_by(frame_step)
        .take(scans)
        .enumerate()
    {
        let cloud = sequence.sweep(k)?;
        let points: Vec<_> = (0..cloud.len())
            .step_by(stride)
            .filter(|&j| cloud.is_valid(j))
            .map(|j| cloud.points[j])
            .collect();
        nodes.push(node(i as u32, poses[k], points));
    }
    let graph = ScanGraph {
        nodes,
        edges: Vec::new(),
    };
    let about = format!(
        "simulated urban drive (raypath-sim urban-kitti, HDL-64E): {} scans {} frames apart, {} points{}",
        graph.nodes.len(),
        frame_step,
        graph.num_points(),
        if stride > 1 {
            format!(" (every {stride}th point)")
        } else {
            String::new()
        }
    );
    finish(ctx, "urban", about, graph).map(Some)
}

/// Writes the graph and draws query points: per scan, points at random fractions
/// `t ∈ [0, 1.05]` of random beams (free space, the surfaces and just behind them).
pub(super) fn finish(
    ctx: &EvalContext,
    name: &str,
    about: String,
    graph: ScanGraph,
) -> Result<Dataset> {
    let dir = ctx.workspace_root.join("target/eval/octomap");
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let path = dir.join(format!("{name}.graph"));
    write_graph_file(&path, &graph)?;
    let mut state = 0x1234_5678_9abc_def0u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let per_scan = 20_000 / graph.nodes.len().max(1);
    let mut queries = Vec::new();
    for n in &graph.nodes {
        if n.points.is_empty() {
            continue;
        }
        let origin = Point3::from(n.world_from_sensor.translation());
        for _ in 0..per_scan {
            let i = ((next() * n.points.len() as f64) as usize).min(n.points.len() - 1);
            let end = n.world_from_sensor.transform_point(&n.points.point_f64(i));
            let t = next() * 1.05;
            queries.push(origin + (end - origin) * t);
        }
    }
    let queries_path = dir.join(format!("{name}.queries.txt"));
    let text: String = queries
        .iter()
        .map(|q| format!("{} {} {}\n", q.x, q.y, q.z))
        .collect();
    std::fs::write(&queries_path, text)?;
    Ok(Dataset {
        name: name.into(),
        about,
        graph,
        path,
        queries,
        queries_path,
        real: false,
        full_sweep: true,
    })
}
