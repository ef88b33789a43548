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
//!
//! The optimized objective adds a log-prior to the log-likelihood: the prior
//! `−ρ ∬ λ dx dy` ([`FitProblem::set_prior_path_density`]) and the numerical ridge
//! `−δ ‖a‖²` ([`FitProblem::set_ridge_factor`]). Both are diagonal quadratics in `a`
//! (the prior by Parseval), so they add `2 w_i` to the Hessian's diagonal and keep its
//! structure; [`FitProblem::log_prior`] returns their value.

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
    /// Path-length density `ρ` (1/m) of the prior `−ρ ∬ λ dx dy`.
    prior: f64,
    /// `w_i` of the log-prior `−Σ_i w_i a_i²` (ridge plus prior, by Parseval).
    penalty: Vec<f64>,
}

/// Default ridge factor: `δ = RIDGE_FACTOR · max_i K_ii` (see [`FitProblem::set_ridge_factor`]).
pub const RIDGE_FACTOR: f64 = 1e-10;

/// Default path-length density `ρ = 1 /m` of the prior `−ρ ∬ λ dx dy` (see
/// [`FitProblem::set_prior_path_density`]): one metre of virtual, unreflected ray per square
/// metre — on a 10 m × 10 m patch as much as 10 rays crossing it, against the 10⁴ mapping
/// rays of Sec. 9.5.
pub const PRIOR_PATH_DENSITY: f64 = 1.0;

/// Value, gradient (and optionally Hessian) of the objective at one point.
#[derive(Clone, Debug)]
pub struct Evaluation {
    /// The objective `Σ_k ln p(z_k | 𝒜) + ln p(𝒜)`: the log-likelihood plus the log-prior
    /// ([`FitProblem::log_prior`]).
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
        let mut problem = Self {
            ridge: RIDGE_FACTOR * max_diag,
            prior: PRIOR_PATH_DENSITY,
            penalty: Vec::new(),
            shape,
            extent_m,
            t_total,
            k_total,
            hit_cx,
            hit_cy,
            subs,
            rays: rays.len(),
        };
        problem.update_penalty();
        Ok(problem)
    }

    fn update_penalty(&mut self) {
        let area = self.extent_m[0] * self.extent_m[1];
        let half = |k: usize| if k == 0 { 1.0 } else { 0.5 };
        let mm = self.shape.m;
        self.penalty = (0..self.shape.len())
            .map(|i| self.ridge + self.prior * area * half(i / mm) * half(i % mm))
            .collect();
    }

    fn penalty_value(&self, a: &[f64]) -> f64 {
        a.iter().zip(&self.penalty).map(|(a, w)| w * a * a).sum()
    }

    /// The log-prior `−ρ ∬ λ dx dy − δ ‖a‖²` at `a` (up to a constant): what the fit's
    /// objective ([`log_likelihood`](Self::log_likelihood), [`evaluate`](Self::evaluate),
    /// [`FitReport::log_likelihoods`](crate::FitReport::log_likelihoods)) adds to the
    /// log-likelihood of the rays.
    pub fn log_prior(&self, a: &[f64]) -> f64 {
        -self.penalty_value(a)
    }

    /// Sets the path-length density `ρ` (1/m, metres of ray per m²) of the prior
    /// `ln p(𝒜) = −ρ ∬ λ(x, y) dx dy + const` over the map (`0`: the thesis's plain
    /// likelihood; default [`PRIOR_PATH_DENSITY`]).
    ///
    /// It is the rate half of the conjugate gamma prior of Sec. 8.4.3 (Eq. 8.17: the belief
    /// `Gamma(H_i + α, R_i + β)` counts `β` metres of virtual ray path in every voxel) made
    /// continuous: as if rays of total length `ρ` per m² had crossed every part of the map
    /// without reflection. Where real rays pass (hundreds of metres per m² in the
    /// experiments) it is negligible; where none pass — behind walls, in corners, in gaps
    /// between scans — it is all that constrains `λ`, and without it the ML fit parks
    /// arbitrarily large rates there (`λ` up to 10⁴–10⁷ /m on the CARMEN patches, see the
    /// crate docs' "Prior" entry). By Parseval it is a diagonal ridge,
    /// `∬ g² = X Y Σ_lm c_l c_m a_lm²` with `c_0 = 1`, `c_{k>0} = ½`, so it adds nothing to
    /// the cost of a fit. Negative or non-finite values are treated as `0`.
    pub fn set_prior_path_density(&mut self, rho_per_m: f64) {
        self.prior = if rho_per_m.is_finite() {
            rho_per_m.max(0.0)
        } else {
            0.0
        };
        self.update_penalty();
    }

    /// The prior's path-length density `ρ` (1/m).
    pub fn prior_path_density(&self) -> f64 {
        self.prior
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
        self.update_penalty();
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

    /// The objective: the log-likelihood `Σ ln g_k² − aᵀ K a + Σ_sub ln(1 − e^{−𝒮_k})`
    /// (Sec. 9.4.4) plus the [`log_prior`](Self::log_prior).
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
        let v = hits - quad + subs - self.penalty_value(a);
        if v.is_nan() { f64::NEG_INFINITY } else { v }
    }

    /// Objective (log-likelihood plus log-prior) and its gradient. `O(K · I + I²)` plus
    /// `O(I²)` per `sub` ray.
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
            .zip(a.iter().zip(&self.penalty))
            .for_each(|((g, k), (a, w))| *g -= 2.0 * (k + w * a));
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
        let v = hits - quad + subs - self.penalty_value(a);
        Evaluation {
            log_likelihood: if v.is_nan() { f64::NEG_INFINITY } else { v },
            gradient,
            amplitudes: g,
        }
    }

    /// The Hessian of the **negative** objective, row-major `I × I`, at `a` with hit
    /// amplitudes `g` (from [`evaluate`](Self::evaluate)): `2 K(T + U)` plus the `sub` terms
    /// (corrected erratum, see [`crate::derivatives`]) plus the log-prior's diagonal `2 w_i`.
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
        for (i, w) in self.penalty.iter().enumerate() {
            h[i * n + i] += 2.0 * w;
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
