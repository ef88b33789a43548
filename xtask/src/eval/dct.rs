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
use crate::stats::{mean_std, paired_less};
use crate::table::{Table, fmt_num};

const NAME: &str = "dct";
const PATCH_M: f64 = 10.0;
const MAPPING_RAYS: usize = 10_000;
const HELD_BACK: usize = 500;
const TIMING_RAYS: usize = 500;
const SEED: u64 = 9;
const HEAVY_FRACTION: f64 = 0.75;
const SIZES: [usize; 5] = [10, 13, 20, 29, 40];
const QUICK_SIZES: [usize; 2] = [13, 40];

/// Thesis Table 9.2 (μ_DCT, σ_DCT, μ_GM, σ_GM, p %, Δ_μ %), Table 9.3 (DCT − GM μ, σ) and
/// Table 9.4 (t_DCT, t_GM in s), per size. Δ_μ of 13² is 5.21 = 1 − 0.3146 / 0.3319 from
/// the thesis' own μ; the thesis prints 0.52 there (see [`THESIS_PRINTED_DELTA_13`]).
/// `(size, μ_DCT, σ_DCT, μ_GM, σ_GM, p, Δ_μ, ΔLL μ, ΔLL σ, t_DCT, t_GM)`.
type ThesisRow = (usize, f64, f64, f64, f64, f64, f64, f64, f64, f64, f64);

const THESIS: [ThesisRow; 5] = [
    (
        10, 0.3314, 0.0679, 0.3330, 0.0708, 39.36, 0.48, 88.5, 74.1, 3.52, 0.0917,
    ),
    (
        13, 0.3146, 0.0675, 0.3319, 0.0752, 1.01, 5.21, 150.6, 146.5, 4.69, 0.0915,
    ),
    (
        20, 0.2932, 0.0645, 0.3093, 0.0690, 0.03, 5.21, 135.7, 63.9, 3.70, 0.0923,
    ),
    (
        29, 0.2571, 0.0611, 0.2822, 0.0672, 0.05, 8.89, 196.1, 101.5, 18.25, 0.0926,
    ),
    (
        40, 0.2370, 0.0563, 0.2543, 0.0583, 0.07, 6.80, 96.8, 132.0, 39.84, 0.0942,
    ),
];

/// Δ_μ [%] of the 13² row as printed in thesis Table 9.2 (0.52; its μ give 5.21).
const THESIS_PRINTED_DELTA_13: f64 = 0.52;

/// Thesis Table 9.3 (DCT − GPOM μ, σ and DCT − HM μ, σ, in nats; printed in units of 10⁴)
/// and Table 9.4 (t_GPOM, t_HM in s), per size:
/// `(size, GPOM μ, GPOM σ, HM μ, HM σ, t_GPOM, t_HM)`.
type ThesisBaselineRow = (usize, f64, f64, f64, f64, f64, f64);

const THESIS_BASELINES: [ThesisBaselineRow; 5] = [
    (10, 4.21e4, 3.00e4, 4.30e4, 3.42e4, 1.12, 22.8),
    (13, 3.89e4, 2.81e4, 4.19e4, 3.46e4, 1.98, 40.6),
    (20, 3.53e4, 2.60e4, 4.06e4, 3.42e4, 3.25, 108.4),
    (29, 2.97e4, 2.15e4, 4.12e4, 3.32e4, 6.45, 328.3),
    (40, 2.68e4, 1.90e4, 4.12e4, 3.31e4, 14.04, 949.3),
];

/// The 12 Radish logs of thesis Table 9.1, named as our corrected logs are.
const THESIS_LOGS: [&str; 12] = [
    "acapulco",
    "aces",
    "belgioioso",
    "csail",
    "edmonton",
    "fhw",
    "seattle",
    "freiburg-079",
    "freiburg-101",
    "infinite-corridor",
    "intel",
    "orebro",
];

/// Our logs beside the thesis' 12 (for the "comparable" cells): how many of its logs, which
/// are absent, which of ours it did not use.
fn logs_text(logs: &[&str]) -> String {
    let (ours, absent, extra) = comparable::log_overlap(logs, &THESIS_LOGS);
    let mut text = format!("real Radish logs in both, {ours} of the thesis' 12");
    if !absent.is_empty() {
        text.push_str(&format!(" (absent: {})", absent.join(", ")));
    }
    if !extra.is_empty() {
        text.push_str(&format!(" plus {} (not in the thesis)", extra.join(", ")));
    }
    text
}

