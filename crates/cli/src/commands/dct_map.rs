//! `raypath dct-map`: a continuous DCT decay-rate map (Schaefer 2020, ch. 9) beside a grid
//! decay-rate map with as many parameters, both built from the same rays of a CARMEN log
//! and scored on the same held-back rays.
//!
//! The rays of the log (SLAM-corrected poses, no-returns decoded per log by the reader) are
//! clipped to a `X × Y` patch (`--patch x0,y0,X,Y`, or `--patch auto`: the 10 m × 10 m
//! patch with the most ray path length), shuffled with `--seed`, and split into `--rays N`
//! mapping rays and 500 held-back rays. A DCT map of `--coefficients L,M` and an `L × M`
//! grid map are fitted; the ground truth is the 0.05 m grid map of the mapping rays.
//!
//! `--json` prints `{"time_s", "grid_time_s", "log_likelihood", "grid_log_likelihood",
//! "rmse_p_ref", "grid_rmse_p_ref", "iterations"}` plus `log`, `patch`, `coefficients`,
//! `rays`, `held_back_rays`, `seed`. `--out map.json` writes the coefficients, `--out
//! map.png` a picture of `p_ref = 1 − e^{−λ}` (4 px per 5 cm).

use std::path::PathBuf;

use raypath_dct_map::experiment::{GroundTruth, auto_patch, compare, draw_rays};
use raypath_dct_map::render::write_p_ref_png;
use raypath_dct_map::{FitConfig, Patch, RangeLimits, Shape};
use raypath_geometry::Ray2;
use raypath_io::carmen::{CarmenReader, Record};
use serde_json::json;

use super::Failure;

/// Held-back rays scored by both maps (Sec. 9.5.2).
const HELD_BACK: usize = 500;
/// Ground-truth cell edge (Sec. 9.5.1).
const TRUTH_CELL_M: f64 = 0.05;

/// Arguments of `raypath dct-map`.
#[derive(clap::Args)]
pub struct Args {
    /// A CARMEN log with corrected poses (plain, .gz or .bz2).
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
    /// Print one JSON document on standard output.
    #[arg(long)]
    pub json: bool,
}

fn parse_numbers(text: &str, n: usize, what: &str, json: bool) -> Result<Vec<f64>, Failure> {
    let values: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| Failure::input(format!("{what} {text:?}: {e}"), json))?;
    if values.len() != n || values.iter().any(|v| !v.is_finite()) {
        return Err(Failure::input(
            format!("{what} {text:?}: expected {n} finite comma-separated numbers"),
            json,
        ));
    }
    Ok(values)
}

fn read_rays(args: &Args) -> Result<Vec<Ray2>, Failure> {
    let reader = CarmenReader::open(&args.log).map_err(|e| Failure::input(e, args.json))?;
    let mut rays = Vec::new();
    for record in reader {
        if let Record::Laser(laser) = record.map_err(|e| Failure::input(e, args.json))? {
            rays.extend(laser.scan.rays(laser.world_from_laser));
        }
    }
    if rays.is_empty() {
        return Err(Failure::input(
            format!("{}: no laser scans", args.log.display()),
            args.json,
        ));
    }
    Ok(rays)
}

/// Runs the subcommand.
pub fn run(args: &Args) -> Result<(), Failure> {
    let json = args.json;
    let lm = parse_numbers(&args.coefficients, 2, "--coefficients", json)?;
    if lm
        .iter()
        .any(|v| v.fract() != 0.0 || *v < 1.0 || *v > 200.0)
    {
        return Err(Failure::input(
            format!(
                "--coefficients {:?}: L and M must be integers in 1..=200",
                args.coefficients
            ),
            json,
        ));
    }
    let shape = Shape {
        l: lm[0] as usize,
        m: lm[1] as usize,
    };
    if args.rays == 0 {
        return Err(Failure::input("--rays must be positive", json));
    }
    if let Some(out) = &args.out {
        let ext = out
            .extension()
            .map(|e| e.to_string_lossy().to_lowercase())
            .unwrap_or_default();
        if ext != "png" && ext != "json" {
            return Err(Failure::input(
                format!("--out {}: use a .json or .png file name", out.display()),
                json,
            ));
        }
    }
    let rays = read_rays(args)?;
    let patch = if args.patch == "auto" {
        auto_patch(&rays, 10.0).ok_or_else(|| {
            Failure::input(
                format!("{}: no rays to choose a patch from", args.log.display()),
                json,
            )
        })?
    } else {
        let v = parse_numbers(&args.patch, 4, "--patch", json)?;
        if v[2] <= 0.0 || v[3] <= 0.0 {
            return Err(Failure::input(
                format!("--patch {:?}: X and Y must be positive", args.patch),
                json,
            ));
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
        return Err(Failure::input(
            format!(
                "{}: no ray reaches the patch {:?}",
                args.log.display(),
                patch
            ),
            json,
        ));
    }
    let fail = |e: raypath_dct_map::DctError| Failure {
        message: e.to_string(),
        bad_input: false,
        json,
    };
    let [xe, ye] = patch.extent_m;
    let truth = GroundTruth::new(patch.extent_m, TRUTH_CELL_M, &mapping).map_err(fail)?;
    let (map, _grid, c) = compare(
        patch.extent_m,
        shape,
        &mapping,
        &held,
        &truth,
        &FitConfig::default(),
    )
    .map_err(fail)?;
    if let Some(out) = &args.out {
        write_map(out, &map, json)?;
    }
    if json {
        let doc = json!({
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
    }
    Ok(())
}

fn write_map(
    out: &std::path::Path,
    map: &raypath_dct_map::DctMap,
    json: bool,
) -> Result<(), Failure> {
    let ext = out
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    let io_fail = |e: String| Failure {
        message: format!("{}: {e}", out.display()),
        bad_input: false,
        json,
    };
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
        _ => Err(Failure::input(
            format!("--out {}: use a .json or .png file name", out.display()),
            json,
        )),
    }
}
