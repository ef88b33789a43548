//! The ray likelihood of a continuous occupancy field, as the thesis scores GPOMs and Hilbert
//! maps (Sec. 9.5.2): rasterize the field on small square pixels (0.05 m there), ray-trace,
//! and read the occupancy `o_k` of each pixel as the probability that a ray entering it is
//! reflected there — the reflection model, Eq. (7.23):
//!
//! ```text
//! P(return in pixel k) = o_k Π_{i<k} (1 − o_i),        P(no return) = Π_i (1 − o_i).
//! ```
//!
//! A return is a range, so its probability is turned into a **density per metre** as the
//! reflection model relates to the decay-rate model (Eq. 7.25, `λ = q / d`): the mass `o_k`
//! is spread evenly over the chord `d_k` the ray cuts through pixel `k` (from where it enters
//! to where it would leave, not to the return), `p(r) = o_k Π_{i<k}(1 − o_i) / d_k`. Summed
//! over the pixels of a ray, these densities and the no-return probability integrate to one.
//! A ray that only grazes the corner of its end pixel gets a short chord and so a large
//! density — the price of a raster; the thesis does not say how it handled it.
//!
//! Only pixels the ray crosses with positive length count (the traversal reports corner
//! touches with zero length). `sub` readings get `1 − Π(1 − o_i)` over the pixels up to
//! `r_min`.
//!
//! **Clamp.** A classifier's `o` may round to exactly 0 or 1, and one held-back return in a
//! pixel with `o = 0` (or one ray through a pixel with `o = 1`) would make the log-likelihood
//! `−∞`. Occupancies are clamped to `[OCCUPANCY_CLAMP, 1 − OCCUPANCY_CLAMP]`
//! (`1e-3`): a ray then pays at most `ln 1000 ≈ 6.9` nats per pixel it should not have
//! passed, and a return in a "free" pixel at most `6.9 + ln(d_k)`. Not in the thesis.

use nalgebra::{Point2, Unit, Vector2};
use rayon::prelude::*;
use raypath_geometry::Grid2;

use crate::experiment::cells_covering;
use crate::{DctError, MapRay, Outcome};

/// Occupancies are clamped to `[OCCUPANCY_CLAMP, 1 − OCCUPANCY_CLAMP]` before scoring rays.
pub const OCCUPANCY_CLAMP: f64 = 1e-3;

/// A return at most this far beyond the raster's edge (rounding of clipped rays) counts as
/// in the edge pixel (m).
const EDGE_TOLERANCE_M: f64 = 1e-6;

/// Pixels predicted per parallel task when rasterizing.
const CHUNK: usize = 1024;

/// A continuous occupancy probability field over a map frame.
pub trait OccupancyField: Sync {
    /// Writes the occupancy probability at each of `points` (map frame, m) into `out`
    /// (`out.len() == points.len()`).
    fn occupancy(&self, points: &[[f64; 2]], out: &mut [f64]);
}

/// A decay-rate field `λ(x, y)` read as an occupancy field on pixels of edge `pixel_m`:
/// `o = 1 − e^{−λ · pixel}`, the reflection probability of a subvoxel of that size
/// (Eq. 7.27, `ln(1 − q) = −λ l`). Scoring a decay-rate map through this raster is the control
/// that shows what the raster itself costs a map, apart from the map's quality.
#[derive(Clone, Copy, Debug)]
pub struct RateAsOccupancy<F> {
    /// `λ` at a map-frame point (1/m).
    pub rate_at: F,
    /// Pixel edge (m).
    pub pixel_m: f64,
}

impl<F: Fn([f64; 2]) -> f64 + Sync> OccupancyField for RateAsOccupancy<F> {
    fn occupancy(&self, points: &[[f64; 2]], out: &mut [f64]) {
        for (o, p) in out.iter_mut().zip(points) {
            *o = -(-(self.rate_at)(*p) * self.pixel_m).exp_m1();
        }
    }
}