/// The "comparable" cell of a Table 9.2 row of `n`² parameters.
fn rmse_comparable(logs: &str, n: usize) -> String {
    let printed = if n == 13 {
        format!("; thesis Δ_μ printed as {THESIS_PRINTED_DELTA_13}, bracket recomputed from its μ")
    } else {
        String::new()
    };
    comparable::no(&format!(
        "{logs}; our seeded patch per log; same sizes, 10⁴ rays, 0.05 m truth and p_ref \
         RMSE{printed}"
    ))
}

/// The "comparable" cell of a Table 9.3 row.
fn likelihood_comparable(logs: &str) -> String {
    comparable::no(&format!(
        "other protocol: ours = {HELD_BACK} held-back rays under maps from {MAPPING_RAYS} rays, \
         thesis = the 500 rays that built the maps; {logs}"
    ))
}

/// The "comparable" cell of a GPOM / Hilbert-map row of Table 9.3.
fn baseline_likelihood_comparable(logs: &str) -> String {
    comparable::no(&format!(
        "our re-implementations with our hyperparameters (GPOM: Matérn 3/2, (ℓ, σ_n) by marginal \
         likelihood on a grid; HM: Nyström RBF γ = 1 /m², L2 logistic regression by L-BFGS), not \
         Jadidi's GPML code and Ott's Python with the thesis' unlisted settings; other protocol: \
         ours = {HELD_BACK} held-back rays under maps from {MAPPING_RAYS} rays, thesis = the 500 \
         rays that built the maps; same {BASELINE_PIXEL_M} m raster; {logs}"
    ))
}

/// The "comparable" cell of a GPOM / Hilbert-map row of Table 9.4.
const BASELINE_TIME_COMPARABLE: &str = "no — other language, hardware and implementation: thesis \
     GPOM in MATLAB/GPML and Hilbert maps in Python (SGD; the thesis blames finite differences) \
     on an i7-2600K, medians of 10-run means; ours our own Rust re-implementations (HM by \
     L-BFGS with an analytic gradient), one run, on 2 shared, loaded cores";

/// The "comparable" cell of a Table 9.4 row.
const TIME_COMPARABLE: &str = "no — other language and hardware: thesis MATLAB R2017b on an \
     Intel i7-2600K (3.4 GHz), medians of 10-run means; ours Rust, one run, on 2 shared, loaded \
     cores";

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

