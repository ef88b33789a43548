//! What one log's unit measures: the seeded patch, the mapping and held-back rays, the
//! ground truth, and at every size the DCT map, the grid map and the two baselines (with the
//! Fig. 9.1 pictures for the Intel log).

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
    DctMap, FitConfig, FitProblem, GridRateMap, MapRay, Patch, RangeLimits, Shape, Solver, fit,
    initial_map,
};
use raypath_geometry::Ray2;
use raypath_io::sequence::{LaserChoice, PlanarOptions, read_planar};
use serde_json::json;

use super::{
    BaselineCell, Cell, HEAVY_FRACTION, HELD_BACK, MAPPING_RAYS, PATCH_M, SEED, TIMING_RAYS,
};

/// One log's patch and rays.
struct Setup {
    name: String,
    patch: Patch,
    mapping: Vec<MapRay>,
    held: Vec<MapRay>,
    truth: GroundTruth,
}

impl Setup {
    fn extent(&self) -> [f64; 2] {
        self.patch.extent_m
    }

    /// The first mapping rays: the thesis' timing set.
    fn timing(&self) -> &[MapRay] {
        &self.mapping[..TIMING_RAYS.min(self.mapping.len())]
    }
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
fn baseline_cell(
    which: Baseline,
    setup: &Setup,
    n: usize,
    fig: Option<&Path>,
) -> Result<BaselineCell> {
    let config = BaselineConfig::default();
    let (mapping, held) = (&setup.mapping, &setup.held);
    let (score, report) =
        score_baseline(which, setup.extent(), mapping, held, n * n, &config, SEED)?;
    let (fit500_s, _, _) = fit_baseline(which, setup.timing(), n * n, &config, SEED)?;
    if let Some(dir) = fig {
        let tag = match which {
            Baseline::Gpom => "gpom",
            Baseline::Hilbert => "hm",
        };
        // Occupancy shown as p_ref: the rate whose p_ref is o.
        let (o, nx, ny) = score.raster.lattice();
        let rates: Vec<f64> = o.iter().map(|o| -(-o).ln_1p()).collect();
        let file = format!("{}-{tag}-{n}x{n}.png", setup.name);
        write_p_ref_png(&dir.join(file), &rates, nx, ny, 2)?;
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

/// Whole mapping time, fit time and training log-likelihood of one DCT fit.
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

/// Reads the log named `name` at `path` and draws its patch and rays.
fn setup(path: &Path, name: &str) -> Result<Setup> {
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
    let truth = GroundTruth::new(patch.extent_m, 0.05, &mapping)?;
    Ok(Setup {
        name: name.to_owned(),
        patch,
        mapping,
        held,
        truth,
    })
}

/// Every size on the log at `path`; the pictures go to `fig_dir` when given.
pub fn run_log(
    path: &Path,
    name: &str,
    sizes: &[usize],
    fig_dir: Option<&Path>,
) -> Result<(Vec<Cell>, serde_json::Value)> {
    let setup = setup(path, name)?;
    let cells = sizes
        .iter()
        .map(|&n| measure_size(&setup, n, fig_dir))
        .collect::<Result<Vec<_>>>()?;
    if let Some(dir) = fig_dir {
        let (g, nx, ny) = grid_lattice(&setup.truth.map);
        let file = format!("{name}-truth-200x200.png");
        write_p_ref_png(&dir.join(file), &g, nx, ny, 2)?;
    }
    Ok((cells, info(&setup)))
}

/// What the log's data are (the page's Data table).
fn info(setup: &Setup) -> serde_json::Value {
    let hits = setup
        .mapping
        .iter()
        .filter(|r| r.outcome == raypath_dct_map::Outcome::Hit)
        .count();
    let (patch, extent) = (&setup.patch, setup.extent());
    json!({
        "log": setup.name,
        "patch": [patch.min[0], patch.min[1], extent[0], extent[1]],
        "mapping_rays": setup.mapping.len(),
        "mapping_hits": hits,
        "held_back_rays": setup.held.len(),
        "truth_observed_cells": setup.truth.points.len(),
    })
}

/// The DCT map and grid map with `n`² parameters beside each other and the baselines: their
/// errors, likelihoods and times.
fn measure_size(setup: &Setup, n: usize, fig_dir: Option<&Path>) -> Result<Cell> {
    let (extent, shape) = (setup.extent(), Shape { l: n, m: n });
    let (mapping, held) = (&setup.mapping, &setup.held);
    let config = FitConfig::default();
    let (map, grid, c) = compare(extent, shape, mapping, held, &setup.truth, &config)?;
    let (time500, _, _) = timed_fit(extent, shape, setup.timing(), Solver::TrustRegionNewton)?;
    let start = Instant::now();
    let _ = GridRateMap::from_rays(PATCH_M / n as f64, [n, n], setup.timing())?;
    let grid_time500 = start.elapsed().as_secs_f64();
    let (_, newton_fit_s, newton_ll) =
        timed_fit(extent, shape, mapping, Solver::TrustRegionNewton)?;
    let (_, lbfgs_s, lbfgs_ll) = timed_fit(extent, shape, mapping, Solver::Lbfgs)?;
    if let Some(dir) = fig_dir {
        write_maps(dir, &setup.name, n, &map, &grid)?;
    }
    let dct_raster_ll = raster_log_likelihood(&map, extent, held)?;
    let fig = fig_dir.filter(|_| n == 13 || n == 40);
    let gpom = baseline_cell(Baseline::Gpom, setup, n, fig)?;
    let hm = baseline_cell(Baseline::Hilbert, setup, n, fig)?;
    let worst = |f: &dyn Fn(&MapRay) -> f64| held.iter().map(f).fold(f64::INFINITY, f64::min);
    Ok(Cell {
        log: setup.name.clone(),
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
        worst_ray_ll: worst(&|r| map.ray_log_likelihood(r)),
        grid_worst_ray_ll: worst(&|r| grid.ray_log_likelihood(r)),
        gpom,
        hm,
        dct_raster_ll,
    })
}

/// The DCT map scored through the baselines' raster (`o = 1 − e^{−λ·0.05}`).
fn raster_log_likelihood(map: &DctMap, extent: [f64; 2], held: &[MapRay]) -> Result<f64> {
    let as_occupancy = RateAsOccupancy {
        rate_at: |p: [f64; 2]| map.rate_at(p),
        pixel_m: BASELINE_PIXEL_M,
    };
    Ok(OccupancyRaster::from_field(extent, BASELINE_PIXEL_M, &as_occupancy)?.log_likelihood(held))
}

/// The DCT map and the grid map of size `n` as p_ref pictures.
fn write_maps(dir: &Path, name: &str, n: usize, map: &DctMap, grid: &GridRateMap) -> Result<()> {
    let rates = map.rates_on_lattice(200, 200);
    write_p_ref_png(
        &dir.join(format!("{name}-dct-{n}x{n}.png")),
        &rates,
        200,
        200,
        2,
    )?;
    let (g, nx, ny) = grid_lattice(grid);
    Ok(write_p_ref_png(
        &dir.join(format!("{name}-grid-{n}x{n}.png")),
        &g,
        nx,
        ny,
        (400 / nx.max(1)) as u32,
    )?)
}
