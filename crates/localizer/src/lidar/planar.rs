//! The 2-D adapter: SE(2) particles, 2-D laser scans.

use raypath_geometry::{Pose2, Scan2};
use raypath_sensor_models::{Planar, PreparedScan, ScanLikelihood, SensorModel};

use super::LidarConfig;
use super::mixture::{RandomMixture, adapter_likelihood};
use crate::{LocalizerError, MeasurementModel};

/// A 2-D scan prepared for weighting many particles: the kept beams' directions and
/// readings (sensor frame) and the likelihood exponent γ.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlanarScan {
    prepared: PreparedScan,
    exponent: f64,
}

impl PlanarScan {
    /// Number of kept beams.
    pub fn len(&self) -> usize {
        self.prepared.len()
    }

    /// True when no beam was kept.
    pub fn is_empty(&self) -> bool {
        self.prepared.is_empty()
    }

    /// The likelihood exponent γ applied to this scan.
    pub fn exponent(&self) -> f64 {
        self.exponent
    }
}

/// [`MeasurementModel`]`<Pose2>` for any 2-D sensor model: the weight of particle
/// `world_from_robot` is `γ · Σ_j ln p(z_j | world_from_robot · robot_from_laser, m)` over
/// every `beam_step`-th beam (see the [module docs](super)).
#[derive(Clone, Debug)]
pub struct Scan2Measurement<M> {
    scan_likelihood: ScanLikelihood<RandomMixture<M>>,
    robot_from_laser: Pose2,
    config: LidarConfig,
}

impl<M: SensorModel<Planar>> Scan2Measurement<M> {
    /// The adapter for `model`, a laser mounted at `robot_from_laser`.
    pub fn new(
        model: M,
        robot_from_laser: Pose2,
        config: LidarConfig,
    ) -> Result<Self, LocalizerError> {
        let scan_likelihood = adapter_likelihood(
            model,
            &config,
            robot_from_laser.is_finite(),
            "robot_from_laser",
        )?;
        Ok(Self {
            scan_likelihood: scan_likelihood.with_beam_step(config.beam_step),
            robot_from_laser,
            config,
        })
    }

    /// The sensor model.
    pub fn model(&self) -> &M {
        self.scan_likelihood.model().inner()
    }

    /// The laser mounting.
    pub fn robot_from_laser(&self) -> Pose2 {
        self.robot_from_laser
    }

    /// The configuration.
    pub fn config(&self) -> &LidarConfig {
        &self.config
    }

    /// Prepares `scan` (every `beam_step`-th beam) for [`MeasurementModel::log_likelihood`].
    pub fn prepare(&self, scan: &Scan2) -> PlanarScan {
        let prepared = self.scan_likelihood.prepare(scan);
        let exponent = self.config.exponent(prepared.len());
        PlanarScan { prepared, exponent }
    }

    /// The un-tempered scan log-likelihood `Σ_j ln p(z_j | x · robot_from_laser, m)`.
    pub fn raw_log_likelihood(&self, world_from_robot: &Pose2, scan: &PlanarScan) -> f64 {
        let world_from_laser = *world_from_robot * self.robot_from_laser;
        self.scan_likelihood
            .log_likelihood_prepared(&world_from_laser, &scan.prepared)
    }
}

impl<M: SensorModel<Planar>> MeasurementModel<Pose2> for Scan2Measurement<M> {
    type Observation = PlanarScan;

    fn log_likelihood(&self, world_from_robot: &Pose2, scan: &PlanarScan) -> f64 {
        let value = scan.exponent * self.raw_log_likelihood(world_from_robot, scan);
        if value.is_nan() {
            f64::NEG_INFINITY
        } else {
            value
        }
    }
}
