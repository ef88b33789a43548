//! Grid decay-rate maps over the same patch (the thesis's baseline, ch. 7) and conversions
//! between them and [`DctMap`]s.
//!
//! The statistics `H_i`, `M_i`, `R_i` are gathered from the same [`MapRay`]s with the exact
//! 2-D traversal of `raypath-geometry`, and the map is `raypath-sensor-models`'
//! [`DecayRateModel2`] (`λ_i = H_i / R_i`, floored at `1e-3 /m`, unobserved cells at the
//! mean rate — its defaults). `sub` rays are ignored in mapping, as there.

use nalgebra::{Point2, Unit, Vector2};
use raypath_geometry::{Grid2, Range, Ray2};
use raypath_sensor_models::{
    CellStats, DecayRateConfig, DecayRateModel2, DenseStats2, MappingSummary,
};

use crate::error::positive;
use crate::{DctError, DctMap, MapRay, Outcome, Shape};

/// A grid decay-rate map over `[0, X] × [0, Y]` (map frame).
#[derive(Clone, Debug)]
pub struct GridRateMap {
    model: DecayRateModel2,
    stats: DenseStats2,
}

impl GridRateMap {
    /// Builds the ML grid map with `dims` cells of edge `cell_m` (map frame, origin at the
    /// patch's lower-left corner) from `rays`.
    pub fn from_rays(cell_m: f64, dims: [usize; 2], rays: &[MapRay]) -> Result<Self, DctError> {
        positive("cell_m", cell_m)?;
        let grid =
            Grid2::new(Point2::origin(), cell_m, dims).map_err(|e| DctError::InvalidParameter {
                name: "grid",
                reason: e.to_string(),
            })?;
        let n = grid.num_cells();
        let (mut h, mut m, mut r) = (vec![0u32; n], vec![0u32; n], vec![0.0f64; n]);
        for ray in rays.iter().filter(|r| r.outcome != Outcome::Sub) {
            let origin = Point2::new(ray.origin[0], ray.origin[1]);
            let dir = Unit::new_normalize(Vector2::new(ray.direction[0], ray.direction[1]));
            let hit_cell = match ray.outcome {
                Outcome::Hit => grid
                    .cell_of(&Point2::from(ray.end()))
                    .map(|c| grid.linear_index(c)),
                _ => None,
            };
            for c in grid.traverse(&origin, &dir, ray.length_m) {
                r[c.index] += c.length();
                if Some(c.index) != hit_cell && c.length() > 0.0 {
                    m[c.index] += 1;
                }
            }
            if let Some(k) = hit_cell {
                h[k] += 1;
            }
        }
        let cells = (0..n).map(|i| CellStats::new(h[i], m[i], r[i])).collect();
        let stats =
            DenseStats2::from_parts(grid, cells, MappingSummary::default()).map_err(|e| {
                DctError::InvalidParameter {
                    name: "grid",
                    reason: e.to_string(),
                }
            })?;
        let model = DecayRateModel2::new(&stats, DecayRateConfig::default()).map_err(|e| {
            DctError::InvalidParameter {
                name: "grid",
                reason: e.to_string(),
            }
        })?;
        Ok(Self { model, stats })
    }

    /// `n × n` square cells over a square extent `size_m` (the thesis's baseline grids).
    pub fn square(size_m: f64, n: usize, rays: &[MapRay]) -> Result<Self, DctError> {
        positive("size_m", size_m)?;
        Self::from_rays(size_m / n.max(1) as f64, [n, n], rays)
    }

    /// The grid (map frame).
    pub fn grid(&self) -> &Grid2 {
        self.model.grid()
    }

    /// The decay-rate model of `raypath-sensor-models`.
    pub fn model(&self) -> &DecayRateModel2 {
        &self.model
    }

    /// The ray statistics per cell.
    pub fn stats(&self) -> &DenseStats2 {
        &self.stats
    }

    /// λ per cell (1/m), linear index of the grid (x fastest).
    pub fn rates(&self) -> &[f64] {
        self.model.rates()
    }

    /// Whether a ray crossed cell `index` (`R_i > 0`).
    pub fn observed(&self, index: usize) -> bool {
        self.stats
            .cells()
            .get(index)
            .is_some_and(|c| c.path_length_m() > 0.0)
    }

    /// λ at a map-frame point (the unknown rate outside the grid).
    pub fn rate_at(&self, p: [f64; 2]) -> f64 {
        let grid = self.grid();
        grid.cell_of(&Point2::new(p[0], p[1]))
            .and_then(|c| self.rates().get(grid.linear_index(c)).copied())
            .unwrap_or(self.model.unknown_rate_per_m())
    }

    /// Log-likelihood of one ray under the grid map (Eq. 7.13 / 7.16, the `sub` form for
    /// `sub`), with the optical depth of `raypath-sensor-models`.
    pub fn ray_log_likelihood(&self, ray: &MapRay) -> f64 {
        let Some(r2) = Ray2::new(
            Point2::new(ray.origin[0], ray.origin[1]),
            Vector2::new(ray.direction[0], ray.direction[1]),
            Range::Hit(ray.length_m),
        ) else {
            return f64::NEG_INFINITY;
        };
        let depth = self.model.optical_depth(&r2, ray.length_m);
        let v = match ray.outcome {
            Outcome::Hit => self.rate_at(ray.end()).ln() - depth,
            Outcome::Sub => (-(-depth).exp_m1()).ln(),
            Outcome::Super => -depth,
        };
        if v.is_nan() { f64::NEG_INFINITY } else { v }
    }

