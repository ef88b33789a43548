//! `raypath dct-map`: a continuous DCT decay-rate map (Schaefer 2020, ch. 9) beside a grid
//! decay-rate map with as many parameters, both built from the same rays of a CARMEN log
//! (or a rosbag2 bag with reference poses) and scored on the same held-back rays.
//!
//! The scans are read through `raypath_io::sequence` (`--laser` picks the laser of a CARMEN
//! log, front by default; a bag's LaserScan topic at its reference poses, else at its logged
//! poses). Their rays (no-returns decoded per log by the reader) are clipped to a `X × Y`
//! patch (`--patch x0,y0,X,Y`, or `--patch auto`: the 10 m × 10 m patch with the most ray
//! path length), shuffled with `--seed`, and split into `--rays N` mapping rays and 500
//! held-back rays. A DCT map of `--coefficients L,M` and an `L × M` grid map are fitted; the
//! ground truth is the 0.05 m grid map of the mapping rays.
//!
//! `--json` prints `{"time_s", "grid_time_s", "log_likelihood", "grid_log_likelihood",
//! "rmse_p_ref", "grid_rmse_p_ref", "iterations"}` plus `log`, `patch`, `coefficients`,
//! `rays`, `held_back_rays`, `seed`. `--out map.json` writes the coefficients, `--out
//! map.png` a picture of `p_ref = 1 − e^{−λ}` (4 px per 5 cm).
//!
//! `--record OUT.mcap` writes a Foxglove recording (see `record`), stamped with the log's last
//! scan time: the fitted DCT map as the `FLOAT32` Grid `/map` of decay rates λ (1/m) at the
//! centres of 5 cm cells over the patch (coarser for patches over 50 m, at most 1000 cells a
//! side), the grid baseline as `/baseline` (λ per cell), and the reference poses of the scans
//! as `/trajectory`.

use std::path::PathBuf;

use raypath_dct_map::experiment::{GroundTruth, auto_patch, compare, draw_rays};
use raypath_dct_map::render::write_p_ref_png;
use raypath_dct_map::{DctMap, FitConfig, GridRateMap, Patch, RangeLimits, Shape};
use raypath_geometry::{Pose2, Ray2};
use raypath_io::foxglove::{GridLayer, GridValues, frame, topic};
use serde_json::json;

use super::Failure;
use super::record::{RecordArgs, Recording};
use super::source_args::{SourceArgs, reference_track};

/// Held-back rays scored by both maps (Sec. 9.5.2).
const HELD_BACK: usize = 500;
/// Ground-truth cell edge (Sec. 9.5.1).
const TRUTH_CELL_M: f64 = 0.05;

/// Arguments of `raypath dct-map`.
#[derive(clap::Args)]
pub struct Args {
    /// A CARMEN log with corrected poses (plain, .gz or .bz2), or a rosbag2 bag (directory
    /// with metadata.yaml, or .mcap file) with LaserScan and reference poses.
    pub log: PathBuf,
    /// The map region: `x0,y0,X,Y` in metres (world frame), or `auto`.
    #[arg(long, default_value = "auto", value_name = "x0,y0,X,Y|auto")]
    pub patch: String,
    /// Number of coefficients `L,M` along x and y (the grid map gets `L × M` cells).
    #[arg(long, value_name = "L,M")]
    pub coefficients: String,
    /// Number of mapping rays (the thesis: 10⁴).
    #[arg(long, default_value_t = 10_000, value_name = "N")]
    pub rays: usize,
    /// Seed of the ray draw.
    #[arg(long, default_value_t = 9, value_name = "S")]
    pub seed: u64,
    /// Write the map: `*.json` (coefficients) or `*.png` (p_ref picture).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// How to read the log.
    #[command(flatten)]
    pub source: SourceArgs,
    /// A Foxglove recording of the run.
    #[command(flatten)]
    pub record: RecordArgs,
}

/// The rays of the log (world frame), the reference poses of its scans and its last stamp.
struct Rays {
    rays: Vec<Ray2>,
    poses: Vec<Pose2>,
    last_stamp_secs: f64,
}

fn parse_numbers(text: &str, n: usize, what: &str) -> Result<Vec<f64>, Failure> {
    let values: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| Failure::input(format!("{what} {text:?}: {e}")))?;
    if values.len() != n || values.iter().any(|v| !v.is_finite()) {
        return Err(Failure::input(format!(
            "{what} {text:?}: expected {n} finite comma-separated numbers"
        )));
    }
    Ok(values)
}

