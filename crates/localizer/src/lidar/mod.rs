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
//! offset), evaluate `ln p(z | x, m) = Σ_j ln p(z_j | x, m)` (Schaefer 2020, Eq. 7.15) on the
//! kept beams and multiply it by the **likelihood exponent** of [`LidarConfig`].
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
//! Frames: poses are `world_from_robot`; `robot_from_sensor` is the sensor mounting;
//! rays in [`SpatialScan`] are in the sensor frame. Metres, radians (REP-103).

mod build;
mod config;
mod planar;
mod run;
mod spatial;

pub use build::{BoxedPlanarModel, ModelKind, ModelSpec};
pub use config::LidarConfig;
pub use run::{PlanarStep, PlanarTrack, TrackConfig, track_planar};
pub use planar::{PlanarScan, Scan2Measurement};
pub use spatial::{Scan3Measurement, SpatialScan};