/// An occupancy field sampled at pixel centres, with the reflection-model ray likelihood.
#[derive(Clone, Debug)]
pub struct OccupancyRaster {
    grid: Grid2,
    /// Clamped occupancy per pixel, linear order of the grid (x fastest).
    occupancy: Vec<f64>,
}

impl OccupancyRaster {
    /// Samples `field` at the centres of the square pixels of edge `pixel_m` covering
    /// `extent_m` (map frame, origin at the lower-left corner); pixels are predicted in
    /// parallel chunks.
    pub fn from_field(
        extent_m: [f64; 2],
        pixel_m: f64,
        field: &(impl OccupancyField + ?Sized),
    ) -> Result<Self, DctError> {
        crate::error::positive("pixel_m", pixel_m)?;
        let grid = Grid2::new(Point2::origin(), pixel_m, cells_covering(extent_m, pixel_m))
            .map_err(|e| DctError::InvalidParameter {
                name: "pixel_m",
                reason: e.to_string(),
            })?;
        let centres: Vec<[f64; 2]> = (0..grid.num_cells())
            .map(|i| {
                let c = grid.cell_center(grid.cell_from_linear(i));
                [c.x, c.y]
            })
            .collect();
        let mut occupancy = vec![0.0; centres.len()];
        occupancy
            .par_chunks_mut(CHUNK)
            .zip(centres.par_chunks(CHUNK))
            .for_each(|(out, pts)| field.occupancy(pts, out));
        Self::from_values(grid, occupancy)
    }

    /// A raster from occupancies in the grid's linear order (x fastest); they are clamped.
    pub fn from_values(grid: Grid2, occupancy: Vec<f64>) -> Result<Self, DctError> {
        if occupancy.len() != grid.num_cells() {
            return Err(DctError::InvalidParameter {
                name: "occupancy",
                reason: format!("{} values for {} pixels", occupancy.len(), grid.num_cells()),
            });
        }
        if let Some(i) = occupancy.iter().position(|o| o.is_nan()) {
            return Err(DctError::InvalidParameter {
                name: "occupancy",
                reason: format!("pixel {i} is NaN"),
            });
        }
        let occupancy = occupancy
            .into_iter()
            .map(|o| o.clamp(OCCUPANCY_CLAMP, 1.0 - OCCUPANCY_CLAMP))
            .collect();
        Ok(Self { grid, occupancy })
    }

    /// The pixel grid (map frame).
    pub fn grid(&self) -> &Grid2 {
        &self.grid
    }

    /// Clamped occupancy per pixel (linear order, x fastest).
    pub fn occupancy(&self) -> &[f64] {
        &self.occupancy
    }

    /// The occupancies in lattice order `ix · ny + iy` (for [`crate::render`]).
    pub fn lattice(&self) -> (Vec<f64>, usize, usize) {
        let [nx, ny] = self.grid.dims();
        let mut out = vec![0.0; nx * ny];
        for ix in 0..nx {
            for iy in 0..ny {
                out[ix * ny + iy] = self.occupancy[self.grid.linear_index([ix, iy])];
            }
        }
        (out, nx, ny)
    }

    /// Log-likelihood of one ray (module docs); `−∞` for an invalid ray or a return outside
    /// the raster.
    pub fn ray_log_likelihood(&self, ray: &MapRay) -> f64 {
        if !ray.is_valid() {
            return f64::NEG_INFINITY;
        }
        let origin = Point2::new(ray.origin[0], ray.origin[1]);
        let dir = Unit::new_unchecked(Vector2::new(ray.direction[0], ray.direction[1]));
        match ray.outcome {
            Outcome::Super | Outcome::Sub => {
                let log_pass: f64 = self
                    .grid
                    .traverse(&origin, &dir, ray.length_m)
                    .filter(|c| c.length() > 0.0)
                    .map(|c| (-self.occupancy[c.index]).ln_1p())
                    .sum();
                if ray.outcome == Outcome::Super {
                    log_pass
                } else {
                    (-log_pass.exp_m1()).ln()
                }
            }
            Outcome::Hit => self.hit_log_density(&origin, &dir, ray.length_m),
        }
    }

