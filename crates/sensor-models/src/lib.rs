//! # raypath-sensor-models
//!
//! Per-cell ray statistics and lidar sensor models for mapping and Monte-Carlo localization,
//! after Schaefer (2020), *Lidar mapping and localization*, **ch. 7** ("decay-rate model")
//! and **ch. 8** ("full map posteriors"); the equations are numbered as in the thesis.
//!
//! ## The idea
//!
//! A lidar ray passes through cells until something reflects it. Every cell `i` keeps three
//! numbers gathered from the mapping rays (algorithm MAP-DECAY, Sec. 7.4.2): the hits `H_i`
//! (rays that ended in it), the misses `M_i` (rays that passed through) and the total path
//! length `R_i` (metres travelled inside it by all rays). Every model below is a function of
//! these numbers, so one map serves them all.
//!
//! * **Decay-rate model** (ch. 7): space is a medium that reflects a ray per metre at the
//!   rate `λ_i`; the ML map is `λ_i = H_i / R_i` (Eq. 7.10) and a return at range `r` has the
//!   density `λ_k · exp(−Σ_i λ_i d_i)` (Eq. 7.13) with `d_i` the in-cell lengths — the
//!   probability of a return depends on how far the ray travels in each cell, not only on
//!   which cells it touches. No-returns have `P(sup) = exp(−Σ λ_i d_i)` up to `r_max`
//!   (Sec. 7.4.4).
//! * **Reflection model** (Hähnel et al. 2003; Sec. 7.5.2): a cell reflects a ray that enters
//!   it with probability `μ_i = H_i / (H_i + M_i)` (Eq. 7.22); turned into a density over the
//!   range by Eq. 7.32. It is the decay-rate model's limit for rays crossing whole cells.
//! * **Full map posteriors (FMP)** (ch. 8): instead of a point estimate, each cell keeps its
//!   posterior, `Beta(H_i + α, M_i + β)` (Eq. 8.15) or `Gamma(H_i + α, R_i + β)` (Eq. 8.17),
//!   with α, β estimated by the method of moments over the whole map (Sec. 8.5); the map is
//!   integrated out in closed form per ray (Eq. 8.20–8.22), which costs no more than the ML
//!   model and never assigns zero probability to a seen measurement.
//! * Baselines users know: the **likelihood field** (AMCL's endpoint model) and **log-odds**
//!   occupancy (OctoMap's update), scored with the same ray likelihood interface.
//!
//! All likelihoods are natural logs; a model may return `−∞` for an impossible reading but
//! never NaN. Frames are REP-103 (x forward, y left, z up), lengths in metres.
//!
//! ## Example
//!
//! Build statistics from a few rays, build a decay-rate model and score a ray:
//!
//! ```
//! use nalgebra::Point2;
//! use raypath_geometry::{Grid2, Range, Ray2};
//! use raypath_sensor_models::{
//!     DecayRateConfig, DecayRateModel2, DenseStats2, MappingConfig, SensorModel,
//! };
//!
//! // A 10 m × 1 m corridor of 0.5 m cells; ten rays along it end 0.1 m into a wall cell at x = 8 m.
//! let grid = Grid2::new(Point2::new(0.0, 0.0), 0.5, [20, 2])?;
//! let mut stats = DenseStats2::planar(grid);
//! let origin = Point2::new(0.25, 0.75);
//! for _ in 0..10 {
//!     stats.insert_ray(&Ray2::from_angle(origin, 0.0, Range::Hit(7.85)), &MappingConfig::default());
//! }
//! let wall = stats.cell(grid.linear_index([16, 1]));
//! assert_eq!((wall.hits(), wall.misses()), (10, 0));
//!
//! // λ = H / R: 10 hits over 10 × 0.1 m in the wall cell, floored at 1e-3 /m elsewhere.
//! let model = DecayRateModel2::new(&stats, DecayRateConfig::default())?;
//! let at_wall = model.ray_log_likelihood(&Ray2::from_angle(origin, 0.0, Range::Hit(7.85)));
//! let in_free_space = model.ray_log_likelihood(&Ray2::from_angle(origin, 0.0, Range::Hit(4.0)));
//! let through_wall = model.ray_log_likelihood(&Ray2::from_angle(origin, 0.0, Range::NoReturn));
//! assert!(at_wall > 1.0 && in_free_space < -6.0); // ln 10 − 1.008 vs ln 1e-3 − 0.004
//! assert!(through_wall < at_wall && through_wall.is_finite());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Map of the crate
//!
//! | item | what |
//! |---|---|
//! | [`CellStats`], [`DenseStats`] / [`SparseStats`] (`…2`, `…3`) | `H`, `M`, `R` per cell, dense or in hashed 16³ blocks; `insert_ray`, `insert_rays_par`, `insert_scans_par`, `insert_clouds_par`, `insert_par` (rayon, per-thread partial maps) |
//! | [`MappingConfig`], [`MappingSummary`] | range limits and no-return handling of map building; counts of what happened to the rays |
//! | [`SensorModel`] | `ray_log_likelihood(&ray_in_map)`, one trait for 2-D and 3-D ([`Planar`], [`Spatial`]) |
//! | [`DecayRateModel`], [`DecayRatePosteriorModel`] | ch. 7 ML map; ch. 8 Gamma posterior |
//! | [`ReflectionModel`] | `maximum_likelihood` (Eq. 7.22) or `posterior` (Beta, Eq. 8.22), both on a [`BernoulliField`] |
//! | [`LogOddsModel`], [`LikelihoodFieldModel`] | OctoMap occupancy; AMCL likelihood field with exact distance transform ([`edt`]) |
//! | [`BetaPrior`], [`GammaPrior`], [`MomentStatistics`] | conjugate priors and their method-of-moments estimates (Sec. 8.5) |
//! | [`Tabulated`], [`OpticalDepthTable`] | O(1) 2-D ray integrals from cumulative optical depth along 360 directions (ML and posterior decay-rate and reflection models, log-odds, likelihood-field normalizer) |
//! | [`ScanLikelihood`], [`PreparedScan`] | (pose, scan or cloud) → summed ray log-likelihood (rays independent, Eq. 7.15) |
//! | [`SensorRange`], [`Reading`] | `r_min`, `r_max` and the classification of a reading as return / `sup` / `sub` (Eq. 7.14) |
//! | [`export`] | ROS `map_server` PGM + YAML, PNG, and the binary `.rpmap` format `raypath map` writes and `raypath localize` reads |
//!
//! `scoring` (when present) holds the Table 7.3 / 8.2 evaluation used by `raypath score-model`.
//!
//! ## Configuration defaults and where they come from
//!
//! | setting | default | source |
//! |---|---|---|
//! | [`SensorRange`] | `r_min = 0`, `r_max = 80 m` | thesis silent; the CARMEN lasers report no-returns at 81.83 / 81.91 m |
//! | [`MappingConfig::include_no_returns`] | `true` | thesis silent; *no-returns in mapping* below |
//! | [`DecayRateConfig`] `min_rate_per_m` | `1e-3` | thesis gives none; *zero rates* below |
//! | [`DecayRateConfig`] `unknown_rate_per_m` | mean observed ML rate | thesis gives none; *unobserved cells* below |
//! | [`ReflectionConfig`] clamps | `μ ∈ [1e-3, 1 − 1e-3]`, unknown = mean ML value | as the two rows above |
//! | [`BetaPosteriorConfig`], [`GammaPosteriorConfig`] `prior` | `None`: method of moments (Sec. 8.5) | Sec. 8.5; *prior moments* below |
//! | [`LogOddsConfig`] | hit 0.7, miss 0.4, clamps 0.12 / 0.97 | OctoMap (Hornung et al. 2013) |
//! | [`LikelihoodFieldConfig`] | `z_hit = z_rand = 0.5`, `σ_hit = 0.2 m`, max distance 2 m, `P(sup) = P(sub) = 0.05`, normalized per ray | AMCL defaults; normalization Sec. 7.6.2 |
//! | [`OpticalDepthConfig`] | 360 directions, 1-cell spacing, blending of the two nearest directions | measured (below) |
//!
//! ## Errata and ambiguities: what is implemented
//!
//! * **Eq. 7.30–7.32** print the integral over `v_i`; we read `v_k`: the density of a return in
//!   cell `k` divides `P(x(r) ∈ v_k)` by the length of the **chord of `v_k`** — and that chord is
//!   **clipped to `[r_min, r_max]`**, so the cell straddling `r_max` puts its whole mass into the
//!   measurable part and densities plus `P(sup)`, `P(sub)` sum to exactly one; chords below `1e-6`
//!   cell edges (corner grazes) are raised to that value.
//! * **No-returns in mapping** (the thesis does not say how they enter the map): no-returns (and
//!   returns at or beyond `r_max`) are traced to `r_max` as pure misses, adding path length but no
//!   hit — exact for both ML maps and conjugate updates; `sub` readings are ignored (no factorizing
//!   likelihood).
//! * **Unobserved cells** (the thesis gives no decay rate for them): cells no ray crossed and space
//!   outside the grid use one "outside" value (mean observed ML value; for the Gamma posterior a
//!   homogeneous medium of rate `κ₀ = (α / c) ln(1 + c/β)`), so probabilities still sum to one off
//!   the map.
//! * **Zero rates** (a cell crossed but never hit has the ML rate 0, so a return in it would
//!   have probability 0): `λ ≥ 1e-3 /m` over the whole map (a proper decay process), `μ`
//!   clamped.
//! * **KL divergences** (the thesis gives neither the ground-truth σ of Sec. 7.6.2 nor the
//!   samples of Sec. 8.5.2): σ = 0.05 m (ch. 8's Applanix accuracy), positions only; a
//!   normalized weighted estimator over the same 50-sample disc — in the scoring code.
//! * **Simulated corridor** (Sec. 8.5.1 leaves open what one measurement of a voxel is): the
//!   corridor's measurement, motion and the MLM floor are recorded in `raypath_sim::corridor` and
//!   in the `mcl` evaluation.
//! * **Prior moments** (Sec. 8.5 does not say which cells enter): moments over observed cells with
//!   a finite ML value; when the moments admit no Beta / Gamma the uniform Beta(1, 1) / an
//!   exponential Gamma(1, 1/E) is used.
//! * **Scan likelihood**: a scan's likelihood is the product of per-ray likelihoods, also under
//!   the map posterior (the thesis's working assumption; strictly, rays sharing cells are
//!   correlated under the posterior).
//! * **Occupancy maps** (ch. 9 only says "cumulate occupancy probabilities along rays"):
//!   log-odds maps are scored as a Bernoulli field with the Eq. 7.32 density, the way the
//!   thesis scores occupancy-style maps.
//! * **Path lengths in fixed point**: `R_i` accumulates in `u64` units of `2^-32` m, so maps
//!   built in parallel are bit-identical for any thread count; counters saturate.
//! * Traversal edge cases: an endpoint outside the grid gives misses only; an endpoint on a
//!   cell face hits the cell of larger index; zero-length crossings are not misses;
//!   zero-length rays record nothing.
//!
//! ## Performance
//!
//! `cargo bench -p raypath-sensor-models --bench likelihood` times ray log-likelihoods per
//! model, exact and tabulated, in 2-D (with `RAYPATH_DATA`: the map of the corrected Intel
//! log) and 3-D; `--bench mapping` times map building from dense and sparse statistics. The
//! optical-depth tables answer a ray in O(1), so they gain most on long rays and for the
//! likelihood field, whose per-ray normalizer is a second integral; on short indoor rays the
//! exact traversal is already cheap. The Gamma posterior costs two logarithms per cell; its
//! table counts every crossed cell at the mean chord of the direction (its miss exponent
//! `a ln(1 + d/b)` is not linear in the length `d`, see [`Tabulated`]), exact for
//! well-observed cells. `tests/real_carmen.rs` checks the tables against the exact models on
//! the Intel map. Measured figures — scoring, inverse KL and the filter updates built on
//! these models — are in `docs/results/sensor-models.md` and `docs/results/mcl.md`.

mod dimension;
pub mod edt;
mod error;
pub mod export;
mod models;
mod optical_depth;
mod reading;
mod scan;
pub mod scoring;
mod stats;

pub use dimension::{Crossing, Dimension, Planar, Spatial};
pub use error::SensorModelError;
pub use models::*;
pub use optical_depth::{OpticalDepthConfig, OpticalDepthTable, Tabulated};
pub use reading::{Reading, SensorRange};
pub use scan::{PreparedScan, ScanLikelihood};
pub use stats::{
    BLOCK_EDGE, CellStats, DenseStats, DenseStats2, DenseStats3, MappingConfig, MappingSummary,
    SparseStats, SparseStats2, SparseStats3,
};
