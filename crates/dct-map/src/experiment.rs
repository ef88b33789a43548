//! The experiment of Sec. 9.5 on a log's rays: choosing a 10 m × 10 m patch, drawing the
//! mapping and held-back rays, fitting a DCT map and a grid map with as many parameters,
//! and scoring both against a fine ground-truth grid and on the held-back rays.
//!
//! The thesis leaves the patch and ray selection open (Sec. 9.5); here:
//! * **patch**: corners on a 1 m lattice; each candidate's weight is the ray path length
//!   inside it (rays traced at most [`PATCH_TRACE_M`] metres, on a 1 m grid). The `auto`
//!   patch is the heaviest (ties: smallest x, then y). The evaluation draws, with a seed,
//!   one patch among those with at least 75 % of the heaviest weight;
//! * **rays**: every ray that reaches the patch is clipped to it ([`Patch::clip_ray`]); they
//!   are shuffled with ChaCha8 seeded by the seed, the first `mapping_rays` build the maps
//!   and the next `held_back_rays` score them;
//! * **ground truth**: the grid decay-rate map of 0.05 m cells (200 × 200 on 10 m) from the
//!   mapping rays, evaluated at the centres of its observed cells (`R_i > 0`);
//! * **occupancy baselines** (Sec. 9.5.2, [`score_baseline`]): a GPOM with as many training
//!   points and a Hilbert map with as many Nyström components as the DCT map has
//!   coefficients, from the same mapping rays, scored on the held-back rays through a
//!   [`BASELINE_PIXEL_M`] raster ([`crate::baselines`]).

use std::time::Instant;

use nalgebra::{Point2, Unit, Vector2};
use rand::SeedableRng;
use rand::seq::{IndexedRandom, SliceRandom};
use rand_chacha::ChaCha8Rng;
use raypath_geometry::{Grid2, Ray2};
use serde::{Deserialize, Serialize};

use crate::baselines::{
    Gpom, GpomConfig, GpomReport, HilbertConfig, HilbertMap, HilbertReport, OccupancyField,
    OccupancyRaster, TrainingConfig, TrainingSet,
};
use crate::render::p_ref;
use crate::{
    DctError, DctMap, FitConfig, FitProblem, FitReport, GridRateMap, MapRay, Patch, RangeLimits,
    Shape, fit, initial_map,
};

/// How far rays are traced when weighing candidate patches (m).
pub const PATCH_TRACE_M: f64 = 30.0;