    /// Sum over rays.
    pub fn log_likelihood(&self, rays: &[MapRay]) -> f64 {
        rays.iter().map(|r| self.ray_log_likelihood(r)).sum()
    }
}

impl DctMap {
    /// The DCT map whose amplitude `g` equals `√λ` at the centres of an `L × M` lattice over the
    /// extent: an exact forward DCT-II of `√λ` (the CEIDCT of Sec. 9.4.2 interpolates it). `rates`
    /// are row-major `ix · M + iy`; negative or non-finite rates are rejected.
    pub fn from_rates_at_centres(
        extent_m: [f64; 2],
        shape: Shape,
        rates: &[f64],
    ) -> Result<Self, DctError> {
        if rates.len() != shape.len() {
            return Err(DctError::InvalidParameter {
                name: "rates",
                reason: format!(
                    "{} rates for {} × {} centres",
                    rates.len(),
                    shape.l,
                    shape.m
                ),
            });
        }
        if let Some(i) = rates.iter().position(|r| !(r.is_finite() && *r >= 0.0)) {
            return Err(DctError::InvalidParameter {
                name: "rates",
                reason: format!("rate {i} is negative or not finite"),
            });
        }
        let (lm, mm) = (shape.l, shape.m);
        let basis = |k: usize, i: usize, n: usize| {
            let w = if k == 0 { 1.0 } else { 2.0 } / n as f64;
            w * (std::f64::consts::PI * k as f64 * (2 * i + 1) as f64 / (2 * n) as f64).cos()
        };
        let roots: Vec<f64> = rates.iter().map(|r| r.sqrt()).collect();
        // Along y, then along x (separable DCT-II with the inverse's normalization).
        let mut tmp = vec![0.0; lm * mm];
        for ix in 0..lm {
            for m in 0..mm {
                tmp[ix * mm + m] = (0..mm)
                    .map(|iy| basis(m, iy, mm) * roots[ix * mm + iy])
                    .sum();
            }
        }
        let mut a = vec![0.0; lm * mm];
        for l in 0..lm {
            for m in 0..mm {
                a[l * mm + m] = (0..lm).map(|ix| basis(l, ix, lm) * tmp[ix * mm + m]).sum();
            }
        }
        DctMap::new(extent_m, shape, a)
    }

    /// Conversion from a grid decay-rate map: `λ` sampled at the `L × M` lattice centres,
    /// then [`from_rates_at_centres`](Self::from_rates_at_centres). Used to initialize fits.
    pub fn from_grid(
        extent_m: [f64; 2],
        shape: Shape,
        grid: &GridRateMap,
    ) -> Result<Self, DctError> {
        let mut rates = Vec::with_capacity(shape.len());
        for ix in 0..shape.l {
            for iy in 0..shape.m {
                let x = (ix as f64 + 0.5) * extent_m[0] / shape.l as f64;
                let y = (iy as f64 + 0.5) * extent_m[1] / shape.m as f64;
                rates.push(grid.rate_at([x, y]));
            }
        }
        Self::from_rates_at_centres(extent_m, shape, &rates)
    }

    /// Conversion to a grid: λ at the centres of `dims` cells of edge `cell_m` (map frame),
    /// in the grid's linear order (x fastest), with the [`Grid2`].
    pub fn to_rate_grid(
        &self,
        cell_m: f64,
        dims: [usize; 2],
    ) -> Result<(Grid2, Vec<f64>), DctError> {
        positive("cell_m", cell_m)?;
        let grid =
            Grid2::new(Point2::origin(), cell_m, dims).map_err(|e| DctError::InvalidParameter {
                name: "grid",
                reason: e.to_string(),
            })?;
        let rates = (0..grid.num_cells())
            .map(|i| {
                let c = grid.cell_center(grid.cell_from_linear(i));
                self.rate_at([c.x, c.y])
            })
            .collect();
        Ok((grid, rates))
    }
}

/// The initial coefficients of a fit: the grid decay-rate map with `L × M` cells (square
/// cells of edge `min(X/L, Y/M)`) from the same rays, converted by [`DctMap::from_grid`].
pub fn initial_map(extent_m: [f64; 2], shape: Shape, rays: &[MapRay]) -> Result<DctMap, DctError> {
    let cell = (extent_m[0] / shape.l.max(1) as f64).min(extent_m[1] / shape.m.max(1) as f64);
    let dims = [
        (extent_m[0] / cell).ceil().max(1.0) as usize,
        (extent_m[1] / cell).ceil().max(1.0) as usize,
    ];
    let grid = GridRateMap::from_rays(cell, dims, rays)?;
    DctMap::from_grid(extent_m, shape, &grid)
}