/// The page's headline (real logs only): held-back log-likelihood DCT − grid over the sizes,
/// RMSE and the 500-ray fit time at the largest size, and the GPOM / Hilbert-map gaps.
fn headline(cells: &[Cell], sizes: &[usize]) -> Option<String> {
    let (&small, &large) = (sizes.first()?, sizes.last()?);
    let at = |n: usize, f: &dyn Fn(&Cell) -> f64| -> Vec<f64> {
        cells.iter().filter(|c| c.size == n).map(f).collect()
    };
    // Min and max over sizes of the mean over logs.
    let range = |f: &dyn Fn(&Cell) -> f64| {
        sizes
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &n| {
                let m = mean_std(&at(n, f)).0;
                (lo.min(m), hi.max(m))
            })
    };
    let logs = at(large, &|_| 0.0).len();
    if logs == 0 {
        return None;
    }
    let (g_lo, g_hi) = range(&|c| c.ll - c.grid_ll);
    let above = at(large, &|c| c.ll - c.grid_ll)
        .iter()
        .filter(|d| **d > 0.0)
        .count();
    let (gp_lo, gp_hi) = range(&|c| c.ll - c.gpom.ll);
    let (hm_lo, hm_hi) = range(&|c| c.ll - c.hm.ll);
    let thesis = THESIS.iter().find(|t| t.0 == large);
    let tb = |f: &dyn Fn(&ThesisBaselineRow) -> f64| {
        let v: Vec<f64> = THESIS_BASELINES
            .iter()
            .filter(|t| sizes.contains(&t.0))
            .map(f)
            .collect();
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min) / 1e4;
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max) / 1e4;
        format!("{lo:.2}–{hi:.2}·10⁴")
    };
    Some(format!(
        "Real CARMEN logs ({logs}, one seeded 10 m × 10 m patch each, {MAPPING_RAYS} mapping and \
         {HELD_BACK} held-back rays): held-back log-likelihood DCT − grid with as many parameters \
         {g_lo:+.0} to {g_hi:+.0} nats per log (means over logs, {small}²–{large}²; DCT higher on \
         {above}/{logs} logs at {large}²); RMSE of p_ref at {large}²: DCT {:.3}, grid {:.3}{}. A \
         {large}² map from 500 rays in {:.2} s{} (not like for like — hardware/language: Rust \
         on 2 shared cores vs MATLAB on an i7-2600K). GPOM and Hilbert maps with as many \
         parameters (our re-implementations, 0.05 m raster) trail the DCT map by \
         {:.2}–{:.2}·10⁴ and {:.2}–{:.2}·10⁴ nats (thesis {} and {}).",
        mean_std(&at(large, &|c| c.rmse)).0,
        mean_std(&at(large, &|c| c.grid_rmse)).0,
        thesis.map_or(String::new(), |t| format!(
            " (thesis {:.3}, {:.3})",
            t.1, t.3
        )),
        median(at(large, &|c| c.time500_s)),
        thesis.map_or(String::new(), |t| format!(" vs the thesis' {:.2} s", t.9)),
        gp_lo / 1e4,
        gp_hi / 1e4,
        hm_lo / 1e4,
        hm_hi / 1e4,
        tb(&|t| t.1),
        tb(&|t| t.3),
    ))
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

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    if v.is_empty() {
        return f64::NAN;
    }
    let k = v.len();
    if k % 2 == 1 {
        v[k / 2]
    } else {
        0.5 * (v[k / 2 - 1] + v[k / 2])
    }
}

