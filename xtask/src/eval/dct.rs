//! `cargo xtask eval dct`: continuous DCT decay-rate maps against grid maps with as many
//! parameters on the real CARMEN logs (Schaefer 2020, Tables 9.2–9.4, Fig. 9.1).
//!
//! Per log: a seeded 10 m × 10 m patch among the most densely traversed ones, 10⁴ mapping
//! rays and 500 held-back rays drawn with a seed ([`raypath_dct_map::experiment`]), the
//! 0.05 m ground-truth grid from the mapping rays, and at each of 10², 13², 20², 29², 40²
//! parameters a DCT map and a grid map. Table 9.4 times the fit from 500 rays (the thesis'
//! timing set) and from 10⁴ rays; both solvers are timed side by side.
//!
//! The other two baselines of Sec. 9.5.2 have the same memory: a GPOM with n² training points
//! and a Hilbert map with n² Nyström components ([`raypath_dct_map::baselines`]), trained on
//! points sampled along the same mapping rays and scored on the held-back rays through a
//! 0.05 m raster (Table 9.3's DCT − GPOM and DCT − HM columns; their fit times beside Table
//! 9.4's t_GPOM and t_HM). As a control, the DCT map is also scored through that raster.
//! The headline (real logs) goes to the README's crate map.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use raypath_dct_map::baselines::{OccupancyRaster, RateAsOccupancy};
use raypath_dct_map::experiment::{
    BASELINE_PIXEL_M, Baseline, BaselineConfig, BaselineReport, GroundTruth, compare, draw_rays,
    fit_baseline, score_baseline, seeded_patch,
};
use raypath_dct_map::render::write_p_ref_png;
use raypath_dct_map::{
    FitConfig, FitProblem, GridRateMap, MapRay, Patch, RangeLimits, Shape, Solver, fit, initial_map,
};
use raypath_geometry::Ray2;
use raypath_io::sequence::{LaserChoice, PlanarOptions, read_planar};
use serde_json::json;

use super::{EvalContext, EvalReport, comparable};

mod report;
mod thesis;

use report::{headline, report_markdown};

const NAME: &str = "dct";
const PATCH_M: f64 = 10.0;
const MAPPING_RAYS: usize = 10_000;
const HELD_BACK: usize = 500;
const TIMING_RAYS: usize = 500;
const SEED: u64 = 9;
const HEAVY_FRACTION: f64 = 0.75;
const SIZES: [usize; 5] = [10, 13, 20, 29, 40];
const QUICK_SIZES: [usize; 2] = [13, 40];

/// One (log, size) result.
struct Cell {
    log: String,
    size: usize,
    rmse: f64,
    grid_rmse: f64,
    ll: f64,
    grid_ll: f64,
    time_s: f64,
    grid_time_s: f64,
    iterations: usize,
    time500_s: f64,
    grid_time500_s: f64,
    lbfgs_time_s: f64,
    lbfgs_ll: f64,
    newton_fit_s: f64,
    newton_train_ll: f64,
    worst_ray_ll: f64,
    grid_worst_ray_ll: f64,
    gpom: BaselineCell,
    hm: BaselineCell,
    /// The DCT map scored through the same raster as the baselines (`o = 1 − e^{−λ·0.05}`).
    dct_raster_ll: f64,
}

/// One occupancy baseline at one (log, size).
#[derive(Clone, Debug, Default)]
struct BaselineCell {
    /// Held-back log-likelihood on the 0.05 m raster.
    ll: f64,
    /// Fit time from the 10⁴ mapping rays (s).
    fit_s: f64,
    /// Raster prediction time (s).
    raster_s: f64,
    /// Fit time from the 500 timing rays (s).
    fit500_s: f64,
    /// What the fit chose (JSON).
    report: serde_json::Value,
}

