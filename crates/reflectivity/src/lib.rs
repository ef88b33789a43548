//! # raypath-reflectivity
//!
//! Laser intensities for 2-D SLAM after Khan (2017, ch. 3): an
//! intensity calibration that turns raw remissions into a pose-invariant **relative
//! reflectivity** `ϱ̄ = I / I_ref(r, α)`, and a Hector-SLAM-style front-end (Kohlbrecher et
//! al., SSRR 2011) whose grid stores occupancy **and** the mean reflectivity per cell, matched
//! by Gauss–Newton from coarse to fine.
//!
//! * [`lut`]: the look-up table `I_ref(r, α)` from reference-surface samples — Delaunay +
//!   barycentric (scattered linear) interpolation resampled to a regular table (§3.3.2).
//! * [`range_model`], [`IntensityCorrection`]: the raw and range-only baselines (§3.5.1).
//! * [`normals`]: PCA normals in 2-D and 3-D and angles of incidence (§3.3.1).
//! * [`GridLevel`], [`MultiResMap`]: log-odds occupancy (Hector's update factors 0.4 / 0.9)
//!   and incremental-mean reflectivity per cell, bilinear value and gradient (§3.4.1).
//! * [`ScanMatcher`]: Gauss–Newton over `(x, y, θ)` with the occupancy (plain Hector),
//!   reflectivity (the thesis) or combined (its future work) residual, an optional odometry
//!   prior, map updates after enough motion and the covariance `σ² H⁻¹` (§3.4.2).
//! * [`export`]: PGM + YAML occupancy maps, reflectivity PNGs and TUM trajectories.
//! * [`benchmark`]: reading CARMEN logs into scans, pairing raw and corrected scans, and the
//!   relative-motion error of Kümmerle et al. (2009) plus the aligned absolute error.
//!
//! Units and frames: metres, radians, seconds; REP-103 (x forward, y left, θ
//! counter-clockwise). The first scan is placed at the map origin (identity), as in Hector.
//!
//! ## Errata and decisions (where the thesis is inconsistent or silent)
//!
//! * The printed bilinear *value* formula permutes its weights; we use the consistent
//!   `(1−u)(1−v)R_i + u(1−v)R_j + (1−u)vR_k + uvR_l` and its derivatives, in metres
//!   (cell values sit at cell centres).
//! * `H = Σ JᵢᵀJᵢ` and `Δζ = H⁻¹ Σ Jᵢᵀ rᵢ` (the thesis writes the sum outside `H⁻¹`).
//! * Unobserved cells have reflectivity 0 by default ([`MatcherConfig::unobserved_reflectivity`];
//!   the alternative, skipping the beam, is `None`).
//! * Only end-point cells receive reflectivity updates. Normals of 2-D scans: PCA over ±3
//!   beams within 0.3 m. LUT steps 0.01 m × 0.5°; outside the samples' hull the nearest
//!   sample's value (flagged).
//! * Hector's node defaults kept: 3 levels, 3 iterations on coarse levels and 5 on the finest,
//!   rotation steps clamped to 0.2 rad, map updates after 0.4 m or 0.9 rad.
//!
//! ## Results
//!
//! `cargo xtask eval scan-matching` measures the calibration and the matcher on the real
//! benchmark logs (relative-motion error against the corrected logs), real KITTI and Ouster
//! intensities, simulated failure cases and generated indoor worlds, with and without the
//! odometry guess, and the matcher's speed: `docs/results/scan-matching.md` has the figures.
//! The basin of convergence is about one coarsest cell; on clean synthetic scans the bilinear
//! map leaves a bias of up to about half a finest cell.
//!
//! ## Example
//!
//! ```
//! use raypath_reflectivity::{MatcherConfig, ScanMatcher, ScanPoints};
//! // A 4.05 m × 3.05 m room seen from its centre, one point every degree.
//! let mut scan = ScanPoints::new();
//! for k in 0..360 {
//!     let a = (k as f64).to_radians();
//!     let (c, s) = (a.cos(), a.sin());
//!     let t = (2.025 / c.abs().max(1e-9)).min(1.525 / s.abs().max(1e-9));
//!     scan.push([t * c, t * s], f64::NAN);
//! }
//! let mut matcher = ScanMatcher::new(MatcherConfig::default())?;
//! matcher.process(&scan, None); // builds the map
//! let r = matcher.process(&scan, None); // the same scan again: no motion
//! // Bilinear occupancy is exact to a fraction of the 5 cm cell.
//! assert!(r.world_from_sensor.translation().norm() < 0.025);
//! # Ok::<(), raypath_reflectivity::ReflectivityError>(())
//! ```

pub mod benchmark;
mod calibration;
mod error;
pub mod export;
mod grid;
pub mod lut;
mod map;
mod matcher;
pub mod normals;
mod points;
pub mod range_model;

pub use calibration::{IntensityCorrection, read_samples_csv};
pub use error::{ReflectivityError, Result};
pub use grid::{GridLevel, LOG_ODDS_LIMIT, Sample, logit, probability};
pub use lut::{CalibrationSample, IntensityLut, LutConfig, ScatteredLinear};
pub use map::{MapConfig, MultiResMap};
pub use matcher::{MatchResult, MatcherConfig, Prior, ResidualMode, ScanMatcher, match_levels};
pub use points::{PointFilter, ScanPoints};
pub use range_model::RangePolynomial;