fn report_markdown(
    ctx: &EvalContext,
    cells: &[Cell],
    infos: &[serde_json::Value],
    sizes: &[usize],
) -> Result<String> {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "Schaefer (2020) ch. 9 / spec §5.6. Per log: one 10 m × 10 m patch drawn with seed {SEED} \
         among the candidate patches (1 m lattice of corners) with at least {:.0} % of the largest \
         ray path length; all rays reaching it are clipped to it, shuffled (ChaCha8, seed {SEED}); \
         the first {MAPPING_RAYS} build the maps, the next {HELD_BACK} are held back. Ground truth: \
         the 0.05 m decay-rate grid (200 × 200) of the mapping rays, compared at its observed cells. \
         DCT maps: trust-region Newton from the grid map of the same size, stop at relative \
         log-likelihood change < 1e-3 (thesis). Grid maps: λ = H/R (ch. 7) with L × L cells. \
         {} threads; times are wall times on a shared, loaded 2-core machine (release build).{}\n",
        HEAVY_FRACTION * 100.0,
        rayon::current_num_threads(),
        if ctx.quick {
            " **Quick run: 2 logs, 2 sizes.**"
        } else {
            ""
        }
    );
    let _ = writeln!(md, "## Data\n");
    let mut t = Table::new([
        "log",
        "patch x0, y0 [m]",
        "mapping rays (hits)",
        "held back",
        "observed GT cells",
    ]);
    for i in infos {
        let p = &i["patch"];
        t.row([
            i["log"].as_str().unwrap_or("").to_string(),
            format!("{}, {}", p[0], p[1]),
            format!("{} ({})", i["mapping_rays"], i["mapping_hits"]),
            i["held_back_rays"].to_string(),
            i["truth_observed_cells"].to_string(),
        ]);
    }
    md.push_str(&t.to_markdown()?);
    let thesis = |n: usize| THESIS.iter().find(|t| t.0 == n);
    let mut logs: Vec<&str> = Vec::new();
    for c in cells {
        if !logs.contains(&c.log.as_str()) {
            logs.push(&c.log);
        }
    }
    let logs = logs_text(&logs);

    let _ = writeln!(
        md,
        "\n## Table 9.2 — RMSE of p_ref against the ground truth\n"
    );
    let _ = writeln!(
        md,
        "Mean μ and standard deviation σ over logs; p: one-sided paired t-test (H1: RMSE_DCT < RMSE_GM); \
         Δ_μ = 1 − μ_DCT / μ_GM. Thesis values (12 Radish logs) in brackets.\n"
    );
    let mut t = Table::new([
        "params",
        "l [m]",
        "DCT μ",
        "DCT σ",
        "GM μ",
        "GM σ",
        "p [%]",
        "Δ_μ [%]",
        "DCT wins",
        comparable::HEADER,
    ]);
    for &n in sizes {
        let d: Vec<f64> = cells
            .iter()
            .filter(|c| c.size == n)
            .map(|c| c.rmse)
            .collect();
        let g: Vec<f64> = cells
            .iter()
            .filter(|c| c.size == n)
            .map(|c| c.grid_rmse)
            .collect();
        let (dm, ds) = mean_std(&d);
        let (gm, gs) = mean_std(&g);
        let p = paired_less(&d, &g) * 100.0;
        let wins = d.iter().zip(&g).filter(|(a, b)| a < b).count();
        let th = thesis(n);
        let br = |v: f64, th: Option<f64>, dec: usize| match th {
            Some(x) => format!("{} ({})", fmt_num(v, dec), fmt_num(x, dec)),
            None => fmt_num(v, dec),
        };
        t.row([
            format!("{n}²"),
            format!("{:.3}", PATCH_M / n as f64),
            br(dm, th.map(|t| t.1), 4),
            br(ds, th.map(|t| t.2), 4),
            br(gm, th.map(|t| t.3), 4),
            br(gs, th.map(|t| t.4), 4),
            br(p, th.map(|t| t.5), 2),
            br((1.0 - dm / gm) * 100.0, th.map(|t| t.6), 2),
            format!("{wins}/{}", d.len()),
            rmse_comparable(&logs, n),
        ]);
    }
    md.push_str(&t.to_markdown()?);

    let _ = writeln!(
        md,
        "\n## Table 9.3 — log-likelihood of the held-back rays, DCT − grid\n"
    );
    let _ = writeln!(
        md,
        "Sum of the natural-log likelihoods of the {HELD_BACK} held-back rays of each log under the \
         maps from the {MAPPING_RAYS} mapping rays; mean and σ over logs of DCT − GM; p: one-sided \
         paired t-test (H1: DCT higher). Thesis (DCT − GM) in brackets.\n"
    );
    let mut t = Table::new([
        "params",
        "DCT − GM μ",
        "DCT − GM σ",
        "DCT − GM median",
        "p [%]",
        "DCT higher",
        comparable::HEADER,
    ]);
    for &n in sizes {
        let d: Vec<f64> = cells
            .iter()
            .filter(|c| c.size == n)
            .map(|c| c.ll - c.grid_ll)
            .collect();
        let neg: Vec<f64> = d.iter().map(|v| -v).collect();
        let zeros = vec![0.0; d.len()];
        let (m, s) = mean_std(&d);
        let th = thesis(n);
        t.row([
            format!("{n}²"),
            format!(
                "{} ({})",
                fmt_num(m, 1),
                th.map(|t| fmt_num(t.7, 1)).unwrap_or_default()
            ),
            format!(
                "{} ({})",
                fmt_num(s, 1),
                th.map(|t| fmt_num(t.8, 1)).unwrap_or_default()
            ),
            fmt_num(median(d.clone()), 1),
            fmt_num(paired_less(&neg, &zeros) * 100.0, 2),
            format!("{}/{}", d.iter().filter(|v| **v > 0.0).count(), d.len()),
            likelihood_comparable(&logs),
        ]);
    }
    md.push_str(&t.to_markdown()?);
    md.push_str(&baseline_likelihood_table(cells, sizes, &logs)?);

    let _ = writeln!(md, "\n## Table 9.4 — mapping time [s], median over logs\n");
    let _ = writeln!(
        md,
        "t_DCT(500): the whole DCT mapping (moments, initialization, fit) from {TIMING_RUNS_TEXT}; \
         the thesis timed its 500-ray sets in MATLAB on an i7-2600K. t_DCT(10⁴): the same from the \
         {MAPPING_RAYS} mapping rays. Fit-only times of the two solvers on the 10⁴ rays, side by side, \
         with the training log-likelihood they reach.\n",
    );
    let mut t = Table::new([
        "params",
        "t_DCT(500)",
        "thesis t_DCT",
        "speed-up",
        "t_GM(500)",
        "thesis t_GM",
        "t_DCT(10⁴)",
        "t_GM(10⁴)",
        "Newton fit",
        "L-BFGS fit",
        "LL L-BFGS − Newton",
        "Newton iterations",
        comparable::HEADER,
    ]);
    for &n in sizes {
        let sel: Vec<&Cell> = cells.iter().filter(|c| c.size == n).collect();
        let med = |f: &dyn Fn(&Cell) -> f64| median(sel.iter().map(|c| f(c)).collect());
        let th = thesis(n);
        let t500 = med(&|c| c.time500_s);
        t.row([
            format!("{n}²"),
            fmt_num(t500, 3),
            th.map(|t| fmt_num(t.9, 2)).unwrap_or_default(),
            th.map(|t| format!("{:.0}×", t.9 / t500))
                .unwrap_or_default(),
            fmt_num(med(&|c| c.grid_time500_s), 4),
            th.map(|t| fmt_num(t.10, 4)).unwrap_or_default(),
            fmt_num(med(&|c| c.time_s), 3),
            fmt_num(med(&|c| c.grid_time_s), 4),
            fmt_num(med(&|c| c.newton_fit_s), 3),
            fmt_num(med(&|c| c.lbfgs_time_s), 3),
            fmt_num(med(&|c| c.lbfgs_ll - c.newton_train_ll), 1),
            fmt_num(med(&|c| c.iterations as f64), 0),
            TIME_COMPARABLE.to_owned(),
        ]);
    }
    md.push_str(&t.to_markdown()?);
    md.push_str(&baseline_time_table(cells, sizes)?);

    let _ = writeln!(md, "\n## Per log\n");
    let mut t = Table::new([
        "log",
        "params",
        "RMSE DCT",
        "RMSE GM",
        "LL DCT",
        "LL GM",
        "worst-ray LL DCT",
        "worst-ray LL GM",
        "LL GPOM",
        "LL HM",
        "t_DCT(10⁴) [s]",
        "iterations",
    ]);
    for c in cells {
        t.row([
            c.log.clone(),
            format!("{}²", c.size),
            fmt_num(c.rmse, 4),
            fmt_num(c.grid_rmse, 4),
            fmt_num(c.ll, 1),
            fmt_num(c.grid_ll, 1),
            fmt_num(c.worst_ray_ll, 1),
            fmt_num(c.grid_worst_ray_ll, 1),
            fmt_num(c.gpom.ll, 1),
            fmt_num(c.hm.ll, 1),
            fmt_num(c.time_s, 3),
            c.iterations.to_string(),
        ]);
    }
    md.push_str(&t.to_markdown()?);
    if cells.iter().any(|c| c.log == "intel") {
        let _ = writeln!(md, "\n## Fig. 9.1 — Intel Research Lab patch\n");
        let _ = writeln!(
            md,
            "p_ref = 1 − exp(−λ) for the decay-rate maps, the occupancy probability (clamped to \
             [0.001, 0.999], on the 0.05 m raster) for GPOM and the Hilbert map (as Fig. 9.2); blue \
             0, green 0.5, yellow 1. DCT map, grid map, GPOM and Hilbert map with as many \
             parameters, and the 0.05 m ground truth.\n"
        );
        for &n in sizes.iter().filter(|n| **n == 13 || **n == 40) {
            let _ = writeln!(
                md,
                "| DCT {n}×{n} | grid {n}×{n} | GPOM, {n}² points | Hilbert map, {n}² components | ground truth 200×200 |\n|---|---|---|---|---|\n| ![](dct/intel-dct-{n}x{n}.png) | ![](dct/intel-grid-{n}x{n}.png) | ![](dct/intel-gpom-{n}x{n}.png) | ![](dct/intel-hm-{n}x{n}.png) | ![](dct/intel-truth-200x200.png) |\n"
            );
        }
    }
    Ok(md)
}