/// Candidate patches of `size_m` (corners on a 1 m lattice) with their ray path length
/// (m), in lattice order.
pub fn candidate_patches(rays: &[Ray2], size_m: f64) -> Vec<(Patch, f64)> {
    let finite: Vec<&Ray2> = rays
        .iter()
        .filter(|r| r.origin.x.is_finite() && r.origin.y.is_finite())
        .collect();
    if finite.is_empty() || !(size_m.is_finite() && size_m >= 1.0) {
        return Vec::new();
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for r in &finite {
        for k in 0..2 {
            lo[k] = lo[k].min(r.origin[k] - PATCH_TRACE_M);
            hi[k] = hi[k].max(r.origin[k] + PATCH_TRACE_M);
        }
    }
    let lo = [lo[0].floor(), lo[1].floor()];
    let dims = [
        (hi[0] - lo[0]).ceil() as usize + 1,
        (hi[1] - lo[1]).ceil() as usize + 1,
    ];
    let Ok(grid) = Grid2::new(Point2::new(lo[0], lo[1]), 1.0, dims) else {
        return Vec::new();
    };
    let mut length = vec![0.0; grid.num_cells()];
    for r in finite {
        let traced = r.range.traced_length(PATCH_TRACE_M);
        for c in grid.traverse(&r.origin, &r.direction, traced) {
            length[c.index] += c.length();
        }
    }
    // Summed-area table, (nx + 1) × (ny + 1).
    let (nx, ny) = (dims[0], dims[1]);
    let mut sat = vec![0.0; (nx + 1) * (ny + 1)];
    for iy in 0..ny {
        for ix in 0..nx {
            let v = length[grid.linear_index([ix, iy])];
            sat[(iy + 1) * (nx + 1) + ix + 1] =
                v + sat[iy * (nx + 1) + ix + 1] + sat[(iy + 1) * (nx + 1) + ix]
                    - sat[iy * (nx + 1) + ix];
        }
    }
    let w = size_m.ceil() as usize;
    let mut out = Vec::new();
    for iy in 0..ny.saturating_sub(w) {
        for ix in 0..nx.saturating_sub(w) {
            let s = sat[(iy + w) * (nx + 1) + ix + w]
                - sat[iy * (nx + 1) + ix + w]
                - sat[(iy + w) * (nx + 1) + ix]
                + sat[iy * (nx + 1) + ix];
            out.push((
                Patch::square([lo[0] + ix as f64, lo[1] + iy as f64], size_m),
                s,
            ));
        }
    }
    out
}

/// The patch with the most ray path length (`--patch auto`; deterministic).
pub fn auto_patch(rays: &[Ray2], size_m: f64) -> Option<Patch> {
    let mut best: Option<(Patch, f64)> = None;
    for (p, w) in candidate_patches(rays, size_m) {
        if best.is_none_or(|(_, bw)| w > bw) {
            best = Some((p, w));
        }
    }
    best.map(|(p, _)| p)
}

/// A seeded draw among the patches with at least `fraction` of the heaviest weight.
pub fn seeded_patch(rays: &[Ray2], size_m: f64, fraction: f64, seed: u64) -> Option<Patch> {
    let all = candidate_patches(rays, size_m);
    let max = all.iter().map(|(_, w)| *w).fold(0.0, f64::max);
    let heavy: Vec<Patch> = all
        .into_iter()
        .filter(|(_, w)| *w >= fraction * max)
        .map(|(p, _)| p)
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    heavy.choose(&mut rng).copied()
}

/// All rays clipped to `patch`, shuffled with `seed`, split into `mapping` and `held_back`
/// sets of at most the given sizes (held-back rays come after the mapping rays).
pub fn draw_rays(
    rays: &[Ray2],
    patch: &Patch,
    limits: &RangeLimits,
    mapping: usize,
    held_back: usize,
    seed: u64,
) -> (Vec<MapRay>, Vec<MapRay>) {
    let mut clipped: Vec<MapRay> = rays
        .iter()
        .filter_map(|r| patch.clip_ray(r, limits))
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    clipped.shuffle(&mut rng);
    let n_map = mapping.min(clipped.len());
    let held: Vec<MapRay> = clipped
        .iter()
        .skip(n_map)
        .take(held_back)
        .copied()
        .collect();
    clipped.truncate(n_map);
    (clipped, held)
}

/// Scores of one DCT map and one grid map with as many parameters (the CLI's JSON keys).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// DCT mapping time: pre-processing, initialization and fit (s).
    pub time_s: f64,
    /// Grid mapping time (s).
    pub grid_time_s: f64,
    /// DCT log-likelihood of the held-back rays.
    pub log_likelihood: f64,
    /// Grid log-likelihood of the held-back rays.
    pub grid_log_likelihood: f64,
    /// RMSE of `p_ref` against the ground-truth grid (DCT).
    pub rmse_p_ref: f64,
    /// RMSE of `p_ref` against the ground-truth grid (grid map).
    pub grid_rmse_p_ref: f64,
    /// Accepted optimizer iterations.
    pub iterations: usize,
    /// The fit's report.
    pub fit: FitReport,
}

/// A ground-truth grid and the centres of its observed cells with their `p_ref`.
#[derive(Clone, Debug)]
pub struct GroundTruth {
    /// The fine grid map.
    pub map: GridRateMap,
    /// Observed cell centres (map frame).
    pub points: Vec<[f64; 2]>,
    /// `p_ref` at those centres.
    pub p_ref: Vec<f64>,
}

