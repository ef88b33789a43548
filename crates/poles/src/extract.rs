//! Pole extraction from a local map (Schaefer 2020, §12.4.1): occupancy, scores, vertical stacks,
//! the 2-D score map, seeds at its local maxima, Gaussian mean shift, widths, non-maximum
//! suppression.

use std::time::Instant;

use nalgebra::Point3;
use rayon::prelude::*;
use raypath_geometry::{Grid3, PointCloud, Pose3};
use raypath_sensor_models::BetaPrior;

use crate::beta::{OccupancyTable, reflection_prior};
use crate::error::{PoleError, Result};
use crate::filters::{Scratch, rect_max};
use crate::hitmiss::HitMissGrid;
use crate::params::PoleParams;
use crate::pole::Pole;
use crate::score::{ScoreVolume, pole_scores};
use crate::sweep::SweepMotion;

/// What one extraction did, for speed figures.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ExtractionStats {
    /// Rays traced (valid points within range).
    pub rays: u64,
    /// Seconds spent tracing rays.
    pub trace_secs: f64,
    /// Seconds spent on occupancy, scores and poles.
    pub score_secs: f64,
    /// Seeds found at local maxima of the score map.
    pub seeds: usize,
}

/// The grid of a local map centred (per [`PoleParams::sensor_in_grid_m`]) at `center`
/// (world frame, axis-aligned with the world).
pub fn local_grid(center: &Point3<f64>, params: &PoleParams) -> Result<Grid3> {
    params.validate()?;
    let [ox, oy, oz] = params.sensor_in_grid_m;
    let origin = Point3::new(center.x - ox, center.y - oy, center.z - oz);
    Grid3::new(origin, params.voxel_m, params.dims()).map_err(|e| PoleError::InvalidParameter {
        name: "center",
        reason: e.to_string(),
    })
}

/// Extracts poles from registered scans (`world_from_sensor`, points in the sensor frame)
/// in a local map centred at `center`. Returns the poles in the world frame.
pub fn extract_poles(
    scans: &[(Pose3, &PointCloud)],
    center: &Point3<f64>,
    params: &PoleParams,
) -> Result<(Vec<Pole>, ExtractionStats)> {
    extract_poles_from_sweeps(scans, None, center, params)
}

/// [`extract_poles`] for de-skewed sweeps: with `motions` (one per scan), every ray is
/// traced from where the sensor was when it measured the point
/// ([`HitMissGrid::insert_sweeps_par`]).
pub fn extract_poles_from_sweeps(
    scans: &[(Pose3, &PointCloud)],
    motions: Option<&[SweepMotion]>,
    center: &Point3<f64>,
    params: &PoleParams,
) -> Result<(Vec<Pole>, ExtractionStats)> {
    let grid = local_grid(center, params)?;
    let started = Instant::now();
    let mut counts = HitMissGrid::new(grid);
    counts.insert_sweeps_par(scans, motions, params.max_range_m);
    let trace_secs = started.elapsed().as_secs_f64();
    let (poles, mut stats) = poles_from_counts(&counts, params)?;
    stats.trace_secs = trace_secs;
    Ok((poles, stats))
}

/// The occupancy `1 − I_{μ_o}(h + α, m + β)` of every voxel (Schaefer 2020, §12.4.1) with the
/// prior fitted to the counts by the method of moments (degenerate moments clamped to a
/// concentration `α + β ≥ 10⁻³`, [`BetaPrior::from_moments_clamped`]).
pub fn occupancy(counts: &HitMissGrid, threshold: f64) -> (Vec<f32>, BetaPrior) {
    let prior = reflection_prior(counts.hits(), counts.misses());
    let mut occ = vec![0.0f32; counts.hits().len()];
    occ.par_chunks_mut(1 << 15)
        .zip(counts.hits().par_chunks(1 << 15))
        .zip(counts.misses().par_chunks(1 << 15))
        .for_each_init(
            || OccupancyTable::new(prior, threshold),
            |table, ((o, h), m)| {
                for ((o, &h), &m) in o.iter_mut().zip(h).zip(m) {
                    *o = table.get(h as u32, m as u32);
                }
            },
        );
    (occ, prior)
}