/// `ours (thesis)` with the thesis figure in units of 10⁴ as printed.
fn beside_1e4(ours: f64, thesis: Option<f64>) -> String {
    match thesis {
        Some(t) => format!("{} ({:.2}·10⁴)", fmt_num(ours, 1), t / 1e4),
        None => fmt_num(ours, 1),
    }
}

/// Table 9.3's GPOM and Hilbert-map columns: held-back log-likelihood differences.
fn baseline_likelihood_table(cells: &[Cell], sizes: &[usize], logs: &str) -> Result<String> {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "\n## Table 9.3 (cont.) — held-back log-likelihood, DCT − GPOM and DCT − Hilbert map\n"
    );
    let _ = writeln!(
        md,
        "The same {HELD_BACK} held-back rays under a GPOM with n² training points and a Hilbert \
         map with n² Nyström components, both from the {MAPPING_RAYS} mapping rays (training points: \
         every return's end point occupied, free points along the beam; `raypath_dct_map::baselines`), \
         rasterized on {BASELINE_PIXEL_M} m pixels and scored by the reflection model (occupancy \
         as reflection probability, density = mass / chord; occupancy clamped to [0.001, 0.999]). \
         Mean and σ over logs of DCT − other, in nats; thesis (printed in units of 10⁴) in brackets. \
         Control: the DCT map itself scored through the same raster (o = 1 − e^{{−λ · 0.05 m}}, \
         the reflection probability of a 0.05 m subvoxel, Eq. 7.27; so λ is clamped to \
         0.02–138 /m) — what the raster scoring costs a map that has no classifier in it.\n"
    );
    let mut t = Table::new([
        "params",
        "DCT − GPOM μ",
        "DCT − GPOM σ",
        "DCT > GPOM",
        "DCT − HM μ",
        "DCT − HM σ",
        "DCT > HM",
        "GM − GPOM μ",
        "GM − HM μ",
        "DCT on the raster − DCT μ",
        comparable::HEADER,
    ]);
    for &n in sizes {
        let sel: Vec<&Cell> = cells.iter().filter(|c| c.size == n).collect();
        let th = THESIS_BASELINES.iter().find(|t| t.0 == n);
        let diff = |f: &dyn Fn(&Cell) -> f64| -> Vec<f64> { sel.iter().map(|c| f(c)).collect() };
        let d_gpom = diff(&|c| c.ll - c.gpom.ll);
        let d_hm = diff(&|c| c.ll - c.hm.ll);
        let higher = |d: &[f64]| format!("{}/{}", d.iter().filter(|v| **v > 0.0).count(), d.len());
        let (gm, gs) = mean_std(&d_gpom);
        let (hm, hs) = mean_std(&d_hm);
        t.row([
            format!("{n}²"),
            beside_1e4(gm, th.map(|t| t.1)),
            beside_1e4(gs, th.map(|t| t.2)),
            higher(&d_gpom),
            beside_1e4(hm, th.map(|t| t.3)),
            beside_1e4(hs, th.map(|t| t.4)),
            higher(&d_hm),
            fmt_num(mean_std(&diff(&|c| c.grid_ll - c.gpom.ll)).0, 1),
            fmt_num(mean_std(&diff(&|c| c.grid_ll - c.hm.ll)).0, 1),
            fmt_num(mean_std(&diff(&|c| c.dct_raster_ll - c.ll)).0, 1),
            baseline_likelihood_comparable(logs),
        ]);
    }
    md.push_str(&t.to_markdown()?);
    Ok(md)
}

