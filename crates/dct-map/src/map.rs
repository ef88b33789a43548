//! [`DctMap`]: the decay-rate field `λ(x, y) = (Σ_lm a_lm cos(l x̃) cos(m ỹ))²` (Eq. 9.6).

use serde::{Deserialize, Serialize};

use crate::error::positive;
use crate::moments::{add_moments, cosines};
use crate::spectrum::self_convolution;
use crate::{DctError, MapRay, Outcome, Shape};

/// A DCT decay-rate map over `[0, X] × [0, Y]` (map frame, metres) with `L × M`
/// coefficients `a_lm` (row-major `l · M + m`; `l` counts x frequencies, `m` y frequencies).
///
/// `λ(x, y) = g(x, y)²` with `g = Σ_lm a_lm cos(l π x / X) cos(m π y / Y)`: the continuous
/// extension of the inverse DCT-II (CEIDCT), squared so that `λ ≥ 0` (Eq. 9.6). The map
/// also caches the self-convolution `b_pq` of the coefficients, which makes a ray integral
/// cost `(2L − 1)(2M − 1)` closed-form terms instead of the `8 I²` of Eq. (9.10).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DctMap {
    extent_m: [f64; 2],
    shape: Shape,
    coefficients: Vec<f64>,
    #[serde(skip)]
    b: Vec<f64>,
}

impl DctMap {
    /// A map of extent `extent_m = [X, Y]` (m) with `L × M = shape` coefficients `a`
    /// (row-major). Fails on non-positive extents, an empty shape, a length mismatch or
    /// non-finite coefficients.
    pub fn new(extent_m: [f64; 2], shape: Shape, coefficients: Vec<f64>) -> Result<Self, DctError> {
        positive("extent_m[0]", extent_m[0])?;
        positive("extent_m[1]", extent_m[1])?;
        if shape.is_empty() {
            return Err(DctError::InvalidParameter {
                name: "shape",
                reason: format!(
                    "needs at least one coefficient, got {} × {}",
                    shape.l, shape.m
                ),
            });
        }
        if coefficients.len() != shape.len() {
            return Err(DctError::InvalidParameter {
                name: "coefficients",
                reason: format!(
                    "{} values for {} × {} coefficients",
                    coefficients.len(),
                    shape.l,
                    shape.m
                ),
            });
        }
        if let Some(i) = coefficients.iter().position(|a| !a.is_finite()) {
            return Err(DctError::InvalidParameter {
                name: "coefficients",
                reason: format!("coefficient {i} is not finite"),
            });
        }
        let b = self_convolution(shape, &coefficients);
        Ok(Self {
            extent_m,
            shape,
            coefficients,
            b,
        })
    }

    /// Restores the cached spectrum after deserialization (serde skips it).
    pub fn revalidated(self) -> Result<Self, DctError> {
        Self::new(self.extent_m, self.shape, self.coefficients)
    }

    /// Extent `[X, Y]` in metres.
    pub fn extent_m(&self) -> [f64; 2] {
        self.extent_m
    }

    /// The coefficient shape `L × M`.
    pub fn shape(&self) -> Shape {
        self.shape
    }

    /// The coefficients `a_lm`, row-major.
    pub fn coefficients(&self) -> &[f64] {
        &self.coefficients
    }

    /// The self-convolution `b_pq` (row-major, `(2L − 1) × (2M − 1)`).
    pub fn spectrum(&self) -> &[f64] {
        &self.b
    }

    /// `g(x, y) = Σ a_lm cos(l x̃) cos(m ỹ)` (the unsquared CEIDCT) at a map-frame point. `O(I)`.
    pub fn amplitude_at(&self, p: [f64; 2]) -> f64 {
        let cy: Vec<f64> = cosines(self.shape.m, p[1], self.extent_m[1]).collect();
        cosines(self.shape.l, p[0], self.extent_m[0])
            .zip(self.coefficients.chunks_exact(self.shape.m))
            .map(|(cx, row)| cx * row.iter().zip(&cy).map(|(a, c)| a * c).sum::<f64>())
            .sum()
    }

    /// The decay rate `λ(x, y)` in 1/m at a map-frame point (Eq. 9.6). `O(I)`.
    pub fn rate_at(&self, p: [f64; 2]) -> f64 {
        let g = self.amplitude_at(p);
        g * g
    }

    /// `λ` at the centres of an `nx × ny` lattice over the map (row-major `ix · ny + iy`),
    /// separable: `O(nx · L · M + nx · ny · M)`.
    pub fn rates_on_lattice(&self, nx: usize, ny: usize) -> Vec<f64> {
        let (lm, mm) = (self.shape.l, self.shape.m);
        let cx: Vec<Vec<f64>> = (0..nx)
            .map(|i| {
                let x = (i as f64 + 0.5) * self.extent_m[0] / nx as f64;
                cosines(lm, x, self.extent_m[0]).collect()
            })
            .collect();
        let cy: Vec<Vec<f64>> = (0..ny)
            .map(|j| {
                let y = (j as f64 + 0.5) * self.extent_m[1] / ny as f64;
                cosines(mm, y, self.extent_m[1]).collect()
            })
            .collect();
        let mut out = Vec::with_capacity(nx * ny);
        for cxi in &cx {
            // w_m = Σ_l cos(l x̃) a_lm
            let mut w = vec![0.0; mm];
            for (c, row) in cxi.iter().zip(self.coefficients.chunks_exact(mm)) {
                w.iter_mut().zip(row).for_each(|(w, a)| *w += c * a);
            }
            for cyj in &cy {
                let g: f64 = w.iter().zip(cyj).map(|(w, c)| w * c).sum();
                out.push(g * g);
            }
        }
        out
    }

    /// The optical depth `𝒮 = ∫_0^r λ(s + v t) dt` of a segment (Eq. 9.9–9.10), through the
    /// self-convolution: `Σ_pq b_pq T_pq` with the closed-form moments `T_pq` (an exact
    /// rearrangement of Eq. 9.10, not in the thesis).
    pub fn optical_depth(&self, ray: &MapRay) -> f64 {
        let mut t = vec![0.0; self.b.len()];
        add_moments(self.shape, self.extent_m, &ray.segment(), 1.0, &mut t);
        t.iter().zip(&self.b).map(|(t, b)| t * b).sum()
    }

    /// The natural-log likelihood of one ray (Sec. 9.4.4):
    /// `ln λ(r) − 𝒮(r)` for a hit, `ln(1 − e^{−𝒮(r_min)})` for `sub`, `−𝒮` for `super`.
    /// `−∞` where the probability is zero, never NaN for a valid ray.
    pub fn ray_log_likelihood(&self, ray: &MapRay) -> f64 {
        let s = self.optical_depth(ray);
        let value = match ray.outcome {
            Outcome::Hit => self.rate_at(ray.end()).ln() - s,
            Outcome::Sub => (-(-s).exp_m1()).ln(), // ln(1 − 𝒩), Eq. (9.11)
            Outcome::Super => -s,                  // Eq. (9.12)
        };
        if value.is_nan() {
            f64::NEG_INFINITY
        } else {
            value
        }
    }

    /// Sum of [`ray_log_likelihood`](Self::ray_log_likelihood) over rays (rays independent).
    pub fn log_likelihood(&self, rays: &[MapRay]) -> f64 {
        use rayon::prelude::*;
        rays.par_iter().map(|r| self.ray_log_likelihood(r)).sum()
    }
}
