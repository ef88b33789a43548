//! # raypath-localizer
//!
//! A generic **particle filter** (Monte-Carlo localization) over SE(2) ([`Pose2`]) and SE(3)
//! ([`Pose3`]), the motion models it needs, and the **trajectory evaluation** of Schaefer
//! (2020), ch. 12. Sensor models plug in through one trait, [`MeasurementModel`]; the
//! filter knows nothing about maps or lidar.
//!
//! ## Idea
//!
//! The belief over the robot pose is a set of weighted samples (particles). Odometry moves
//! every particle by a noisy sample of the motion ([`MotionModel`]); a measurement reweights
//! every particle by its likelihood ([`MeasurementModel`], log-space); when the weights
//! degenerate, resampling copies good particles and drops bad ones. Weighting runs in
//! parallel with rayon, per particle; results are **bit-identical for a given seed on any
//! number of threads**.
//!
//! ## Algorithms and references
//!
//! | part | module | reference |
//! | --- | --- | --- |
//! | particle filter / MCL cycle | [`ParticleFilter`] | Thrun, Burgard, Fox, *Probabilistic Robotics* (2005), §4.3, Table 8.2 |
//! | log-weights, log-sum-exp, effective sample size | [`weights`] | Thrun et al. §4.3.4; Kong et al. (1994) |
//! | low-variance (systematic) resampling | [`resample`] | Thrun et al. Table 4.4 |
//! | KLD-sampling (adaptive particle count) | [`kld`] | Fox, IJRR 22(12), 2003; Thrun et al. §8.3.7 |
//! | odometry motion model (α1..α4) | [`motion::OdometryMotionModel`] | Thrun et al. §5.4, Table 5.6; ROS AMCL |
//! | Gaussian increment model (SE(2)) | [`motion::PlanarGaussianMotionModel`] | Schaefer (2020), ch. 12 |
//! | 6-DOF Gaussian increment model | [`motion::Gaussian6DofMotionModel`] | ours (ch. 7 leaves it open) |
//! | estimators: weighted mean, best 10 %, max weight | [`Estimator`] | Schaefer (2020), ch. 12; Markley et al. (2007) for quaternions |
//! | initial distributions | [`init`] | Schaefer (2020), ch. 7 (Gaussian 1 m / 0.2 m / 0.1 rad), ch. 12 (disc) |
//! | trajectory errors every 1 m, divergence, relative motion | [`eval`] | Schaefer (2020), ch. 12 |
//! | lidar scans as measurements (any raypath-sensor-models model; beam step, likelihood exponent), log tracking | [`lidar`] | Schaefer (2020), Eq. 7.15; Thrun et al. §6.4 |
//!
//! ## Decisions on the thesis's open points and errata
//!
//! * ESS threshold: resample when ESS / N < 0.5. The thesis (§12.5.1) prints ESS < 0.5, which
//!   never holds for normalized weights (ESS ≥ 1); its reference implementation divides by N.
//! * Motion composition: body-frame increments multiply on the right, x' = x · Δ, as the
//!   reference implementation does; the thesis (§12.4.3) prints Δ · x.
//! * Initial spreads of ch. 7 ("variance" 1 m, 0.2 m, 0.1 rad) are standard deviations (their
//!   units are those of a standard deviation); the disc initializer is uniform in area unless
//!   asked to mimic the reference implementation (uniform in the radius, although the thesis
//!   says "uniformly in a circle").
//! * The thesis states no motion model, resampling scheme or estimator for ch. 7: we use the
//!   models above, systematic resampling and, by default, the best-10 % estimator.
//! * Divergence threshold: the thesis gives none; default 5 m.
//!
//! ## Example: beacons in a plane
//!
//! A robot at (3, 2) measures its distance to three beacons; the filter starts uniform over a
//! 10 m × 10 m square and finds it.
//!
//! ```
//! use nalgebra::{Point2, Vector2};
//! use raypath_geometry::Pose2;
//! use raypath_localizer::{
//!     Estimator, FilterConfig, MeasurementModel, ParticleFilter, init::UniformBox,
//!     motion::{OdometryControl, OdometryMotionModel},
//! };
//!
//! struct Beacons { at: Vec<Point2<f64>>, sigma_m: f64 }
//! impl MeasurementModel<Pose2> for Beacons {
//!     type Observation = [f64];
//!     fn log_likelihood(&self, pose: &Pose2, ranges_m: &[f64]) -> f64 {
//!         let p = Point2::from(pose.translation());
//!         self.at.iter().zip(ranges_m).map(|(b, r)| {
//!             let e = ((b - p).norm() - r) / self.sigma_m;
//!             -0.5 * e * e
//!         }).sum()
//!     }
//! }
//!
//! let beacons = Beacons {
//!     at: vec![Point2::new(0.0, 0.0), Point2::new(10.0, 0.0), Point2::new(0.0, 10.0)],
//!     sigma_m: 0.2,
//! };
//! let truth = Point2::new(3.0, 2.0);
//! let ranges: Vec<f64> = beacons.at.iter().map(|b| (b - truth).norm()).collect();
//!
//! let start = UniformBox::new([0.0, 10.0], [0.0, 10.0]);
//! let mut filter = ParticleFilter::from_initializer(&start, 2000, FilterConfig::default(), 42)?;
//! let standing = OdometryControl::from_increment(&Pose2::identity());
//! let motion = OdometryMotionModel::new(0.0, 0.0, 0.0, 0.0)?;
//! for _ in 0..10 {
//!     // The robot stands still; the constant-free noiseless model keeps the particles, the
//!     // resampling concentrates them.
//!     filter.step(&motion, &standing, &beacons, ranges.as_slice())?;
//! }
//! let estimate = filter.estimate(Estimator::BestFraction(0.1));
//! assert!((estimate.translation() - Vector2::new(3.0, 2.0)).norm() < 0.3);
//! # Ok::<(), raypath_localizer::LocalizerError>(())
//! ```
//!
//! ## Configuration (defaults)
//!
//! * [`FilterConfig`]: `resample_ess_ratio` 0.5, `kld` off, `min_particles_per_task` 64.
//! * [`kld::KldConfig`]: ε 0.01, δ 0.01, bins 0.5 m × 0.5 m (× 0.5 m) × 10°, 100 – 5000
//!   particles (ROS AMCL's defaults).
//! * [`motion::OdometryMotionModel`]: α1 = α2 = α3 = α4 = 0.2 (ROS AMCL).
//! * [`init::GaussianInit`]: σ 1 m horizontal, 0.2 m vertical, 0.1 rad (thesis ch. 7).
//! * [`eval::EvaluationConfig`]: spacing 1 m, divergence threshold 5 m.
//! * [`lidar::LidarConfig`]: every beam, likelihood exponent γ = 8 / (kept beams), per-beam
//!   random-measurement mixture ε = 0.05 (AMCL's `z_rand`; half no-return, half uniform return);
//!   [`lidar::TrackConfig`]: 1000 particles, updates after 0.2 m / 0.2 rad.
//!
//! ## Performance
//!
//! `cargo bench -p raypath-localizer --bench filter` (criterion; synthetic model of 8 beacon
//! ranges, odometry motion model, resampling every step) times predict, update and resample
//! for SE(2) and SE(3) at 1000 and 5000 particles. Prediction and weighting scale with rayon;
//! normalization and resampling are O(N) and partly sequential. Filter speed on real maps is
//! measured by `cargo xtask eval mcl`: `docs/results/mcl.md` has the figures.
//!
//! Units and frames: metres, radians, seconds; REP-103 (x forward, y left, z up). Poses are
//! `world_from_robot`.

mod error;
mod estimate;
pub mod eval;
mod filter;
pub mod init;
pub mod kld;
pub mod lidar;
mod models;
pub mod motion;
pub mod resample;
mod rng;
mod state;
mod track;
pub mod weights;

pub use error::LocalizerError;
pub use estimate::Estimator;
pub use filter::{FilterConfig, ParticleFilter, ResampleReport, StepReport, UpdateReport};
pub use models::{MeasurementModel, MotionModel};
pub use raypath_geometry::{Pose2, Pose3};
pub use rng::ParticleRng;
pub use state::FilterState;
pub use track::{PoseTrack, Stamped};