/// Table 9.4's GPOM and Hilbert-map columns: mapping times.
fn baseline_time_table(cells: &[Cell], sizes: &[usize]) -> Result<String> {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "\n## Table 9.4 (cont.) — GPOM and Hilbert-map mapping time [s], median over logs\n"
    );
    let _ = writeln!(
        md,
        "t(500): training points from the first 500 mapping rays, hyperparameters and fit (GPOM: \
         marginal-likelihood grid over 4 × 3 (ℓ, σ_n), Cholesky, squashing calibration; HM: \
         Nyström factor and L-BFGS), as the thesis timed its 500-ray sets; at 500 rays there are \
         fewer training points than 40² parameters, so GPOM and HM use all of them. t(10⁴): the \
         same from the {MAPPING_RAYS} mapping rays (the maps of Table 9.3). Raster: predicting the \
         200 × 200 pixels, not part of t. ℓ, σ_n: GPOM's most frequent choice.\n"
    );
    let mut t = Table::new([
        "params",
        "t_GPOM(500)",
        "thesis t_GPOM",
        "t_HM(500)",
        "thesis t_HM",
        "t_GPOM(10⁴)",
        "t_HM(10⁴)",
        "raster GPOM",
        "raster HM",
        "GPOM ℓ, σ_n",
        "HM L-BFGS iterations",
        comparable::HEADER,
    ]);
    for &n in sizes {
        let sel: Vec<&Cell> = cells.iter().filter(|c| c.size == n).collect();
        let med = |f: &dyn Fn(&Cell) -> f64| median(sel.iter().map(|c| f(c)).collect());
        let th = THESIS_BASELINES.iter().find(|t| t.0 == n);
        t.row([
            format!("{n}²"),
            fmt_num(med(&|c| c.gpom.fit500_s), 3),
            th.map(|t| fmt_num(t.5, 2)).unwrap_or_default(),
            fmt_num(med(&|c| c.hm.fit500_s), 3),
            th.map(|t| fmt_num(t.6, 1)).unwrap_or_default(),
            fmt_num(med(&|c| c.gpom.fit_s), 3),
            fmt_num(med(&|c| c.hm.fit_s), 3),
            fmt_num(med(&|c| c.gpom.raster_s), 3),
            fmt_num(med(&|c| c.hm.raster_s), 3),
            most_frequent_hyperparameters(&sel),
            fmt_num(
                med(&|c| c.hm.report["iterations"].as_f64().unwrap_or(f64::NAN)),
                0,
            ),
            BASELINE_TIME_COMPARABLE.to_owned(),
        ]);
    }
    md.push_str(&t.to_markdown()?);
    Ok(md)
}