fn report_json(report: &BaselineReport) -> serde_json::Value {
    match report {
        BaselineReport::Gpom(r) => json!({
            "training_points": r.training_points, "occupied": r.occupied,
            "length_scale_m": r.length_scale_m, "noise_std": r.noise_std,
            "log_marginal_likelihood": r.log_marginal_likelihood,
            "squash_scale": r.squash_scale, "squash_offset": r.squash_offset,
        }),
        BaselineReport::Hilbert(r) => json!({
            "components": r.components, "training_points": r.training_points,
            "iterations": r.iterations, "converged": r.converged, "objective": r.objective,
        }),
    }
}

/// Fits and scores one baseline at `n`² parameters; writes its occupancy PNG into `fig`.
#[allow(clippy::too_many_arguments)]
fn baseline_cell(
    which: Baseline,
    extent: [f64; 2],
    mapping: &[MapRay],
    held: &[MapRay],
    timing: &[MapRay],
    n: usize,
    fig: Option<(&Path, &str)>,
) -> Result<BaselineCell> {
    let config = BaselineConfig::default();
    let (score, report) = score_baseline(which, extent, mapping, held, n * n, &config, SEED)?;
    let (fit500_s, _, _) = fit_baseline(which, timing, n * n, &config, SEED)?;
    if let Some((dir, log)) = fig {
        let tag = match which {
            Baseline::Gpom => "gpom",
            Baseline::Hilbert => "hm",
        };
        // Occupancy shown as p_ref: the rate whose p_ref is o.
        let (o, nx, ny) = score.raster.lattice();
        let rates: Vec<f64> = o.iter().map(|o| -(-o).ln_1p()).collect();
        write_p_ref_png(
            &dir.join(format!("{log}-{tag}-{n}x{n}.png")),
            &rates,
            nx,
            ny,
            2,
        )?;
    }
    Ok(BaselineCell {
        ll: score.log_likelihood,
        fit_s: score.fit_s,
        raster_s: score.raster_s,
        fit500_s,
        report: report_json(&report),
    })
}

fn log_rays(path: &Path) -> Result<Vec<Ray2>> {
    let options = PlanarOptions {
        laser: LaserChoice::Front,
        ..PlanarOptions::default()
    };
    let mut rays = Vec::new();
    for frame in read_planar(path, &options)? {
        rays.extend(frame.scan.rays(frame.world_from_laser));
    }
    Ok(rays)
}

fn log_name(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    name.split("-corrected").next().unwrap_or(&name).to_owned()
}

/// Grid rates in the grid's linear order (x fastest) → lattice order `ix · ny + iy`.
fn grid_lattice(grid: &GridRateMap) -> (Vec<f64>, usize, usize) {
    let g = grid.grid();
    let [nx, ny] = g.dims();
    let mut out = vec![0.0; nx * ny];
    for ix in 0..nx {
        for iy in 0..ny {
            out[ix * ny + iy] = grid.rates()[g.linear_index([ix, iy])];
        }
    }
    (out, nx, ny)
}

fn timed_fit(
    extent: [f64; 2],
    shape: Shape,
    rays: &[MapRay],
    solver: Solver,
) -> Result<(f64, f64, f64)> {
    let start = Instant::now();
    let problem = FitProblem::new(extent, shape, rays)?;
    let init = initial_map(extent, shape, rays)?;
    let fit_start = Instant::now();
    let (_, report) = fit(
        &problem,
        init.coefficients(),
        &FitConfig {
            solver,
            ..FitConfig::default()
        },
    )?;
    Ok((
        start.elapsed().as_secs_f64(),
        fit_start.elapsed().as_secs_f64(),
        report.log_likelihood(),
    ))
}

