//! The ML objective of a whole ray set, aggregated so that an evaluation costs `O(K · I + I²)`
//! instead of `O(K · 8 I²)`.
//!
//! For hits and `super` rays the log-likelihood's integral part is `−𝒮_k` with weight one,
//! so it sums to `−aᵀ K a` with `K` the [`product_matrix`] of the **summed** moments
//! `T = Σ_k T_k`, computed once before the optimization. The hit terms
//! `ln λ(e_k) = ln g_k²` need the basis at the endpoints (`O(I)` each), and their Hessian
//! `−2 φ_k φ_kᵀ / g_k²` sums to `−2 K(U)` with `U_pq = Σ_k cos(p x̃_k) cos(q ỹ_k) / g_k²` —
//! the same product-to-sum trick, so the full Hessian is `−2 K(T + U)` plus the rare `sub`
//! terms. Without `sub` rays the negative log-likelihood is therefore convex on every
//! region where the signs of all `g_k` are fixed (a log barrier at `g_k = 0`).

use rayon::prelude::*;

use crate::moments::{add_moments, cosines, moments};
use crate::spectrum::{
    fill_product_matrix, product_matrix, product_matrix_times, self_convolution,
};
use crate::{DctError, MapRay, Outcome, Shape};

/// Rays of a fit, pre-processed: summed moments, endpoint cosines, `sub` moments.
#[derive(Clone, Debug)]
pub struct FitProblem {
    shape: Shape,
    extent_m: [f64; 2],
    /// `Σ_k T_k` over hits and `super` rays (length `P · Q`).
    t_total: Vec<f64>,
    /// `K(t_total)`, row-major `I × I`.
    k_total: Vec<f64>,
    /// `cos(p x̃)` at each hit endpoint, `p < P` (hit-major).
    hit_cx: Vec<f64>,
    /// `cos(q ỹ)` at each hit endpoint, `q < Q`.
    hit_cy: Vec<f64>,
    /// Moments of each `sub` ray.
    subs: Vec<Vec<f64>>,
    rays: usize,
    /// Weight `δ` of the ridge `−δ ‖a‖²` added to the log-likelihood.
    ridge: f64,
}

/// Default ridge factor: `δ = RIDGE_FACTOR · max_i K_ii` (see [`FitProblem::set_ridge_factor`]).
pub const RIDGE_FACTOR: f64 = 1e-10;

/// Value, gradient (and optionally Hessian) of the log-likelihood at one point.
#[derive(Clone, Debug)]
pub struct Evaluation {
    /// `Σ_k ln p(z_k | 𝒜)`.
    pub log_likelihood: f64,
    /// Its gradient.
    pub gradient: Vec<f64>,
    /// `g_k` at the hit endpoints.
    pub amplitudes: Vec<f64>,
}

impl FitProblem {
    /// Pre-processes `rays` (map frame) for a map of `extent_m` and `shape`; invalid rays are
    /// rejected with their index. Parallel over rays.
    pub fn new(extent_m: [f64; 2], shape: Shape, rays: &[MapRay]) -> Result<Self, DctError> {
        if shape.is_empty() {
            return Err(DctError::InvalidParameter {
                name: "shape",
                reason: "needs at least one coefficient".into(),
            });
        }
        if let Some(i) = rays.iter().position(|r| !r.is_valid()) {
            return Err(DctError::InvalidParameter {
                name: "rays",
                reason: format!("ray {i} has a non-finite or non-positive length or direction"),
            });
        }
        if rays.is_empty() {
            return Err(DctError::NoData("no rays to fit".into()));
        }
        let (pn, qn) = (shape.p(), shape.q());
        let t_total = rays
            .par_chunks(64)
            .fold(
                || vec![0.0; pn * qn],
                |mut acc, chunk| {
                    for r in chunk.iter().filter(|r| r.outcome != Outcome::Sub) {
                        add_moments(shape, extent_m, &r.segment(), 1.0, &mut acc);
                    }
                    acc
                },
            )
            .reduce(
                || vec![0.0; pn * qn],
                |mut a, b| {
                    a.iter_mut().zip(&b).for_each(|(a, b)| *a += b);
                    a
                },
            );
        let hits: Vec<&MapRay> = rays.iter().filter(|r| r.outcome == Outcome::Hit).collect();
        let mut hit_cx = Vec::with_capacity(hits.len() * pn);
        let mut hit_cy = Vec::with_capacity(hits.len() * qn);
        for r in &hits {
            let e = r.end();
            hit_cx.extend(cosines(pn, e[0], extent_m[0]));
            hit_cy.extend(cosines(qn, e[1], extent_m[1]));
        }
        let subs = rays
            .iter()
            .filter(|r| r.outcome == Outcome::Sub)
            .map(|r| moments(shape, extent_m, &r.segment()))
            .collect();
        let k_total = product_matrix(shape, &t_total);
        let n = shape.len();
        let max_diag = (0..n).map(|i| k_total[i * n + i]).fold(0.0, f64::max);
        Ok(Self {
            ridge: RIDGE_FACTOR * max_diag,
            shape,
            extent_m,
            t_total,
            k_total,
            hit_cx,
            hit_cy,
            subs,
            rays: rays.len(),
        })
    }