/// Extracts poles from hit/miss counts.
pub fn poles_from_counts(
    counts: &HitMissGrid,
    params: &PoleParams,
) -> Result<(Vec<Pole>, ExtractionStats)> {
    params.validate()?;
    let started = Instant::now();
    let grid = counts.grid();
    let dims = grid.dims();
    let (occ, _) = occupancy(counts, params.occupancy_threshold);
    let scores = pole_scores(&occ, dims, params.max_width_cells, params.hull_cells());
    let columns = stacks(&scores, params);
    let seeds = seeds(&columns, dims[0], dims[1], params.hull_cells());
    let n_seeds = seeds.len();
    let voxel = grid.cell_size();
    let origin = grid.origin();
    let mut poles: Vec<Pole> = seeds
        .iter()
        .filter_map(|seed| {
            let converged = mean_shift(&columns, dims[0], dims[1], *seed, params);
            let cell = |p: [f64; 2]| -> Option<usize> {
                let (cx, cy) = (p[0].floor(), p[1].floor());
                (cx >= 0.0 && cy >= 0.0 && (cx as usize) < dims[0] && (cy as usize) < dims[1])
                    .then(|| cy as usize * dims[0] + cx as usize)
            };
            let (pos, col) = match cell(converged) {
                Some(c) if columns.get(c).is_some_and(|s| s.valid()) => (converged, c),
                _ => (*seed, cell(*seed)?),
            };
            let stack = columns.get(col)?;
            if !stack.valid() {
                return None;
            }
            let (width_cells, score) = width_and_score(&scores, col, stack, dims);
            Some(Pole {
                x: origin.x + pos[0] * voxel,
                y: origin.y + pos[1] * voxel,
                z_start: origin.z + stack.start as f64 * voxel,
                z_end: origin.z + (stack.start + stack.len) as f64 * voxel,
                width: width_cells * voxel,
                score,
            })
        })
        .collect();
    let poles_nms = non_maximum_suppression(&mut poles, params.free_length_m);
    let stats = ExtractionStats {
        rays: counts.rays(),
        trace_secs: 0.0,
        score_secs: started.elapsed().as_secs_f64(),
        seeds: n_seeds,
    };
    Ok((poles_nms, stats))
}

/// The longest vertical run of a column with `Q ≥ q_min`.
#[derive(Clone, Copy, Debug, Default)]
struct Stack {
    start: usize,
    len: usize,
    /// Mean `Q` over the run; 0 when the run is shorter than `h_min`.
    score: f32,
}

impl Stack {
    fn valid(&self) -> bool {
        self.score > 0.0
    }
}

fn stacks(scores: &ScoreVolume, params: &PoleParams) -> Vec<Stack> {
    let [nx, ny, nz] = scores.dims;
    let n_slice = nx * ny;
    let min_len = params.min_stack_cells();
    let q_min = params.min_score as f32;
    (0..n_slice)
        .into_par_iter()
        .map(|col| {
            let (mut best, mut run_start, mut run_len) = (Stack::default(), 0, 0);
            for z in 0..=nz {
                let q = if z < nz {
                    scores.best.get(z * n_slice + col).copied().unwrap_or(0.0)
                } else {
                    f32::NEG_INFINITY
                };
                if q >= q_min {
                    if run_len == 0 {
                        run_start = z;
                    }
                    run_len += 1;
                } else {
                    if run_len > best.len {
                        best = Stack {
                            start: run_start,
                            len: run_len,
                            score: 0.0,
                        };
                    }
                    run_len = 0;
                }
            }
            if best.len >= min_len {
                let sum: f32 = (best.start..best.start + best.len)
                    .filter_map(|z| scores.best.get(z * n_slice + col))
                    .sum();
                best.score = sum / best.len as f32;
            }
            best
        })
        .collect()
}

/// Seeds: local maxima of the score map over `(2f + 1)²` windows, plateaus merged by
/// 8-connected labelling, each seed at its plateau's centroid (cell-centre coordinates,
/// `skimage.feature.peak_local_max(S, min_distance = f)`).
fn seeds(columns: &[Stack], nx: usize, ny: usize, f: usize) -> Vec<[f64; 2]> {
    let map: Vec<f32> = columns.iter().map(|s| s.score).collect();
    let mut dilated = vec![0.0; map.len()];
    let mut scratch = Scratch::default();
    let w = 2 * f + 1;
    rect_max(
        &map,
        nx,
        ny,
        (-(f as isize), w),
        (-(f as isize), w),
        0.0,
        &mut dilated,
        &mut scratch,
    );
    let is_peak: Vec<bool> = map
        .iter()
        .zip(&dilated)
        .map(|(&s, &d)| s > 0.0 && s >= d)
        .collect();
    let mut label = vec![false; map.len()];
    let mut out = Vec::new();
    let mut stack = Vec::new();
    for start in 0..map.len() {
        if !is_peak[start] || label[start] {
            continue;
        }
        label[start] = true;
        stack.push(start);
        let (mut sx, mut sy, mut count) = (0.0, 0.0, 0usize);
        while let Some(i) = stack.pop() {
            let (x, y) = (i % nx, i / nx);
            sx += x as f64 + 0.5;
            sy += y as f64 + 0.5;
            count += 1;
            for dy in -1isize..=1 {
                for dx in -1isize..=1 {
                    let (xx, yy) = (x as isize + dx, y as isize + dy);
                    if xx < 0 || yy < 0 || xx as usize >= nx || yy as usize >= ny {
                        continue;
                    }
                    let j = yy as usize * nx + xx as usize;
                    if is_peak[j] && !label[j] {
                        label[j] = true;
                        stack.push(j);
                    }
                }
            }
        }
        out.push([sx / count as f64, sy / count as f64]);
    }
    out
}