impl GroundTruth {
    /// The ground truth over `extent_m` with square cells of edge `cell_m` (the thesis: 0.05 m,
    /// 200 × 200 on 10 m) from `rays`.
    pub fn new(extent_m: [f64; 2], cell_m: f64, rays: &[MapRay]) -> Result<Self, DctError> {
        let map = GridRateMap::from_rays(cell_m, cells_covering(extent_m, cell_m), rays)?;
        let grid = *map.grid();
        let (mut points, mut p) = (Vec::new(), Vec::new());
        for i in 0..grid.num_cells() {
            if map.observed(i) {
                let c = grid.cell_center(grid.cell_from_linear(i));
                points.push([c.x, c.y]);
                p.push(p_ref(map.rates()[i]));
            }
        }
        if points.is_empty() {
            return Err(DctError::NoData("no ground-truth cell was observed".into()));
        }
        Ok(Self {
            map,
            points,
            p_ref: p,
        })
    }

    /// RMSE of `p_ref` of a rate field against the ground truth.
    pub fn rmse(&self, rate_at: impl Fn([f64; 2]) -> f64 + Sync) -> f64 {
        use rayon::prelude::*;
        let sum: f64 = self
            .points
            .par_iter()
            .zip(&self.p_ref)
            .map(|(p, want)| (p_ref(rate_at(*p)) - want).powi(2))
            .sum();
        (sum / self.points.len() as f64).sqrt()
    }
}

/// The number of square cells of edge `cell_m` that cover `extent_m` (rounded to the
/// nearest count when within 1e-9 of an integer).
pub fn cells_covering(extent_m: [f64; 2], cell_m: f64) -> [usize; 2] {
    let n = |e: f64| {
        let k = e / cell_m;
        (if (k - k.round()).abs() < 1e-9 {
            k.round()
        } else {
            k.ceil()
        })
        .max(1.0) as usize
    };
    [n(extent_m[0]), n(extent_m[1])]
}

/// Fits a DCT map of `shape` over `extent_m` and a grid map with `L × M` parameters
/// (square cells of edge `min(X/L, Y/M)`; exactly `L × M` cells when `X/L = Y/M`) from
/// `mapping`, scores both on `held_back` and against `truth`.
pub fn compare(
    extent_m: [f64; 2],
    shape: Shape,
    mapping: &[MapRay],
    held_back: &[MapRay],
    truth: &GroundTruth,
    config: &FitConfig,
) -> Result<(DctMap, GridRateMap, Comparison), DctError> {
    let extent = extent_m;
    let start = Instant::now();
    let problem = FitProblem::new(extent, shape, mapping)?;
    let init = initial_map(extent, shape, mapping)?;
    let (map, report) = fit(&problem, init.coefficients(), config)?;
    let time_s = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let cell = (extent[0] / shape.l.max(1) as f64).min(extent[1] / shape.m.max(1) as f64);
    let grid = GridRateMap::from_rays(cell, cells_covering(extent, cell), mapping)?;
    let grid_time_s = start.elapsed().as_secs_f64();
    let comparison = Comparison {
        time_s,
        grid_time_s,
        log_likelihood: map.log_likelihood(held_back),
        grid_log_likelihood: grid.log_likelihood(held_back),
        rmse_p_ref: truth.rmse(|p| map.rate_at(p)),
        grid_rmse_p_ref: truth.rmse(|p| grid.rate_at(p)),
        iterations: report.iterations,
        fit: report,
    };
    Ok((map, grid, comparison))
}

/// Pixel edge of the raster on which the occupancy baselines are scored (thesis Sec. 9.5.2).
pub const BASELINE_PIXEL_M: f64 = 0.05;

