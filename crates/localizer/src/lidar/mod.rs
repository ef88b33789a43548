//! Lidar measurement models for the filter: adapters from any
//! [`raypath_sensor_models::SensorModel`] to [`crate::MeasurementModel`].
//!
//! * [`Scan2Measurement`]: SE(2) particles ([`Pose2`](crate::Pose2), `world_from_robot`)
//!   and 2-D laser scans ([`raypath_geometry::Scan2`]), prepared once per scan
//!   ([`PlanarScan`]).
//! * [`Scan3Measurement`]: SE(3) particles and 3-D rays in the sensor frame
//!   ([`SpatialScan`], e.g. the points of a Velodyne cloud).
//!
//! Both compose the particle pose with the fixed mounting `robot_from_sensor` (the laser
//! offset), evaluate `ln p(z | x, m) = Σ_j ln p̃(z_j | x, m)` (Schaefer 2020, Eq. 7.15) on the
//! kept beams, each beam mixed with a **random measurement** (below), and multiply it by
//! the **likelihood exponent** of [`LidarConfig`].
//!
//! ## Keeping the filter healthy: beam subsampling and a likelihood exponent
//!
//! Eq. (7.15) treats the rays of a scan as independent given pose and map. They are not
//! (neighbouring beams see the same wall; map errors are shared), so the product of
//! hundreds of ray likelihoods is far too peaked: a 10 cm pose offset changes the summed
//! log-likelihood by tens to hundreds of nats, one particle takes all the weight after the
//! first update and the filter collapses (Thrun et al. 2005, §6.4.1 and §6.8, recommend
//! "using only a subset of all measurements" and "artificially inflating the measurement
//! noise"). AMCL keeps `max_beams` = 30 beams; many MCL implementations raise the likelihood
//! to a power < 1. We use both, as two fields of [`LidarConfig`]:
//!
//! * `beam_step` = k keeps every k-th beam (AMCL's `max_beams` idea; default 1, all beams),
//!   for speed;
//! * `effective_beams` = n sets the exponent γ = min(1, n / J) for a scan with J kept beams:
//!   `ln p̃(z | x) = γ Σ_j ln p(z_j | x, m)`, i.e. the scan counts as n independent beams
//!   (default **8**; `None` = γ = 1, the plain product of Eq. 7.15).
//!
//! The exponent is the same for every sensor model (the evaluation `cargo xtask eval mcl`
//! uses the defaults for all of them), so models are compared under equal conditions; it
//! changes only how peaked the weights are, not where their maximum lies.
//!
//! ## Outlier beams: a random-measurement mixture
//!
//! The ray-casting models (decay-rate, reflection, their full map posteriors, log-odds) have
//! no false-detection term (the thesis lists this as a limitation): a no-return through glass
//! or an open door that the map shows closed, a person in front of a wall, or a ray leaving
//! the mapped area through unknown cells costs tens to hundreds of nats per beam (on the
//! Intel log a single no-return beam scores −80 under decay-rate and −450 to −500 under
//! log-odds at the *true* pose), so a handful of such beams decide the weights. Every beam
//! is therefore mixed with a random reading (AMCL's `z_rand`, Thrun et al. 2005, §6.3):
//!
//! ```text
//! p̃(z_j | x, m) = (1 − ε) p(z_j | x, m) + ε q(z_j)
//! ```
//!
//! with `q` a proper distribution on the thesis's measurement space `{sub} ∪ [r_min, r_max)
//! ∪ {sup}` (Eq. 7.14): a reading unrelated to the map is a no-return or a return uniform
//! on `[0, r_max)` with equal probability (`q(sup) = 1/2`, `q(r) = 1 / (2 r_max)`,
//! `q(sub) = r_min / (2 r_max)`). It is computed in log space (log-sum-exp, never NaN) and
//! applied here, not in the sensor models, which stay the thesis's. `ε =
//! LidarConfig::random_weight`, default [`DEFAULT_RANDOM_WEIGHT`] = 0.05 (AMCL's `z_rand`);
//! 0 gives the models' own values. On the Intel log (`cargo xtask eval mcl` settings, 10
//! seeds) it lowers the diverged runs of decay-rate from 3 to 1 and of reflection (FMP)
//! from 3 to 2 without changing the accuracy of the runs that converge in both; the
//! remaining failures start with the initial mean 1.6–2.4 m from the truth and never
//! converge (no particle reaches the narrow basin of the ray-casting likelihoods; with the
//! initial mean at the truth decay-rate converges in 10 of 10 runs).
//!
//! ## Running along a log, choosing a model
//!
//! [`track_planar`] runs the filter along a 2-D log ([`PlanarStep`]s: odometry pose and scan)
//! with AMCL-style update thresholds (0.2 m / 0.2 rad) and forced updates (e.g. at scans
//! with ground truth); [`ModelSpec`] builds any sensor model of raypath-sensor-models from a
//! statistics map at run time (exact traversal or optical-depth table), as `raypath
//! localize` and `cargo xtask eval mcl` do.
//!
//! ## Performance
//!
//! `RAYPATH_DATA=… cargo bench -p raypath-localizer --bench mcl` times one full update
//! (predict + weight + resample, 1000 particles × 180 beams with `LidarConfig::default()`
//! including the random-measurement mixture) per sensor model on the map of the Intel Research
//! Lab; the `mcl` evaluation measures whole filter runs (`docs/results/mcl.md`). The mixture
//! costs a logarithm and an exponential per beam. The optical-depth table answers a ray in
//! O(1) but with two bilinear look-ups per end in two directions, so it gains over the exact
//! traversal where rays are long and loses little where they are short.
//!
//! Frames: poses are `world_from_robot`; `robot_from_sensor` is the sensor mounting;
//! rays in [`SpatialScan`] are in the sensor frame. Metres, radians (REP-103).

mod build;
mod config;
mod mixture;
mod planar;
mod report;
mod run;
mod spatial;

pub use build::{BoxedPlanarModel, ModelKind, ModelSpec};
pub use config::{DEFAULT_RANDOM_WEIGHT, LidarConfig};
pub use planar::{PlanarScan, Scan2Measurement};
pub use report::{LocalizeReport, TrajectoryErrorReport};
pub use run::{PlanarStep, PlanarTrack, TrackConfig, track_planar};
pub use spatial::{Scan3Measurement, SpatialScan};
