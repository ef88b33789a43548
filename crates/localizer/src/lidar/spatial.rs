//! The 3-D adapter: SE(3) particles, rays in the sensor frame.

use nalgebra::Point3;
use raypath_geometry::{PointCloud, Pose3, Range, Ray3};
use raypath_sensor_models::{ScanLikelihood, SensorModel, Spatial};

use super::LidarConfig;
use super::mixture::{RandomMixture, adapter_likelihood};
use crate::{LocalizerError, MeasurementModel};

/// A 3-D scan prepared for weighting: the kept rays in the **sensor frame** and the
/// likelihood exponent γ.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SpatialScan {
    rays_in_sensor: Vec<Ray3>,
    exponent: f64,
}

impl SpatialScan {
    /// The kept rays (sensor frame).
    pub fn rays(&self) -> &[Ray3] {
        &self.rays_in_sensor
    }

    /// Number of kept rays.
    pub fn len(&self) -> usize {
        self.rays_in_sensor.len()
    }

    /// True when no ray was kept.
    pub fn is_empty(&self) -> bool {
        self.rays_in_sensor.is_empty()
    }

    /// The likelihood exponent γ applied to this scan.
    pub fn exponent(&self) -> f64 {
        self.exponent
    }
}

/// [`MeasurementModel`]`<Pose3>` for any 3-D sensor model: the weight of particle
/// `world_from_robot` is `γ · Σ_j ln p(z_j | world_from_robot · robot_from_sensor, m)`
/// over the kept rays (see the [module docs](super)).
#[derive(Clone, Debug)]
pub struct Scan3Measurement<M> {
    scan_likelihood: ScanLikelihood<RandomMixture<M>>,
    robot_from_sensor: Pose3,
    config: LidarConfig,
}

impl<M: SensorModel<Spatial>> Scan3Measurement<M> {
    /// The adapter for `model`, a sensor mounted at `robot_from_sensor`.
    pub fn new(
        model: M,
        robot_from_sensor: Pose3,
        config: LidarConfig,
    ) -> Result<Self, LocalizerError> {
        // Subsampling happens in `prepare_*`; the inner adapter uses every prepared ray.
        let scan_likelihood = adapter_likelihood(
            model,
            &config,
            robot_from_sensor.is_finite(),
            "robot_from_sensor",
        )?;
        Ok(Self {
            scan_likelihood,
            robot_from_sensor,
            config,
        })
    }

    /// The sensor model.
    pub fn model(&self) -> &M {
        self.scan_likelihood.model().inner()
    }

    /// The configuration.
    pub fn config(&self) -> &LidarConfig {
        &self.config
    }

    /// Prepares rays given in the sensor frame (every `beam_step`-th).
    pub fn prepare_rays(&self, rays_in_sensor: &[Ray3]) -> SpatialScan {
        let rays_in_sensor: Vec<Ray3> = rays_in_sensor
            .iter()
            .step_by(self.config.beam_step)
            .copied()
            .collect();
        let exponent = self.config.exponent(rays_in_sensor.len());
        SpatialScan {
            rays_in_sensor,
            exponent,
        }
    }

    /// Prepares a point cloud in the sensor frame: every `beam_step`-th valid point becomes
    /// a return along the ray from the sensor origin (missing points and points at the
    /// origin are skipped).
    pub fn prepare_cloud(&self, cloud_in_sensor: &PointCloud) -> SpatialScan {
        let rays_in_sensor: Vec<Ray3> = (0..cloud_in_sensor.len())
            .filter(|&i| cloud_in_sensor.is_valid(i))
            .step_by(self.config.beam_step)
            .filter_map(|i| {
                let p = cloud_in_sensor.point_f64(i);
                Ray3::new(Point3::origin(), p.coords, Range::Hit(p.coords.norm()))
            })
            .collect();
        let exponent = self.config.exponent(rays_in_sensor.len());
        SpatialScan {
            rays_in_sensor,
            exponent,
        }
    }

    /// The un-tempered log-likelihood `Σ_j ln p(z_j | x · robot_from_sensor, m)`.
    pub fn raw_log_likelihood(&self, world_from_robot: &Pose3, scan: &SpatialScan) -> f64 {
        let world_from_sensor = *world_from_robot * self.robot_from_sensor;
        self.scan_likelihood
            .rays_log_likelihood(&world_from_sensor, &scan.rays_in_sensor)
    }
}

impl<M: SensorModel<Spatial>> MeasurementModel<Pose3> for Scan3Measurement<M> {
    type Observation = SpatialScan;

    fn log_likelihood(&self, world_from_robot: &Pose3, scan: &SpatialScan) -> f64 {
        let value = scan.exponent * self.raw_log_likelihood(world_from_robot, scan);
        if value.is_nan() {
            f64::NEG_INFINITY
        } else {
            value
        }
    }
}