    /// `ln( o_k Π_{i<k}(1 − o_i) / d_k )` for a return at `r` (Eq. 7.23, 7.25).
    fn hit_log_density(&self, origin: &Point2<f64>, dir: &Unit<Vector2<f64>>, r: f64) -> f64 {
        let mut log_pass = 0.0;
        // The last pixel with positive chord, its exit and the survival before it: a return
        // on the raster's far edge (beyond the last exit by rounding) falls there.
        let mut last: Option<(usize, f64, f64, f64)> = None;
        for c in self.grid.traverse(origin, dir, f64::INFINITY) {
            let d = c.length();
            if d <= 0.0 {
                continue;
            }
            if c.t_exit > r {
                return self.occupancy[c.index].ln() + log_pass - d.ln();
            }
            last = Some((c.index, d, log_pass, c.t_exit));
            log_pass += (-self.occupancy[c.index]).ln_1p();
        }
        match last {
            Some((k, d, before, exit)) if r - exit <= EDGE_TOLERANCE_M => {
                self.occupancy[k].ln() + before - d.ln()
            }
            _ => f64::NEG_INFINITY,
        }
    }

    /// Sum of the ray log-likelihoods (rays scored in parallel, summed in order).
    pub fn log_likelihood(&self, rays: &[MapRay]) -> f64 {
        let each: Vec<f64> = rays
            .par_iter()
            .map(|r| self.ray_log_likelihood(r))
            .collect();
        each.iter().sum()
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // test code: a panic is the failure report
mod tests {
    use super::*;

    fn raster(values: &[f64], pixel: f64) -> OccupancyRaster {
        let grid = Grid2::new(Point2::origin(), pixel, [values.len(), 1]).unwrap();
        OccupancyRaster::from_values(grid, values.to_vec()).unwrap()
    }

    /// One pixel: a return inside it has density `o / d`, a crossing `1 − o`.
    #[test]
    fn one_pixel_closed_form() {
        let r = raster(&[0.3], 0.05);
        let hit = MapRay::from_angle([0.0, 0.025], 0.0, 0.02, Outcome::Hit);
        assert!((r.ray_log_likelihood(&hit) - (0.3f64 / 0.05).ln()).abs() < 1e-12);
        let pass = MapRay::from_angle([0.0, 0.025], 0.0, 0.05, Outcome::Super);
        assert!((r.ray_log_likelihood(&pass) - 0.7f64.ln()).abs() < 1e-12);
    }

    /// Two pixels: a return in the second has `o₂ (1 − o₁) / d₂`; no return
    /// `(1 − o₁)(1 − o₂)`; a ray entering the second pixel obliquely divides by its chord.
    #[test]
    fn two_pixel_closed_form() {
        let (o1, o2) = (0.2, 0.6);
        let r = raster(&[o1, o2], 0.05);
        let hit = MapRay::from_angle([0.0, 0.025], 0.0, 0.075, Outcome::Hit);
        let want = (o2 * (1.0 - o1) / 0.05f64).ln();
        assert!((r.ray_log_likelihood(&hit) - want).abs() < 1e-12);
        let pass = MapRay::from_angle([0.0, 0.025], 0.0, 0.1, Outcome::Super);
        assert!((r.ray_log_likelihood(&pass) - ((1.0 - o1) * (1.0 - o2)).ln()).abs() < 1e-12);
        // From (0, 0.01) at 0.5 rad: leaves pixel 1 at x = 0.05, the raster at y = 0.05.
        let a = 0.5f64;
        let t1 = 0.05 / a.cos();
        let t2 = 0.04 / a.sin();
        let oblique = MapRay::from_angle([0.0, 0.01], a, t1 + 0.5 * (t2 - t1), Outcome::Hit);
        let want = (o2 * (1.0 - o1) / (t2 - t1)).ln();
        assert!((r.ray_log_likelihood(&oblique) - want).abs() < 1e-9);
    }

    /// The densities of returns along a ray and the no-return probability sum to one.
    #[test]
    fn ray_probabilities_integrate_to_one() {
        let r = raster(&[0.1, 0.5, 0.9, 0.3], 0.25);
        let n = 4000;
        let step = 1.0 / n as f64;
        let mass: f64 = (0..n)
            .map(|k| {
                let t = (k as f64 + 0.5) * step;
                let ray = MapRay::from_angle([0.0, 0.1], 0.0, t, Outcome::Hit);
                r.ray_log_likelihood(&ray).exp() * step
            })
            .sum();
        let none = r
            .ray_log_likelihood(&MapRay::from_angle([0.0, 0.1], 0.0, 1.0, Outcome::Super))
            .exp();
        assert!((mass + none - 1.0).abs() < 1e-9, "{mass} + {none}");
    }

    /// Occupancies are clamped: a return in an `o = 0` pixel stays finite.
    #[test]
    fn clamped_occupancy_keeps_scores_finite() {
        let r = raster(&[1.0, 0.0], 0.05);
        assert_eq!(r.occupancy(), &[1.0 - OCCUPANCY_CLAMP, OCCUPANCY_CLAMP]);
        let hit = MapRay::from_angle([0.0, 0.025], 0.0, 0.07, Outcome::Hit);
        let want = (OCCUPANCY_CLAMP * OCCUPANCY_CLAMP / 0.05).ln();
        assert!((r.ray_log_likelihood(&hit) - want).abs() < 1e-9);
        let sub = MapRay::from_angle([0.0, 0.025], 0.0, 0.05, Outcome::Sub);
        assert!((r.ray_log_likelihood(&sub) - (1.0 - OCCUPANCY_CLAMP).ln()).abs() < 1e-12);
    }

    struct Ramp;
    impl OccupancyField for Ramp {
        fn occupancy(&self, points: &[[f64; 2]], out: &mut [f64]) {
            for (o, p) in out.iter_mut().zip(points) {
                *o = p[0] / 10.0;
            }
        }
    }

    /// A constant decay rate through the raster: a ray crossing whole pixels keeps exactly
    /// the decay-rate model's `e^{−λ r}` (Eq. 7.27), a return differs from `λ e^{−λ r}` only by
    /// the chord normalisation.
    #[test]
    fn constant_rate_as_occupancy_matches_the_decay_rate_model() {
        let lambda = 0.7;
        let field = RateAsOccupancy {
            rate_at: |_: [f64; 2]| lambda,
            pixel_m: 0.05,
        };
        let r = OccupancyRaster::from_field([1.0, 1.0], 0.05, &field).unwrap();
        let pass = MapRay::from_angle([0.0, 0.52], 0.0, 1.0, Outcome::Super);
        assert!((r.ray_log_likelihood(&pass) + lambda * 1.0).abs() < 1e-9);
        let hit = MapRay::from_angle([0.0, 0.52], 0.0, 0.5 + 0.025, Outcome::Hit);
        let q: f64 = -(-lambda * 0.05f64).exp_m1();
        let want = (q / 0.05).ln() - lambda * 0.5;
        assert!((r.ray_log_likelihood(&hit) - want).abs() < 1e-9);
        assert!((want - (lambda.ln() - lambda * 0.525)).abs() < 1e-3);
    }

    #[test]
    fn rasterizes_at_pixel_centres() {
        let r = OccupancyRaster::from_field([10.0, 10.0], 0.05, &Ramp).unwrap();
        assert_eq!(r.grid().dims(), [200, 200]);
        let i = r.grid().linear_index([10, 3]);
        assert!((r.occupancy()[i] - 0.525 / 10.0).abs() < 1e-12);
        let (lat, nx, ny) = r.lattice();
        assert_eq!((nx, ny), (200, 200));
        assert_eq!(lat[10 * 200 + 3], r.occupancy()[i]);
    }
}
