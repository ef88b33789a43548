//! # raypath-dct-map
//!
//! Continuous decay-rate maps in the cosine domain — **DCT maps** — after Schaefer (2020),
//! *Lidar mapping and localization*, **ch. 9** ("DCT Maps: Compact Differentiable Lidar Maps
//! Based on the Cosine Transform"); equations are numbered as in the thesis.
//!
//! ## The idea
//!
//! A decay-rate map (ch. 7) says how often a laser ray is reflected per metre, `λ(x, y)`.
//! Instead of one `λ` per grid cell, a DCT map stores `L × M` cosine amplitudes `a_lm` (as
//! JPEG does) and evaluates the **continuous extension of the inverse DCT**, squared so that
//! the rate is never negative (Eq. 9.6):
//!
//! ```text
//! λ(x, y) = ( Σ_lm a_lm cos(l π x / X) cos(m π y / Y) )².
//! ```
//!
//! Along a ray `s + v t` the optical depth `𝒮 = ∫ λ dt` has a closed form (Eq. 9.9–9.10), so
//! a ray's likelihood — `λ(r) e^{−𝒮(r)}` for a return, `1 − e^{−𝒮(r_min)}` for `sub`,
//! `e^{−𝒮}` for `super` (Eq. 9.5, 9.11, 9.12) — comes straight from the coefficients, with
//! no rasterization. The map is the maximum-likelihood coefficient set of Sec. 9.4.4 under
//! a weak prior `−ρ ∬ λ` that keeps `λ` bounded where no ray passes (see "Prior" below),
//! found by Newton's method with analytic derivatives.
//!
//! ## Making it fast (exact rearrangements, not approximations)
//!
//! * `λ = g²` is itself a cosine series with `(2L − 1)(2M − 1)` terms whose coefficients are
//!   the **self-convolution** `b_pq` of `a` ([`self_convolution`]), so a ray integral is
//!   `Σ_pq b_pq T_pq` with closed-form moments `T_pq` ([`moments`]): about `4 I` terms per
//!   ray instead of the `8 I²` of Eq. (9.10) (kept in [`reference`](mod@reference) for the tests).
//! * In a fit every hit and `super` ray enters the likelihood through `−𝒮` with weight one,
//!   so the integral part of the whole data set is `−aᵀ K a` with one Gram matrix `K` of the
//!   summed moments, built once; the hit Hessians `−2 φφᵀ/g²` sum to the same kind of matrix
//!   ([`FitProblem`]). An iteration costs `O(K · I + I²)` plus one dense Cholesky (`faer`).
//!
//! ## Example
//!
//! ```
//! use raypath_dct_map::{DctMap, FitConfig, FitProblem, MapRay, Outcome, Shape, fit, initial_map};
//!
//! // A 4 m × 4 m room, a wall at x = 3 m; rays from (0.5, y) along +x hit it.
//! let extent = [4.0, 4.0];
//! let rays: Vec<MapRay> = (0..40)
//!     .map(|k| MapRay::from_angle([0.5, 0.05 + 0.1 * k as f64], 0.0, 2.5 + 0.01 * (k % 3) as f64, Outcome::Hit))
//!     .collect();
//! let shape = Shape { l: 6, m: 3 };
//! let start = initial_map(extent, shape, &rays)?;
//! let problem = FitProblem::new(extent, shape, &rays)?;
//! let (map, report) = fit(&problem, start.coefficients(), &FitConfig::default())?;
//! assert!(report.log_likelihood() >= report.log_likelihoods[0]);
//! // The wall reflects, the free space in front of it does not.
//! assert!(map.rate_at([3.0, 2.0]) > 5.0 * map.rate_at([1.5, 2.0]));
//! # Ok::<(), raypath_dct_map::DctError>(())
//! ```
//!
//! ## Map of the crate
//!
//! | item | what |
//! |---|---|
//! | [`DctMap`] | coefficients, `λ` at a point in `O(I)`, on a lattice, optical depth, ray log-likelihood |
//! | [`MapRay`], [`Outcome`], [`Patch`], [`RangeLimits`] | rays in the map frame; clipping world rays to a patch |
//! | [`FitProblem`], [`fit`], [`FitConfig`], [`Solver`], [`FitReport`] | ML fit under a weak prior (trust-region Newton or L-BFGS) |
//! | [`derivatives`] | per-ray gradient and Hessian in the thesis's `B`/`C` notation |
//! | [`GridRateMap`], [`initial_map`], [`DctMap::from_grid`], [`DctMap::to_rate_grid`] | the grid baseline (ch. 7) and conversions |
//! | [`render`] | PNG of `p_ref = 1 − e^{−λ}` |
//! | [`experiment`] | patch choice, ray draws, ground truth and the DCT-vs-grid comparison of Sec. 9.5 |
//! | [`baselines`] | GPOM (Matérn) and Hilbert maps (Nyström) with as many parameters, and their rasterized ray likelihood (Sec. 9.5.2) |
//!
//! ## Defaults and where they come from
//!
//! | setting | default | source |
//! |---|---|---|
//! | [`FitConfig::relative_tolerance`] | `1e-3` | Sec. 9.5.3 |
//! | [`FitConfig::solver`] | trust-region Newton | thesis names trust-region methods; measured faster than L-BFGS at equal likelihood (`docs/results/dct.md`) |
//! | initialization | grid decay-rate map with `L × M` cells, `√λ` transformed | thesis silent; never `𝒜 = 0` (a saddle) |
//! | [`RangeLimits`] | `r_min = 0`, `r_max = ∞` | CARMEN logs have no `sub` readings; no-returns are decoded by the reader |
//! | [`RIDGE_FACTOR`] | `δ = 1e-10 · max K_ii` | not in the thesis; numerical safeguard (below) |
//! | [`PRIOR_PATH_DENSITY`] | `ρ = 1 /m` (prior `−ρ ∬ λ dx dy`) | not in ch. 9 (bare ML); the rate part of the gamma prior of Sec. 8.4.3, made continuous (below) |
//! | [`baselines::GpomConfig`] | Matérn 3/2, `σ_f = 1`, `(ℓ, σ_n)` by marginal likelihood over `{0.2, 0.5, 1, 2} m × {0.1, 0.3, 1}` | thesis: Jadidi et al.'s settings, not listed; grid search on the mapping rays only |
//! | [`baselines::HilbertConfig`] | RBF `γ = 1 /m²`, L2 `α = 1e-4`, ≤ 20 000 training points | Ramos & Ott's published code defaults (their SGD replaced by L-BFGS) |
//! | [`baselines::TrainingConfig`] | one free point per 2 m of beam (≥ 1), 0.1 m off the return | Ramos & Ott's published code |
//! | [`experiment::BASELINE_PIXEL_M`], [`baselines::OCCUPANCY_CLAMP`] | 0.05 m raster; occupancy clamped to `[1e-3, 1 − 1e-3]` | Sec. 9.5.2; the clamp is not in the thesis |
//!
//! ## Errata and decisions
//!
//! * **Eq. (9.7)** lacks the `cos` around its argument; implemented with it (factor `1/8`).
//! * **`sub` Hessian** (Sec. 9.4.4): the printed `+ 𝒩² C_i C_j/(1 − 𝒩)²` must be `−`; see
//!   [`derivatives`], whose test shows the printed form failing finite differences.
//! * `C_i = ⅛ Σ_j a_j Σ A_ij + A_ji` is read as `Σ (A_ij + A_ji)`.
//! * Map frame: `x̃ = π x / X` with `x` measured from the patch's lower-left corner.
//! * **Eq. (9.10) taken literally is unstable** for nearly axis-parallel rays: a direction such as
//!   `(cos π/2, −1) = (6e-17, −1)` gives `ω ≈ 1e-17 ≠ 0`, and `(sin(φ + ωr) − sin φ)/ω` divides
//!   rounding noise by it. The `sinc` form `r cos(φ + ωr/2) sinc(ωr/2)` (the same integral,
//!   rewritten) is used everywhere; the literal form is kept in [`reference`](mod@reference) and
//!   the test shows the difference.
//! * **Ridge.** The thesis maximizes the bare likelihood. With fewer rays than coefficients
//!   (its own 500-ray timing sets at 40 × 40) the Gram matrix has near-null directions, and
//!   along them the rounding error of `aᵀ K a` let Newton's method "increase" the likelihood
//!   without bound (on the aces log of `cargo xtask eval dct`). A ridge `−δ ‖a‖²` with
//!   `δ = 1e-10 · max K_ii` ([`FitProblem::set_ridge_factor`]) stops it; on 10⁴ rays it
//!   changes the log-likelihood by well under one nat per thousand rays.
//! * **Prior** ([`FitProblem::set_prior_path_density`], default [`PRIOR_PATH_DENSITY`]
//!   `ρ = 1 /m`). The thesis maximizes the bare likelihood (Sec. 9.4.4) and, in Sec. 9.5.2,
//!   scores maps on the rays they were built from. The likelihood does not constrain `λ`
//!   where no mapping ray passes (behind walls, in patch corners, in gaps between scans —
//!   the "random values" in unexplored areas of Sec. 3.3, the missing "unexplored areas" of
//!   Sec. 9.6), and the ML fit parks huge rates there: on the CARMEN patches of `cargo xtask
//!   eval dct` the largest maps hold holes and corners that no mapping ray enters with rates
//!   many orders of magnitude above the walls', and one held-back no-return ray crossing such
//!   a hole can outweigh every other ray of the log. It is not `λ → 0` (Eq. 9.6 squares `g`,
//!   so `λ ≥ 0`; the held-back *hits* on those maps score as usual), nor an early stop (a
//!   much tighter relative tolerance gives the same maps). The numerical ridge above is a prior
//!   of this kind, but `δ ≈ 2.5·10⁻⁶` there amounts to `ρ ≈ 10⁻⁷ /m`. The fix is a prior of
//!   physical size:
//!   the rate part `β` of the conjugate gamma prior on decay rates of Sec. 8.4.3 (Eq. 8.17,
//!   `Gamma(H + α, R + β)`: `β` metres of virtual unreflected path per voxel) made
//!   continuous, `ln p(𝒜) = −ρ ∬ λ dx dy`, i.e. `ρ` metres of virtual no-return ray per m²
//!   everywhere — on 10 m × 10 m about 10 rays crossing the patch, against 10⁴ mapping
//!   rays. By Parseval it is a diagonal ridge on `a`, so a fit costs the same. (The shape
//!   part `α` has no closed form for a continuous map and, with `α < 1` as Sec. 8.5's
//!   moment matching gives on these logs, would reward `λ → 0`; it is not used.)
//!   On the logs of `cargo xtask eval dct` the prior lifts the largest DCT maps above the
//!   grid on held-back rays, moves the smaller sizes little and leaves the RMSE of `p_ref`
//!   as it was; the held-back figures of the default are in `docs/results/dct.md`. Much
//!   weaker densities leave some of the holes; `ρ` around 1 /m is flat; the empirical-Bayes
//!   `β` of Sec. 8.5 (moment matching on the `L × M` grid), per cell area, varies by orders
//!   of magnitude between logs and sizes, so a fixed density was chosen. `0` restores the
//!   thesis's plain ML fit.
//! * **Solver.** Trust-region Newton (Levenberg–Marquardt damping on the exact Hessian, with
//!   step doubling while the quadratic model is accurate) is the default: it reaches the
//!   thesis's stopping rule in 4–6 iterations, while L-BFGS stops early under the same
//!   relative rule at a much lower likelihood (see `docs/results/dct.md`, Table 9.4).
//! * Rays are clipped to the patch ([`ray`] module docs): the likelihood is conditioned on a
//!   ray reaching the patch, and rays crossing it without a return are `super` rays whose
//!   `r_max` is the exit point.

#![warn(missing_docs)]

pub mod baselines;
pub mod derivatives;
mod error;
pub mod experiment;
mod fit;
mod grid;
mod lbfgs;
mod map;
pub mod moments;
mod objective;
pub mod ray;
pub mod reference;
pub mod render;
mod spectrum;

pub use error::DctError;
pub use fit::{FitConfig, FitReport, Solver, fit};
pub use grid::{GridRateMap, initial_map};
pub use map::DctMap;
pub use objective::{Evaluation, FitProblem, PRIOR_PATH_DENSITY, RIDGE_FACTOR};
pub use ray::{MapRay, Outcome, Patch, RangeLimits};
pub use spectrum::{
    Shape, fill_product_matrix, product_matrix, product_matrix_times, self_convolution,
};