/// GPOM's most frequent `(ℓ, σ_n)` over the cells, with its count.
fn most_frequent_hyperparameters(cells: &[&Cell]) -> String {
    let mut counts: Vec<(String, usize)> = Vec::new();
    for c in cells {
        let r = &c.gpom.report;
        let key = match (r["length_scale_m"].as_f64(), r["noise_std"].as_f64()) {
            (Some(l), Some(s)) => format!("{l} m, {s}"),
            _ => continue,
        };
        match counts.iter_mut().find(|(k, _)| *k == key) {
            Some((_, n)) => *n += 1,
            None => counts.push((key, 1)),
        }
    }
    counts
        .iter()
        .max_by_key(|(_, n)| *n)
        .map(|(k, n)| format!("{k} ({n}/{})", cells.len()))
        .unwrap_or_default()
}

const TIMING_RUNS_TEXT: &str = "the first 500 mapping rays (one run)";

#[cfg(test)]
mod tests {
    use super::*;

    fn cell(log: &str, size: usize, k: f64) -> Cell {
        Cell {
            log: log.to_owned(),
            size,
            rmse: 0.2 + 0.01 * k,
            grid_rmse: 0.25,
            ll: -100.0 + k,
            grid_ll: -150.0,
            time_s: 0.1,
            grid_time_s: 0.001,
            iterations: 4,
            time500_s: 0.01,
            grid_time500_s: 0.0001,
            lbfgs_time_s: 0.2,
            lbfgs_ll: -101.0,
            newton_fit_s: 0.05,
            newton_train_ll: -100.0,
            worst_ray_ll: -5.0,
            grid_worst_ray_ll: -6.0,
            gpom: BaselineCell {
                ll: -20_000.0 - 100.0 * k,
                fit_s: 0.5,
                raster_s: 2.0,
                fit500_s: 0.1,
                report: json!({"length_scale_m": 0.5, "noise_std": 0.3}),
            },
            hm: BaselineCell {
                ll: -9000.0,
                fit_s: 3.0,
                raster_s: 0.4,
                fit500_s: 0.2,
                report: json!({"iterations": 80}),
            },
            dct_raster_ll: -110.0,
        }
    }