/// How the occupancy baselines of Sec. 9.5.2 are built (each field's docs give its default).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BaselineConfig {
    /// Training points along the rays.
    pub training: TrainingConfig,
    /// GPOM hyperparameters.
    pub gpom: GpomConfig,
    /// Hilbert-map hyperparameters.
    pub hilbert: HilbertConfig,
}

/// One occupancy baseline with `parameters` reals, scored on the held-back rays.
#[derive(Clone, Debug)]
pub struct BaselineScore {
    /// Log-likelihood of the held-back rays on the [`BASELINE_PIXEL_M`] raster.
    pub log_likelihood: f64,
    /// Mapping time: training points from the rays, hyperparameters and fit (s).
    pub fit_s: f64,
    /// Time to predict the raster (s), not part of [`fit_s`](Self::fit_s).
    pub raster_s: f64,
    /// The raster (clamped occupancies).
    pub raster: OccupancyRaster,
}

/// Which occupancy baseline.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Baseline {
    /// Gaussian process occupancy map, `parameters` training points.
    Gpom,
    /// Hilbert map, `parameters` Nyström components.
    Hilbert,
}

/// The fit report of either baseline.
#[derive(Clone, Debug, PartialEq)]
pub enum BaselineReport {
    /// GPOM.
    Gpom(GpomReport),
    /// Hilbert map.
    Hilbert(HilbertReport),
}

/// Fits `which` with `parameters` reals from `mapping` (training points sampled with ChaCha8
/// seeded by `seed`, the same stream then drawing the GPOM subset or the Nyström
/// landmarks) and returns the fit time and the fitted field. Used for the timing runs.
pub fn fit_baseline(
    which: Baseline,
    mapping: &[MapRay],
    parameters: usize,
    config: &BaselineConfig,
    seed: u64,
) -> Result<(f64, Box<dyn OccupancyField>, BaselineReport), DctError> {
    let start = Instant::now();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let training = TrainingSet::sample(mapping, &config.training, &mut rng)?;
    Ok(match which {
        Baseline::Gpom => {
            let (map, report) = Gpom::fit(&training, parameters, &config.gpom, &mut rng)?;
            let t = start.elapsed().as_secs_f64();
            (t, Box::new(map), BaselineReport::Gpom(report))
        }
        Baseline::Hilbert => {
            let (map, report) = HilbertMap::fit(&training, parameters, &config.hilbert, &mut rng)?;
            let t = start.elapsed().as_secs_f64();
            (t, Box::new(map), BaselineReport::Hilbert(report))
        }
    })
}

/// [`fit_baseline`], then the [`BASELINE_PIXEL_M`] raster over `extent_m` and the
/// log-likelihood of `held_back` on it ([`OccupancyRaster::log_likelihood`]).
pub fn score_baseline(
    which: Baseline,
    extent_m: [f64; 2],
    mapping: &[MapRay],
    held_back: &[MapRay],
    parameters: usize,
    config: &BaselineConfig,
    seed: u64,
) -> Result<(BaselineScore, BaselineReport), DctError> {
    let (fit_s, field, report) = fit_baseline(which, mapping, parameters, config, seed)?;
    let start = Instant::now();
    let raster = OccupancyRaster::from_field(extent_m, BASELINE_PIXEL_M, &*field)?;
    let raster_s = start.elapsed().as_secs_f64();
    let score = BaselineScore {
        log_likelihood: raster.log_likelihood(held_back),
        fit_s,
        raster_s,
        raster,
    };
    Ok((score, report))
}

/// A world ray from a map ray of `patch` (helper for callers that trace in the world frame).
pub fn world_ray(patch: &Patch, ray: &MapRay) -> Option<Ray2> {
    let d = Unit::try_new(Vector2::new(ray.direction[0], ray.direction[1]), 0.0)?;
    Some(Ray2 {
        origin: Point2::new(ray.origin[0] + patch.min[0], ray.origin[1] + patch.min[1]),
        direction: d,
        range: raypath_geometry::Range::Hit(ray.length_m),
    })
}