    /// Sets the ridge to `factor · max_i K_ii` (`0` for the plain likelihood).
    ///
    /// The thesis optimizes the bare likelihood. With fewer rays than coefficients the Gram
    /// matrix `K` has directions of near-zero curvature (coefficient combinations that live
    /// where no ray passes), and along them the rounding error of `aᵀ K a` (relative
    /// `~1e-16 ‖K‖ ‖a‖²`) can turn negative: the optimizer then "increases" the likelihood
    /// without bound by growing `a`. A ridge `δ ‖a‖²` with `δ = 1e-10 · max K_ii`
    /// ([`RIDGE_FACTOR`], a weak Gaussian prior far below any data term) removes that
    /// numerical escape while changing well-posed fits negligibly.
    pub fn set_ridge_factor(&mut self, factor: f64) {
        let n = self.shape.len();
        let max_diag = (0..n).map(|i| self.k_total[i * n + i]).fold(0.0, f64::max);
        self.ridge = factor.max(0.0) * max_diag;
    }

    /// The ridge weight `δ` (log-likelihood `− δ ‖a‖²`).
    pub fn ridge(&self) -> f64 {
        self.ridge
    }

    /// The coefficient shape.
    pub fn shape(&self) -> Shape {
        self.shape
    }

    /// The map extent.
    pub fn extent_m(&self) -> [f64; 2] {
        self.extent_m
    }

    /// Number of rays.
    pub fn rays(&self) -> usize {
        self.rays
    }

    /// Number of hits.
    pub fn hits(&self) -> usize {
        self.hit_cx.len() / self.shape.p().max(1)
    }

    /// `g_k` at every hit endpoint. `O(K · I)`, parallel.
    pub fn amplitudes(&self, a: &[f64]) -> Vec<f64> {
        let (lm, mm, pn, qn) = (self.shape.l, self.shape.m, self.shape.p(), self.shape.q());
        self.hit_cx
            .par_chunks_exact(pn)
            .zip(self.hit_cy.par_chunks_exact(qn))
            .map(|(cx, cy)| {
                a.chunks_exact(mm)
                    .zip(&cx[..lm])
                    .map(|(row, c)| c * row.iter().zip(&cy[..mm]).map(|(a, c)| a * c).sum::<f64>())
                    .sum()
            })
            .collect()
    }

    fn quadratic(&self, a: &[f64]) -> Vec<f64> {
        let n = self.shape.len();
        self.k_total
            .par_chunks_exact(n)
            .map(|row| row.iter().zip(a).map(|(k, a)| k * a).sum())
            .collect()
    }

    /// The log-likelihood `Σ ln g_k² − aᵀ K a + Σ_sub ln(1 − e^{−𝒮_k})` (Sec. 9.4.4).
    pub fn log_likelihood(&self, a: &[f64]) -> f64 {
        let g = self.amplitudes(a);
        let ka = self.quadratic(a);
        let quad: f64 = ka.iter().zip(a).map(|(k, a)| k * a).sum();
        let hits: f64 = g.par_iter().map(|g| (g * g).ln()).sum();
        let subs: f64 = if self.subs.is_empty() {
            0.0
        } else {
            let b = self_convolution(self.shape, a);
            self.subs
                .iter()
                .map(|t| {
                    let s: f64 = t.iter().zip(&b).map(|(t, b)| t * b).sum();
                    (-(-s).exp_m1()).ln()
                })
                .sum()
        };
        let v = hits - quad + subs - self.ridge * a.iter().map(|a| a * a).sum::<f64>();
        if v.is_nan() { f64::NEG_INFINITY } else { v }
    }

