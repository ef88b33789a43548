//! `raypath polylines`: maximum-likelihood polylines (PLE, PLE+; Schaefer 2020 ch. 10) or a
//! baseline (VVL, IEF, SAM) from the scans of a CARMEN log or a rosbag2 bag, in the scan
//! frame.
//!
//! The scans are read through `raypath_io::sequence`: the laser `--laser` of a CARMEN log
//! (front by default), or a bag's LaserScan topic; indices count these scans from 0.
//!
//! Prints per scan the vertices, the RMSE of the ray radii and the fraction `f` of reflected
//! rays the polylines explain; `--svg FILE` draws scan and polylines (one file per scan,
//! `FILE-<index>.svg` when several scans are selected).
//!
//! `--json` prints `{"scans": [{"index", "polylines": [[[x, y], …], …], "rmse", "f"}, …]}`
//! (scan entries carry exactly these contract keys; `rmse` is `null` when no ray hits the
//! polylines) plus the top-level keys `log`, `method`, `optimizer`, `max_vertices`,
//! `max_edge_m`, `removed_residual_m` and `closed` (per scan, per polyline: whether it is a
//! closed polygon, whose last vertex connects back to the first).
//!
//! `--record OUT.mcap` writes a Foxglove recording (see `record`): per processed scan, at its
//! stamp, `/tf` `map → base_link` (the logged robot pose), the `/scan` LaserScan in `base_link`
//! (with the laser's mounting) and its polylines as line strips (polygons as loops) on
//! `/polylines`, one entity that the next scan's replaces.

use std::path::{Path, PathBuf};

use raypath_io::foxglove::{frame, topic};
use raypath_io::sequence::PlanarFrame;
use raypath_polylines::metrics::ray_metrics;
use raypath_polylines::report::PolylinesReport;
use raypath_polylines::svg::scan_svg;
use raypath_polylines::{Method, Optimizer, PolylineConfig, Polylines, extract};

use super::Failure;
use super::record::{RecordArgs, Recording, polyline_entities};
use super::source_args::SourceArgs;

/// `--method`: the polyline extractor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// PLE: maximum-likelihood polylines (Schaefer 2020, ch. 10); PLE+ with `--optimize`.
    Ple,
    /// VVL baseline: Visvalingam line simplification.
    Vvl,
    /// IEF baseline: iterative end-point fit.
    Ief,
    /// SAM baseline: split-and-merge.
    Sam,
}

/// `--solver`: the vertex optimizer of PLE+.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SolverArg {
    /// Levenberg–Marquardt.
    Lm,
    /// Nelder–Mead, as the thesis.
    Nm,
}

/// Arguments of `raypath polylines`.
#[derive(clap::Args)]
pub struct Args {
    /// A CARMEN log (plain, .gz or .bz2), or a rosbag2 bag (directory with metadata.yaml, or
    /// .mcap file) with LaserScan.
    pub log: PathBuf,
    /// Comma-separated 0-based indices of the laser scans to process (default: the first).
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "I,J,…",
        conflicts_with = "all"
    )]
    pub scans: Vec<usize>,
    /// Process every scan of the log.
    #[arg(long)]
    pub all: bool,
    /// J_max: the largest number of vertices per scan.
    #[arg(long, default_value_t = 20, value_name = "J")]
    pub vertices: usize,
    /// Optimize the vertices after extraction (PLE+).
    #[arg(long)]
    pub optimize: bool,
    /// Extractor: PLE or a baseline. `--optimize` applies to ple.
    #[arg(long, value_enum, default_value_t = MethodArg::Ple, value_name = "NAME")]
    pub method: MethodArg,
    /// PLE+ solver.
    #[arg(long, value_enum, default_value_t = SolverArg::Lm, value_name = "NAME")]
    pub solver: SolverArg,
    /// l_max: longest edge between neighbouring endpoints, metres.
    #[arg(long, default_value_t = 1.0, value_name = "M")]
    pub max_edge: f64,
    /// d_rm: residual charged to rays of a removed end segment, metres.
    #[arg(long, default_value_t = 0.5, value_name = "M")]
    pub removed_residual: f64,
    /// Write an SVG picture of scan and polylines.
    #[arg(long, value_name = "FILE")]
    pub svg: Option<PathBuf>,
    /// How to read the log.
    #[command(flatten)]
    pub source: SourceArgs,
    /// A Foxglove recording of the run.
    #[command(flatten)]
    pub record: RecordArgs,
}

/// One processed scan.
struct Extracted {
    index: usize,
    map: Polylines,
    rmse_m: f64,
    f: f64,
}

fn config(args: &Args) -> Result<PolylineConfig, Failure> {
    let method = match (args.method, args.optimize) {
        (MethodArg::Ple, false) => Method::Ple,
        (MethodArg::Ple, true) => Method::PlePlus,
        (MethodArg::Vvl, false) => Method::Vvl,
        (MethodArg::Ief, false) => Method::Ief,
        (MethodArg::Sam, false) => Method::Sam,
        (other @ (MethodArg::Vvl | MethodArg::Ief | MethodArg::Sam), true) => {
            return Err(Failure::input(format!(
                "--optimize applies to ple only, not {}",
                super::choice_name(&other)
            )));
        }
    };
    let optimizer = match args.solver {
        SolverArg::Lm => Optimizer::LEVENBERG_MARQUARDT,
        SolverArg::Nm => Optimizer::NELDER_MEAD,
    };
    let config = PolylineConfig {
        method,
        max_vertices: args.vertices,
        max_edge_m: args.max_edge,
        removed_residual_m: args.removed_residual,
        optimizer,
        ..PolylineConfig::default()
    };
    config.validate().map_err(Failure::input)?;
    Ok(config)
}