fn run_log(
    ctx: &EvalContext,
    path: &Path,
    sizes: &[usize],
    figures: bool,
) -> Result<(Vec<Cell>, serde_json::Value)> {
    let name = log_name(path);
    let rays = log_rays(path).with_context(|| format!("reading {}", path.display()))?;
    let patch: Patch = seeded_patch(&rays, PATCH_M, HEAVY_FRACTION, SEED)
        .with_context(|| format!("{}: no patch", path.display()))?;
    let (mapping, held) = draw_rays(
        &rays,
        &patch,
        &RangeLimits::default(),
        MAPPING_RAYS,
        HELD_BACK,
        SEED,
    );
    let extent = patch.extent_m;
    let truth = GroundTruth::new(extent, 0.05, &mapping)?;
    let fig_dir = if figures {
        Some(ctx.figure_dir(NAME)?)
    } else {
        None
    };
    let mut cells = Vec::new();
    for &n in sizes {
        let shape = Shape { l: n, m: n };
        let (map, grid, c) = compare(
            extent,
            shape,
            &mapping,
            &held,
            &truth,
            &FitConfig::default(),
        )?;
        let timing = &mapping[..TIMING_RAYS.min(mapping.len())];
        let (time500, _, _) = timed_fit(extent, shape, timing, Solver::TrustRegionNewton)?;
        let start = Instant::now();
        let _ = GridRateMap::from_rays(PATCH_M / n as f64, [n, n], timing)?;
        let grid_time500 = start.elapsed().as_secs_f64();
        let (_, newton_fit_s, newton_ll) =
            timed_fit(extent, shape, &mapping, Solver::TrustRegionNewton)?;
        let (_, lbfgs_s, lbfgs_ll) = timed_fit(extent, shape, &mapping, Solver::Lbfgs)?;
        if let Some(dir) = &fig_dir {
            let rates = map.rates_on_lattice(200, 200);
            write_p_ref_png(
                &dir.join(format!("{name}-dct-{n}x{n}.png")),
                &rates,
                200,
                200,
                2,
            )?;
            let (g, nx, ny) = grid_lattice(&grid);
            write_p_ref_png(
                &dir.join(format!("{name}-grid-{n}x{n}.png")),
                &g,
                nx,
                ny,
                (400 / nx.max(1)) as u32,
            )?;
        }
        let fig = fig_dir
            .as_deref()
            .filter(|_| n == 13 || n == 40)
            .map(|d| (d, name.as_str()));
        let as_occupancy = RateAsOccupancy {
            rate_at: |p: [f64; 2]| map.rate_at(p),
            pixel_m: BASELINE_PIXEL_M,
        };
        let dct_raster_ll = OccupancyRaster::from_field(extent, BASELINE_PIXEL_M, &as_occupancy)?
            .log_likelihood(&held);
        let gpom = baseline_cell(Baseline::Gpom, extent, &mapping, &held, timing, n, fig)?;
        let hm = baseline_cell(Baseline::Hilbert, extent, &mapping, &held, timing, n, fig)?;
        let worst = |f: &dyn Fn(&MapRay) -> f64| held.iter().map(f).fold(f64::INFINITY, f64::min);
        let worst_ray_ll = worst(&|r| map.ray_log_likelihood(r));
        let grid_worst_ray_ll = worst(&|r| grid.ray_log_likelihood(r));
        cells.push(Cell {
            log: name.clone(),
            size: n,
            rmse: c.rmse_p_ref,
            grid_rmse: c.grid_rmse_p_ref,
            ll: c.log_likelihood,
            grid_ll: c.grid_log_likelihood,
            time_s: c.time_s,
            grid_time_s: c.grid_time_s,
            iterations: c.iterations,
            time500_s: time500,
            grid_time500_s: grid_time500,
            lbfgs_time_s: lbfgs_s,
            lbfgs_ll,
            newton_fit_s,
            newton_train_ll: newton_ll,
            worst_ray_ll,
            grid_worst_ray_ll,
            gpom,
            hm,
            dct_raster_ll,
        });
    }
    if let Some(dir) = &fig_dir {
        let (g, nx, ny) = grid_lattice(&truth.map);
        write_p_ref_png(
            &dir.join(format!("{name}-truth-200x200.png")),
            &g,
            nx,
            ny,
            2,
        )?;
    }
    let hits = mapping
        .iter()
        .filter(|r| r.outcome == raypath_dct_map::Outcome::Hit)
        .count();
    let info = json!({
        "log": name,
        "patch": [patch.min[0], patch.min[1], extent[0], extent[1]],
        "mapping_rays": mapping.len(),
        "mapping_hits": hits,
        "held_back_rays": held.len(),
        "truth_observed_cells": truth.points.len(),
    });
    Ok((cells, info))
}