/// The rays of every scan with a reference pose, in the world frame.
fn read_rays(args: &Args) -> Result<Rays, Failure> {
    let frames = args.source.read_frames(&args.log).map_err(Failure::input)?;
    let mut rays = Vec::new();
    let mut poses = Vec::new();
    for (frame, pose) in frames.iter().zip(reference_track(&frames)) {
        if let Some(pose) = pose {
            rays.extend(frame.scan.rays(pose));
            poses.push(pose);
        }
    }
    if rays.is_empty() {
        return Err(Failure::input(format!(
            "{}: no laser scans",
            args.log.display()
        )));
    }
    let last_stamp_secs = frames.iter().map(|f| f.stamp_secs).fold(0.0, f64::max);
    Ok(Rays {
        rays,
        poses,
        last_stamp_secs,
    })
}

/// Runs the subcommand.
pub fn run(args: &Args) -> Result<(), Failure> {
    let json = super::console::json();
    let lm = parse_numbers(&args.coefficients, 2, "--coefficients")?;
    if lm
        .iter()
        .any(|v| v.fract() != 0.0 || *v < 1.0 || *v > 200.0)
    {
        return Err(Failure::input(format!(
            "--coefficients {:?}: L and M must be integers in 1..=200",
            args.coefficients
        )));
    }
    let shape = Shape {
        l: lm[0] as usize,
        m: lm[1] as usize,
    };
    if args.rays == 0 {
        return Err(Failure::input("--rays must be positive"));
    }
    if let Some(out) = &args.out {
        let ext = out
            .extension()
            .map(|e| e.to_string_lossy().to_lowercase())
            .unwrap_or_default();
        if ext != "png" && ext != "json" {
            return Err(Failure::input(format!(
                "--out {}: use a .json or .png file name",
                out.display()
            )));
        }
    }
    let mut recording = Recording::open(&args.record)?;
    let Rays {
        rays,
        poses,
        last_stamp_secs,
    } = read_rays(args)?;
    let patch = if args.patch == "auto" {
        auto_patch(&rays, 10.0).ok_or_else(|| {
            Failure::input(format!(
                "{}: no rays to choose a patch from",
                args.log.display()
            ))
        })?
    } else {
        let v = parse_numbers(&args.patch, 4, "--patch")?;
        if v[2] <= 0.0 || v[3] <= 0.0 {
            return Err(Failure::input(format!(
                "--patch {:?}: X and Y must be positive",
                args.patch
            )));
        }
        Patch {
            min: [v[0], v[1]],
            extent_m: [v[2], v[3]],
        }
    };
    let (mapping, held) = draw_rays(
        &rays,
        &patch,
        &RangeLimits::default(),
        args.rays,
        HELD_BACK,
        args.seed,
    );
    if mapping.is_empty() {
        return Err(Failure::input(format!(
            "{}: no ray reaches the patch {:?}",
            args.log.display(),
            patch
        )));
    }
    let fail = |e: raypath_dct_map::DctError| Failure::internal(e.to_string());
    let [xe, ye] = patch.extent_m;
    let truth = GroundTruth::new(patch.extent_m, TRUTH_CELL_M, &mapping).map_err(fail)?;
    let spinner = super::console::spinner("fitting the DCT and grid maps");
    let (map, grid, c) = compare(
        patch.extent_m,
        shape,
        &mapping,
        &held,
        &truth,
        &FitConfig::default(),
    )
    .map_err(fail)?;
    spinner.finish_and_clear();
    if let Some(out) = &args.out {
        write_map(out, &map)?;
    }
    if let Some(recording) = &mut recording {
        record(recording, last_stamp_secs, &patch, &map, &grid, &poses)?;
    }
    if json {
        let mut doc = json!({
            "time_s": c.time_s,
            "grid_time_s": c.grid_time_s,
            "log_likelihood": c.log_likelihood,
            "grid_log_likelihood": c.grid_log_likelihood,
            "rmse_p_ref": c.rmse_p_ref,
            "grid_rmse_p_ref": c.grid_rmse_p_ref,
            "iterations": c.iterations,
            "log": args.log.display().to_string(),
            "patch": [patch.min[0], patch.min[1], xe, ye],
            "coefficients": [shape.l, shape.m],
            "rays": mapping.len(),
            "held_back_rays": held.len(),
            "seed": args.seed,
        });
        super::record::finish(recording, Some(&mut doc))?;
        println!("{doc}");
    } else {
        println!(
            "patch [{:.1}, {:.1}] + {xe} × {ye} m, {} mapping / {} held-back rays, {} × {} coefficients",
            patch.min[0],
            patch.min[1],
            mapping.len(),
            held.len(),
            shape.l,
            shape.m
        );
        println!("{:<22} {:>12} {:>12}", "", "DCT", "grid");
        println!(
            "{:<22} {:>12.4} {:>12.4}",
            "mapping time [s]", c.time_s, c.grid_time_s
        );
        println!(
            "{:<22} {:>12.2} {:>12.2}",
            "held-back log-lik.", c.log_likelihood, c.grid_log_likelihood
        );
        println!(
            "{:<22} {:>12.4} {:>12.4}",
            "RMSE p_ref", c.rmse_p_ref, c.grid_rmse_p_ref
        );
        println!("iterations: {}", c.iterations);
        super::record::finish(recording, None)?;
    }
    Ok(())
}