    /// The report renders from a small known input (every row has the header's cell count)
    /// and each table beside the thesis says why it does not compare.
    #[test]
    fn tables_beside_the_thesis_say_what_compares() {
        let ctx = EvalContext {
            workspace_root: crate::eval::workspace_root(),
            data_dir: std::env::temp_dir().join("raypath-dct-test-absent-data"),
            quick: true,
        };
        let cells: Vec<Cell> = ["intel", "freiburg-campus", "aces"]
            .iter()
            .enumerate()
            .flat_map(|(k, log)| [cell(log, 13, k as f64), cell(log, 40, k as f64)])
            .collect();
        let md = report_markdown(&ctx, &cells, &[], &[13, 40]).expect("report renders");
        for section in [
            "## Table 9.2",
            "## Table 9.3",
            "## Table 9.3 (cont.)",
            "## Table 9.4",
            "## Table 9.4 (cont.)",
        ] {
            let body = md.split(section).nth(1).expect(section);
            let header = body.lines().find(|l| l.starts_with("| params")).unwrap();
            assert_eq!(comparable::last_cell(header), "comparable", "{header}");
            let row = body.lines().find(|l| l.starts_with("| 13²")).unwrap();
            assert!(row.contains("| no — "), "{row}");
        }
        let table_92 = md.split("## Table 9.2").nth(1).unwrap();
        let row_13 = table_92.lines().find(|l| l.starts_with("| 13²")).unwrap();
        assert!(row_13.contains("printed as 0.52"), "{row_13}");
        assert!(row_13.contains("2 of the thesis' 12"), "{row_13}");
        assert!(
            row_13.contains("freiburg-campus (not in the thesis)"),
            "{row_13}"
        );
        let row_40 = table_92.lines().find(|l| l.starts_with("| 40²")).unwrap();
        assert!(!row_40.contains("printed as"), "{row_40}");
        assert!(md.contains("thesis = the 500 rays that built the maps"));
        // The baseline rows: DCT − GPOM = −100 − (−20 000) + 0 = 19 900 for log 0, … (mean
        // 19 900 + 101 k̄ = 20 001), beside the thesis' 10⁴ figures, and honest about code.
        let cont = md.split("## Table 9.3 (cont.)").nth(1).unwrap();
        let row = cont.lines().find(|l| l.starts_with("| 13²")).unwrap();
        assert!(row.contains("20001.0 (3.89·10⁴)"), "{row}");
        assert!(row.contains("our re-implementations"), "{row}");
        let times = md.split("## Table 9.4 (cont.)").nth(1).unwrap();
        let row = times.lines().find(|l| l.starts_with("| 40²")).unwrap();
        assert!(row.contains("| 14.04 "), "{row}");
        assert!(row.contains("0.5 m, 0.3 (3/3)"), "{row}");
        assert!(
            row.contains("other language, hardware and implementation"),
            "{row}"
        );
    }

    /// The headline states the real-log figures, the time with its caveat and the baselines.
    #[test]
    fn headline_from_known_cells() {
        let cells: Vec<Cell> = ["intel", "aces"]
            .iter()
            .enumerate()
            .flat_map(|(k, log)| [cell(log, 13, k as f64), cell(log, 40, k as f64)])
            .collect();
        let h = headline(&cells, &[13, 40]).unwrap();
        assert!(h.starts_with("Real CARMEN logs (2,"), "{h}");
        // DCT − grid = 50 + k: means 50.5 at both sizes.
        assert!(h.contains("+50 to +50 nats per log"), "{h}");
        assert!(h.contains("DCT higher on 2/2 logs at 40²"), "{h}");
        assert!(
            h.contains("in 0.01 s vs the thesis' 39.84 s (not like for like — hardware/language"),
            "{h}"
        );
        // DCT − GPOM = 19 900 + 101 k: 1.995·10⁴.
        assert!(
            h.contains("trail the DCT map by 2.00–2.00·10⁴ and 0.89–0.89·10⁴ nats"),
            "{h}"
        );
        assert!(
            h.contains("(thesis 2.68–3.89·10⁴ and 4.12–4.19·10⁴)"),
            "{h}"
        );
        assert!(headline(&[], &[13, 40]).is_none());
    }

    #[test]
    fn the_thesis_delta_of_13_is_recomputed_from_its_means() {
        let row = THESIS.iter().find(|t| t.0 == 13).unwrap();
        let recomputed = (1.0 - row.1 / row.3) * 100.0;
        assert!((recomputed - row.6).abs() < 0.01, "{recomputed}");
        assert!((recomputed - THESIS_PRINTED_DELTA_13).abs() > 1.0);
    }
}
