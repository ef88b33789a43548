//! Scan likelihoods: a pose and a scan (or cloud) to the summed ray log-likelihood.

use nalgebra::{Point2, Point3, Unit, Vector2};
use raypath_geometry::{PointCloud, Pose2, Pose3, Range, Ray2, Ray3, Scan2};

use crate::dimension::{Planar, Spatial};
use crate::models::SensorModel;

/// Turns a pose hypothesis and a measurement into `ln p(z | x, m) = Σ_j ln p(z_j | x, m)`
/// (rays independent given pose and map, Eq. 7.15) with any [`SensorModel`].
///
/// The pose is `world_from_sensor` (the sensor's pose in the map frame; a particle filter
/// composes `world_from_robot * robot_from_sensor`). `beam_step = k` uses every k-th beam or
/// point (AMCL's `max_beams`); the default is 1 (all). The result may be `−∞`, never NaN;
/// a non-finite pose gives `−∞`.
#[derive(Clone, Debug)]
pub struct ScanLikelihood<M> {
    model: M,
    beam_step: usize,
}

/// A 2-D scan prepared for many pose hypotheses: beam directions (sensor frame) and
/// readings, computed once.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PreparedScan {
    beams: Vec<(Vector2<f64>, Range)>,
}

impl PreparedScan {
    /// Number of beams kept.
    pub fn len(&self) -> usize {
        self.beams.len()
    }

    /// True when no beam was kept.
    pub fn is_empty(&self) -> bool {
        self.beams.is_empty()
    }
}

impl<M> ScanLikelihood<M> {
    /// The adapter for `model`, using every beam.
    pub fn new(model: M) -> Self {
        Self {
            model,
            beam_step: 1,
        }
    }

    /// Uses every `step`-th beam (0 counts as 1).
    pub fn with_beam_step(mut self, step: usize) -> Self {
        self.beam_step = step.max(1);
        self
    }

    /// The sensor model.
    pub fn model(&self) -> &M {
        &self.model
    }

    /// The beam step.
    pub fn beam_step(&self) -> usize {
        self.beam_step
    }
}

impl<M: SensorModel<Planar>> ScanLikelihood<M> {
    /// `ln p(scan | world_from_sensor, m)`: the sum over the scan's beams (every
    /// `beam_step`-th) of the model's ray log-likelihood.
    pub fn log_likelihood(&self, world_from_sensor: &Pose2, scan: &Scan2) -> f64 {
        if !world_from_sensor.is_finite() {
            return f64::NEG_INFINITY;
        }
        scan.rays(*world_from_sensor)
            .step_by(self.beam_step)
            .map(|ray| self.model.ray_log_likelihood(&ray))
            .sum()
    }

    /// The scan's beams prepared for [`Self::log_likelihood_prepared`] (every
    /// `beam_step`-th beam).
    pub fn prepare(&self, scan: &Scan2) -> PreparedScan {
        PreparedScan {
            beams: (0..scan.len())
                .step_by(self.beam_step)
                .map(|i| {
                    let angle = scan.angle(i);
                    (Vector2::new(angle.cos(), angle.sin()), scan.range(i))
                })
                .collect(),
        }
    }

    /// Same as [`Self::log_likelihood`] for a prepared scan: no trigonometry per beam.
    pub fn log_likelihood_prepared(&self, world_from_sensor: &Pose2, scan: &PreparedScan) -> f64 {
        if !world_from_sensor.is_finite() {
            return f64::NEG_INFINITY;
        }
        let origin = Point2::new(world_from_sensor.x(), world_from_sensor.y());
        let rotation = world_from_sensor.isometry.rotation;
        scan.beams
            .iter()
            .map(|(direction, range)| {
                let ray = Ray2 {
                    origin,
                    direction: Unit::new_unchecked(rotation * direction),
                    range: *range,
                };
                self.model.ray_log_likelihood(&ray)
            })
            .sum()
    }
}

impl<M: SensorModel<Spatial>> ScanLikelihood<M> {
    /// `ln p(cloud | world_from_sensor, m)` for a point cloud in the sensor frame: every
    /// valid point (every `beam_step`-th) is a return along the ray from the sensor origin;
    /// missing points (NaN) are skipped.
    pub fn cloud_log_likelihood(&self, world_from_sensor: &Pose3, cloud: &PointCloud) -> f64 {
        if !world_from_sensor.is_finite() {
            return f64::NEG_INFINITY;
        }
        let origin = world_from_sensor.transform_point(&Point3::origin());
        (0..cloud.len())
            .step_by(self.beam_step)
            .filter(|&i| cloud.is_valid(i))
            .filter_map(|i| {
                Ray3::between(
                    origin,
                    world_from_sensor.transform_point(&cloud.point_f64(i)),
                )
            })
            .map(|ray| self.model.ray_log_likelihood(&ray))
            .sum()
    }

    /// `ln p(rays | world_from_sensor, m)` for rays given in the sensor frame (every
    /// `beam_step`-th), including no-returns.
    pub fn rays_log_likelihood(&self, world_from_sensor: &Pose3, rays_in_sensor: &[Ray3]) -> f64 {
        if !world_from_sensor.is_finite() {
            return f64::NEG_INFINITY;
        }
        rays_in_sensor
            .iter()
            .step_by(self.beam_step)
            .map(|ray| {
                let ray_in_map = Ray3 {
                    origin: world_from_sensor.transform_point(&ray.origin),
                    direction: Unit::new_unchecked(
                        world_from_sensor.transform_vector(ray.direction.as_ref()),
                    ),
                    range: ray.range,
                };
                self.model.ray_log_likelihood(&ray_in_map)
            })
            .sum()
    }
}