/// Most cells a side of the recorded DCT map lattice.
const MAX_RECORDED_SIDE: usize = 1000;

/// `--record`: the DCT map's rates on a lattice over the patch (`/map`), the grid baseline's
/// (`/baseline`), and the reference poses (`/trajectory`), all at `stamp`.
fn record(
    recording: &mut Recording,
    stamp: f64,
    patch: &Patch,
    map: &DctMap,
    grid: &GridRateMap,
    poses: &[Pose2],
) -> Result<(), Failure> {
    let [xe, ye] = map.extent_m();
    let cell = TRUTH_CELL_M.max(xe.max(ye) / MAX_RECORDED_SIDE as f64);
    let (nx, ny) = (
        ((xe / cell).round() as usize).max(1),
        ((ye / cell).round() as usize).max(1),
    );
    // `rates_on_lattice` is x-major (`ix · ny + iy`); a Grid is row by row (x fastest).
    let lattice = map.rates_on_lattice(nx, ny);
    let rates: Vec<f32> = (0..ny)
        .flat_map(|iy| (0..nx).map(move |ix| ix * ny + iy))
        .map(|k| lattice.get(k).map_or(f32::NAN, |&v| v as f32))
        .collect();
    let corner = Pose2::new(patch.min[0], patch.min[1], 0.0);
    let layer = GridLayer {
        frame_id: frame::MAP,
        origin: corner.to_pose3(),
        cell_size_m: xe / nx as f64,
        columns: nx,
        rows: ny,
        field: "decay_rate",
        values: GridValues::F32(&rates),
    };
    recording.grid_layer(topic::MAP, stamp, &layer)?;
    // The baseline's grid lies in the patch frame (origin at the patch's corner).
    let g = grid.grid();
    let baseline: Vec<f32> = grid.rates().iter().map(|&v| v as f32).collect();
    let [columns, rows] = g.dims();
    let layer = GridLayer {
        origin: Pose2::new(
            patch.min[0] + g.origin().x,
            patch.min[1] + g.origin().y,
            0.0,
        )
        .to_pose3(),
        cell_size_m: g.cell_size(),
        columns,
        rows,
        values: GridValues::F32(&baseline),
        ..layer
    };
    recording.grid_layer(topic::BASELINE, stamp, &layer)?;
    recording.planar_trajectory(topic::TRAJECTORY, stamp, poses)
}

fn write_map(out: &std::path::Path, map: &DctMap) -> Result<(), Failure> {
    let ext = out
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    let io_fail = |e: String| Failure::internal(format!("{}: {e}", out.display()));
    match ext.as_str() {
        "png" => {
            let [xe, ye] = map.extent_m();
            let (nx, ny) = (
                (xe / TRUTH_CELL_M).round() as usize,
                (ye / TRUTH_CELL_M).round() as usize,
            );
            let rates = map.rates_on_lattice(nx.max(1), ny.max(1));
            write_p_ref_png(out, &rates, nx.max(1), ny.max(1), 2)
                .map_err(|e| io_fail(e.to_string()))
        }
        "json" => {
            let text = serde_json::to_string_pretty(map).map_err(|e| io_fail(e.to_string()))?;
            std::fs::write(out, text).map_err(|e| io_fail(e.to_string()))
        }
        _ => Err(Failure::input(format!(
            "--out {}: use a .json or .png file name",
            out.display()
        ))),
    }
}