    /// Log-likelihood and gradient. `O(K · I + I²)` plus `O(I²)` per `sub` ray.
    pub fn evaluate(&self, a: &[f64]) -> Evaluation {
        let (n, lm, mm, pn, qn) = (
            self.shape.len(),
            self.shape.l,
            self.shape.m,
            self.shape.p(),
            self.shape.q(),
        );
        let g = self.amplitudes(a);
        let ka = self.quadratic(a);
        let quad: f64 = ka.iter().zip(a).map(|(k, a)| k * a).sum();
        let hits: f64 = g.par_iter().map(|g| (g * g).ln()).sum();
        // ∂ ln g² / ∂a_lm = 2 φ_lm / g (= B_i / λ); ∂(−aᵀKa) = −2 K a (= −C_i summed).
        let mut gradient = self
            .hit_cx
            .par_chunks_exact(pn)
            .zip(self.hit_cy.par_chunks_exact(qn))
            .zip(g.par_iter())
            .fold(
                || vec![0.0; n],
                |mut acc, ((cx, cy), g)| {
                    let w = 2.0 / g;
                    for (l, row) in acc.chunks_exact_mut(mm).enumerate().take(lm) {
                        let c = w * cx[l];
                        row.iter_mut()
                            .zip(&cy[..mm])
                            .for_each(|(o, cy)| *o += c * cy);
                    }
                    acc
                },
            )
            .reduce(
                || vec![0.0; n],
                |mut x, y| {
                    x.iter_mut().zip(&y).for_each(|(x, y)| *x += y);
                    x
                },
            );
        gradient
            .iter_mut()
            .zip(&ka)
            .for_each(|(g, k)| *g -= 2.0 * k);
        let mut subs = 0.0;
        if !self.subs.is_empty() {
            let b = self_convolution(self.shape, a);
            for t in &self.subs {
                let s: f64 = t.iter().zip(&b).map(|(t, b)| t * b).sum();
                let one_minus = -(-s).exp_m1();
                subs += one_minus.ln();
                // 𝒩 C_i / (1 − 𝒩) with C_i = 2 (K_k a)_i.
                let w = 2.0 / s.exp_m1();
                let kv = product_matrix_times(self.shape, t, a);
                gradient.iter_mut().zip(&kv).for_each(|(g, k)| *g += w * k);
            }
        }
        let v = hits - quad + subs - self.ridge * a.iter().map(|a| a * a).sum::<f64>();
        Evaluation {
            log_likelihood: if v.is_nan() { f64::NEG_INFINITY } else { v },
            gradient,
            amplitudes: g,
        }
    }

    /// The Hessian of the **negative** log-likelihood, row-major `I × I`, at `a` with hit
    /// amplitudes `g` (from [`evaluate`](Self::evaluate)): `2 K(T + U)` plus the `sub` terms
    /// (corrected erratum, see [`crate::derivatives`]).
    pub fn negative_hessian(&self, a: &[f64], g: &[f64]) -> Vec<f64> {
        let (n, pn, qn) = (self.shape.len(), self.shape.p(), self.shape.q());
        let u = self
            .hit_cx
            .par_chunks_exact(pn)
            .zip(self.hit_cy.par_chunks_exact(qn))
            .zip(g.par_iter())
            .fold(
                || vec![0.0; pn * qn],
                |mut acc, ((cx, cy), g)| {
                    let w = 1.0 / (g * g);
                    for (row, c) in acc.chunks_exact_mut(qn).zip(cx) {
                        let c = w * c;
                        row.iter_mut().zip(cy).for_each(|(o, cy)| *o += c * cy);
                    }
                    acc
                },
            )
            .reduce(
                || vec![0.0; pn * qn],
                |mut x, y| {
                    x.iter_mut().zip(&y).for_each(|(x, y)| *x += y);
                    x
                },
            );
        let sum: Vec<f64> = self
            .t_total
            .iter()
            .zip(&u)
            .map(|(t, u)| 2.0 * (t + u))
            .collect();
        let mut h = vec![0.0; n * n];
        fill_product_matrix(self.shape, &sum, |i, j, v| h[i * n + j] = v);
        for i in 0..n {
            h[i * n + i] += 2.0 * self.ridge;
        }
        if !self.subs.is_empty() {
            let b = self_convolution(self.shape, a);
            for t in &self.subs {
                let s: f64 = t.iter().zip(&b).map(|(t, b)| t * b).sum();
                let one_minus = -(-s).exp_m1();
                let nn = (-s).exp();
                let w = nn / one_minus;
                let c_i: Vec<f64> = product_matrix_times(self.shape, t, a)
                    .iter()
                    .map(|v| 2.0 * v)
                    .collect();
                let wc = nn / (one_minus * one_minus);
                fill_product_matrix(self.shape, t, |i, j, k| {
                    // −(𝒩 C_ij/(1−𝒩) − 𝒩 C_i C_j/(1−𝒩)²)
                    h[i * n + j] -= w * 2.0 * k - wc * c_i[i] * c_i[j];
                });
            }
        }
        h
    }
}