/// The selected scans `(index, frame)`, read until the last one needed.
fn read_scans(args: &Args) -> Result<Vec<(usize, PlanarFrame)>, Failure> {
    let mut wanted: Vec<usize> = if args.scans.is_empty() {
        vec![0]
    } else {
        args.scans.clone()
    };
    wanted.sort_unstable();
    wanted.dedup();
    let last = wanted.last().copied().unwrap_or(0);
    let source = args.source.open_planar(&args.log).map_err(Failure::input)?;
    let mut scans = Vec::new();
    let mut index = 0usize;
    for frame in source {
        let frame = frame.map_err(Failure::input)?;
        if args.all || wanted.binary_search(&index).is_ok() {
            scans.push((index, frame));
        }
        index += 1;
        if !args.all && index > last {
            break;
        }
    }
    if !args.all && index <= last {
        return Err(Failure::input(format!(
            "{}: scan {last} requested, but the log has {index} laser scan(s)",
            args.log.display()
        )));
    }
    Ok(scans)
}

fn svg_path(base: &Path, index: usize, several: bool) -> PathBuf {
    if !several {
        return base.to_path_buf();
    }
    let stem = base
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "polylines".into());
    base.with_file_name(format!("{stem}-{index}.svg"))
}

/// Runs `raypath polylines`.
pub fn run(args: &Args) -> Result<(), Failure> {
    let config = config(args)?;
    let mut recording = Recording::open(&args.record)?;
    let scans = read_scans(args)?;
    let several = scans.len() > 1;
    let mut results = Vec::with_capacity(scans.len());
    let bar = super::console::progress(scans.len(), "polylines");
    for (index, frame) in &scans {
        bar.inc(1);
        let scan = &frame.scan;
        let place = || format!("{}: scan {index}", args.log.display());
        let map =
            extract(scan, &config).map_err(|e| Failure::input(format!("{}: {e}", place())))?;
        let m = ray_metrics(scan, &map).map_err(|e| Failure::input(format!("{}: {e}", place())))?;
        if let Some(base) = &args.svg {
            let path = svg_path(base, *index, several);
            std::fs::write(&path, scan_svg(scan, &map, 800.0))
                .map_err(|e| Failure::internal(format!("{}: {e}", path.display())))?;
        }
        if let Some(recording) = &mut recording {
            record(recording, frame, &map)?;
        }
        results.push(Extracted {
            index: *index,
            map,
            rmse_m: m.rmse_m,
            f: m.f,
        });
    }
    if super::console::json() {
        let mut doc = super::to_json(&report(args, &config, &results))?;
        super::record::finish(recording, Some(&mut doc))?;
        println!("{doc}");
    } else {
        print_text(args, &config, &results);
        super::record::finish(recording, None)?;
    }
    Ok(())
}

/// `--record`: the scan where it was logged and its polylines, in `base_link`.
fn record(recording: &mut Recording, frame: &PlanarFrame, map: &Polylines) -> Result<(), Failure> {
    let robot_from_laser = frame.robot_from_laser();
    recording.planar_scan(
        frame.stamp_secs,
        &frame.world_from_robot,
        &robot_from_laser,
        &frame.scan,
    )?;
    let entities = polyline_entities(map, &robot_from_laser, "polylines");
    recording.scene(
        topic::POLYLINES,
        frame.stamp_secs,
        frame::BASE_LINK,
        &entities,
    )
}

fn report(args: &Args, config: &PolylineConfig, results: &[Extracted]) -> PolylinesReport {
    let extracted: Vec<_> = results
        .iter()
        .map(|r| (r.index, &r.map, r.rmse_m, r.f))
        .collect();
    PolylinesReport::new(args.log.display().to_string(), config, &extracted)
}

fn print_text(args: &Args, config: &PolylineConfig, results: &[Extracted]) {
    println!(
        "{}: {} with at most {} vertices (l_max {} m, d_rm {} m){}",
        args.log.display(),
        config.method.name(),
        config.max_vertices,
        config.max_edge_m,
        config.removed_residual_m,
        if config.method == Method::PlePlus {
            format!(", solver {}", config.optimizer.name())
        } else {
            String::new()
        }
    );
    for r in results {
        let rmse = if r.rmse_m.is_finite() {
            format!("{:.1} mm", r.rmse_m * 1e3)
        } else {
            "—".into()
        };
        println!(
            "scan {}: {} vertices in {} polyline(s), RMSE {rmse}, f {:.3}",
            r.index,
            r.map.vertex_count(),
            r.map.lines.len(),
            r.f
        );
        for (i, line) in r.map.lines.iter().enumerate() {
            let points: Vec<String> = line
                .vertices
                .iter()
                .map(|v| format!("({:.3}, {:.3})", v.x, v.y))
                .collect();
            println!(
                "  {} {i}: {}",
                if line.closed { "polygon" } else { "polyline" },
                points.join(" ")
            );
        }
    }
}