/// Runs the evaluation.
pub fn run(ctx: &EvalContext) -> Result<EvalReport> {
    let dir = ctx.data("carmen/corrected");
    let mut logs: Vec<_> = std::fs::read_dir(&dir)
        .map(|d| {
            d.flatten()
                .map(|e| e.path())
                .filter(|p| p.to_string_lossy().ends_with("-corrected.log.gz"))
                .collect()
        })
        .unwrap_or_default();
    logs.sort();
    let sizes: &[usize] = if ctx.quick { &QUICK_SIZES } else { &SIZES };
    if ctx.quick {
        // The two smallest logs keep CI fast.
        logs.retain(|p| {
            let n = log_name(p);
            n == "aces" || n == "intel"
        });
    }
    let mut md = String::new();
    if logs.is_empty() {
        let _ = writeln!(
            md,
            "No corrected CARMEN logs under `{}` — skipped.",
            dir.display()
        );
        return Ok(EvalReport {
            name: NAME,
            title: "Continuous DCT decay-rate maps against grid maps (Tables 9.2-9.4)".into(),
            markdown: md,
            json: json!({ "status": "skipped: no data" }),
            headline: None,
        });
    }
    let load_before = load_average();
    let bar = ctx.progress(logs.len() as u64, NAME);
    let mut cells = Vec::new();
    let mut infos = Vec::new();
    for path in &logs {
        let figures = log_name(path) == "intel";
        let (c, info) = run_log(ctx, path, sizes, figures)?;
        cells.extend(c);
        infos.push(info);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let _ = writeln!(
        md,
        "Load average (1 min) of the machine: {load_before} at the start, {} at the end — other \
         evaluations ran at the same time, so absolute times are inflated; ratios within one row \
         were measured side by side.\n",
        load_average()
    );
    md.push_str(&report_markdown(ctx, &cells, &infos, sizes)?);
    let json_cells: Vec<_> = cells
        .iter()
        .map(|c| {
            json!({
                "log": c.log, "size": c.size, "rmse_p_ref": c.rmse, "grid_rmse_p_ref": c.grid_rmse,
                "log_likelihood": c.ll, "grid_log_likelihood": c.grid_ll, "time_s": c.time_s,
                "grid_time_s": c.grid_time_s, "iterations": c.iterations, "time_500_s": c.time500_s,
                "grid_time_500_s": c.grid_time500_s, "lbfgs_fit_s": c.lbfgs_time_s,
                "lbfgs_train_log_likelihood": c.lbfgs_ll, "newton_fit_s": c.newton_fit_s,
                "newton_train_log_likelihood": c.newton_train_ll,
                "worst_held_back_ray_log_likelihood": c.worst_ray_ll,
                "grid_worst_held_back_ray_log_likelihood": c.grid_worst_ray_ll,
                "gpom": baseline_json(&c.gpom), "hilbert_map": baseline_json(&c.hm),
                "dct_on_baseline_raster_log_likelihood": c.dct_raster_ll,
            })
        })
        .collect();
    Ok(EvalReport {
        name: NAME,
        title: "Continuous DCT decay-rate maps against grid maps (Tables 9.2-9.4)".into(),
        markdown: md,
        json: json!({ "logs": infos, "results": json_cells, "quick": ctx.quick, "threads": rayon::current_num_threads() }),
        headline: headline(&cells, sizes),
    })
}

fn baseline_json(b: &BaselineCell) -> serde_json::Value {
    json!({
        "held_back_log_likelihood": b.ll, "fit_s": b.fit_s, "raster_s": b.raster_s,
        "fit_500_s": b.fit500_s, "fit": b.report,
    })
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_owned))
        .unwrap_or_else(|| "n/a".into())
}