/// Gaussian mean shift on the score map from `seed` (cell units; kernel σ and the stop
/// distance from `params`). Cells beyond 3σ are ignored.
fn mean_shift(
    columns: &[Stack],
    nx: usize,
    ny: usize,
    seed: [f64; 2],
    params: &PoleParams,
) -> [f64; 2] {
    let sigma = params.mean_shift_sigma_m / params.voxel_m;
    let stop = params.mean_shift_stop_m / params.voxel_m;
    let radius = (3.0 * sigma).ceil() as isize + 1;
    let inv_two_var = 0.5 / (sigma * sigma);
    let mut p = seed;
    for _ in 0..100 {
        let (cx, cy) = (p[0].floor() as isize, p[1].floor() as isize);
        let (mut wx, mut wy, mut wsum) = (0.0, 0.0, 0.0);
        for y in (cy - radius).max(0)..=(cy + radius).min(ny as isize - 1) {
            for x in (cx - radius).max(0)..=(cx + radius).min(nx as isize - 1) {
                let s = columns
                    .get(y as usize * nx + x as usize)
                    .map_or(0.0, |c| c.score as f64);
                if s <= 0.0 {
                    continue;
                }
                let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                let d2 = (px - p[0]).powi(2) + (py - p[1]).powi(2);
                let w = s * (-d2 * inv_two_var).exp();
                wx += w * px;
                wy += w * py;
                wsum += w;
            }
        }
        if wsum <= 0.0 {
            return p;
        }
        let next = [wx / wsum, wy / wsum];
        let step = ((next[0] - p[0]).powi(2) + (next[1] - p[1]).powi(2)).sqrt();
        p = next;
        if step < stop {
            break;
        }
    }
    p
}

/// Width (cells) `Σ a w_a / Σ w_a` with `w_a` the mean over the stack of the **raw** score
/// `max(0, q_a) = max(0, 2q'_a − 1)`, and the score: the stack's mean `Q`. Deviation from
/// `poles.py`, which weights by the remapped `q'_a ≥ 0.5` so that every width gets about the
/// same weight and all widths are pulled towards the middle of the range scored.
fn width_and_score(
    scores: &ScoreVolume,
    col: usize,
    stack: &Stack,
    dims: [usize; 3],
) -> (f64, f64) {
    let n_slice = dims[0] * dims[1];
    let (mut num, mut den) = (0.0, 0.0);
    for a in 1..=scores.widths {
        let w: f64 = (stack.start..stack.start + stack.len)
            .map(|z| (2.0 * scores.width_score(a, z * n_slice + col) as f64 - 1.0).max(0.0))
            .sum::<f64>()
            / stack.len.max(1) as f64;
        num += a as f64 * w;
        den += w;
    }
    let width = if den <= 0.0 { 1.0 } else { num / den };
    (width, stack.score as f64)
}

/// Sorts by score (descending) and drops every pole closer than `free_length` (gap between
/// footprints, `‖c_i − c_j‖ − (a_i + a_j)/2`) to a better one.
pub fn non_maximum_suppression(poles: &mut [Pole], free_length: f64) -> Vec<Pole> {
    poles.sort_by(|a, b| b.score.total_cmp(&a.score));
    let mut kept: Vec<Pole> = Vec::with_capacity(poles.len());
    for p in poles.iter() {
        let suppressed = kept.iter().any(|k| {
            let d = ((p.x - k.x).powi(2) + (p.y - k.y).powi(2)).sqrt();
            d - 0.5 * (p.width + k.width) < free_length
        });
        if !suppressed {
            kept.push(*p);
        }
    }
    kept
}
