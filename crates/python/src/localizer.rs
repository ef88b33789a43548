//! `raypath.Localizer`: Monte-Carlo localization on a sensor-model map, one scan at a time
//! (the particle filter of `raypath localize`).

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use raypath_geometry::{Pose2, Scan2};
use raypath_localizer::init::GaussianInit;
use raypath_localizer::lidar::{
    BoxedPlanarModel, LidarConfig, ModelKind, ModelSpec, Scan2Measurement, TrackConfig,
};
use raypath_localizer::motion::OdometryControl;
use raypath_localizer::{LocalizerError, ParticleFilter};
use raypath_sensor_models::export::MapKind;
use raypath_sensor_models::{OpticalDepthConfig, Planar, SensorModel, SensorRange};

use crate::arrays::{pose_vector, pose2, poses2, scan2, vec1};
use crate::errors::{input_error, value_error};
use crate::io::Scan;
use crate::sensor_map::SensorMap;

/// A sensor model the localizer owns (the library's adapters borrow or own any
/// `SensorModel`; a boxed one is owned through this).
struct OwnedModel(BoxedPlanarModel);

impl SensorModel<Planar> for OwnedModel {
    fn ray_log_likelihood(&self, ray_in_map: &raypath_geometry::Ray2) -> f64 {
        self.0.ray_log_likelihood(ray_in_map)
    }

    fn sensor_range(&self) -> SensorRange {
        self.0.sensor_range()
    }
}

fn model_kind(name: Option<&str>, map: MapKind) -> PyResult<ModelKind> {
    Ok(match name {
        None => match map {
            MapKind::Statistics | MapKind::DecayRate => ModelKind::DecayRate,
            MapKind::Reflection => ModelKind::Reflection,
            MapKind::LogOdds => ModelKind::LogOdds,
            MapKind::LikelihoodField => ModelKind::LikelihoodField,
        },
        Some(name) => name.parse().map_err(|e: String| value_error("model", e))?,
    })
}

/// Monte-Carlo localization (Schaefer 2020, ch. 7; AMCL's defaults where the thesis is
/// silent) of a robot with a planar laser on a `SensorMap`, fed one scan at a time: the
/// odometry increment between updates drives the motion model, the scan weights the
/// particles through the map's sensor model, and the particles are resampled when the
/// effective sample size falls below half. The same seed gives the same particles.
///
/// `map`: a `SensorMap` (`raypath.sensor_models.build` or `load`). `initial`: `(x, y, theta)`
/// of the robot in the map frame; particles start Gaussian around it (σ 1 m, 0.1 rad).
/// `particles`, `seed`: as `raypath localize --particles --seed`. `model`: `"decay-rate"`,
/// `"reflection"`, `"endpoint"`, `"likelihood-field"` or `"log-odds"` (default: the map's).
/// `exact`: traverse the grid instead of optical-depth tables. `beam_step`: use every k-th
/// beam. `effective_beams`: the scan counts as this many independent beams (0 = no
/// tempering). `robot_from_laser`: the laser's mounting `(x, y, theta)` on the robot
/// (default: at the robot's origin).
#[pyclass(module = "raypath", name = "Localizer")]
pub struct Localizer {
    filter: ParticleFilter<Pose2>,
    measurement: Scan2Measurement<OwnedModel>,
    config: TrackConfig,
    last_odometry: Option<Pose2>,
    updates: usize,
    failed_updates: usize,
    resamplings: usize,
    label: String,
}

#[pymethods]
impl Localizer {
    #[new]
    #[pyo3(signature = (map, initial, *, particles = 1000, seed = 0, model = None, exact = false, beam_step = 1, effective_beams = 8.0, robot_from_laser = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        map: &Bound<'_, SensorMap>,
        initial: &Bound<'_, PyAny>,
        particles: usize,
        seed: u64,
        model: Option<&str>,
        exact: bool,
        beam_step: usize,
        effective_beams: f64,
        robot_from_laser: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        if particles == 0 {
            return Err(value_error("particles", "must be at least 1"));
        }
        if beam_step == 0 {
            return Err(value_error("beam_step", "must be at least 1"));
        }
        if !(effective_beams.is_finite() && effective_beams >= 0.0) {
            return Err(value_error(
                "effective_beams",
                format!("must be a finite number ≥ 0, got {effective_beams}"),
            ));
        }
        let initial = pose2(initial, "initial")?;
        let robot_from_laser = match robot_from_laser.filter(|p| !p.is_none()) {
            Some(p) => pose2(p, "robot_from_laser")?,
            None => Pose2::identity(),
        };
        let map = map.get();
        let spec = ModelSpec {
            kind: model_kind(model, map.file.kind)?,
            posterior: map.file.posterior,
            tabulated: (!exact).then(OpticalDepthConfig::default),
        };
        let range = map.file.mapping.range;
        let built = py
            .allow_threads(|| spec.build(map.stats(), range))
            .map_err(input_error)?;
        let lidar = LidarConfig {
            beam_step,
            effective_beams: (effective_beams > 0.0).then_some(effective_beams),
            ..LidarConfig::default()
        };
        let measurement = Scan2Measurement::new(OwnedModel(built), robot_from_laser, lidar)
            .map_err(|e| value_error("Localizer", e))?;
        let config = TrackConfig {
            particles,
            ..TrackConfig::default()
        };
        let filter = ParticleFilter::from_initializer(
            &GaussianInit::new(initial),
            particles,
            config.filter,
            seed,
        )
        .map_err(|e| value_error("Localizer", e))?;
        Ok(Self {
            filter,
            measurement,
            config,
            last_odometry: None,
            updates: 0,
            failed_updates: 0,
            resamplings: 0,
            label: spec.label(),
        })
    }

    /// Feeds one scan: `odometry` the robot's odometry pose `(x, y, theta)` at the scan (only
    /// increments are used); `ranges` a `raypath.Scan` (then no `angles`), or `(B,)` ranges
    /// with `angles` `(B,)` (evenly spaced, increasing; readings at or above `max_range` are
    /// no-returns). The filter updates at the first scan, when `force` is true, and when the
    /// odometry moved 0.2 m or turned 0.2 rad since the last update (as `raypath localize`).
    /// Returns True when it updated.
    #[pyo3(signature = (odometry, ranges, angles = None, *, max_range = None, force = false))]
    fn step(
        &mut self,
        py: Python<'_>,
        odometry: &Bound<'_, PyAny>,
        ranges: &Bound<'_, PyAny>,
        angles: Option<&Bound<'_, PyAny>>,
        max_range: Option<f64>,
        force: bool,
    ) -> PyResult<bool> {
        let odometry = pose2(odometry, "odometry")?;
        let scan: Scan2 = match (ranges.downcast::<Scan>(), angles) {
            (Ok(scan), None) => scan.get().frame.scan.clone(),
            (Ok(_), Some(_)) => {
                return Err(value_error("angles", "must be None when a Scan is given"));
            }
            (Err(_), Some(angles)) => scan2(ranges, angles, max_range)?,
            (Err(_), None) => {
                return Err(value_error(
                    "angles",
                    "expected an array of shape (B,) with the ranges (or a raypath.Scan)",
                ));
            }
        };
        if let Some(previous) = self.last_odometry {
            let increment = previous.inverse() * odometry;
            let moved = increment.translation().norm() >= self.config.update_min_distance_m
                || increment.theta().abs() >= self.config.update_min_angle_rad;
            if !(moved || force) {
                return Ok(false);
            }
            let control = OdometryControl::from_poses(&previous, &odometry);
            let (filter, motion) = (&mut self.filter, &self.config.motion);
            py.allow_threads(|| filter.predict(motion, &control));
        }
        self.last_odometry = Some(odometry);
        let (filter, measurement) = (&mut self.filter, &self.measurement);
        let outcome = py.allow_threads(|| {
            let prepared = measurement.prepare(&scan);
            filter
                .update(measurement, &prepared)
                .map(|_| filter.resample_if_needed().is_some())
        });
        match outcome {
            Ok(resampled) => {
                self.updates += 1;
                self.resamplings += usize::from(resampled);
            }
            Err(LocalizerError::AllParticlesImpossible { .. }) => self.failed_updates += 1,
            Err(e) => return Err(input_error(e)),
        }
        Ok(true)
    }

    /// The estimate `(x, y, theta)` of the robot: the weighted mean of the best 10 % of the
    /// particles.
    #[getter]
    fn pose<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        pose_vector(py, self.filter.estimate(self.config.estimator))
    }

    /// The particles, `(N, 3)` float64 `x, y, theta`.
    #[getter]
    fn particles<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        poses2(py, self.filter.states().iter().copied())
    }

    /// The normalized particle weights, `(N,)`.
    #[getter]
    fn weights<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.filter.weights().collect())
    }

    /// Filter updates so far.
    #[getter]
    fn updates(&self) -> usize {
        self.updates
    }

    /// Updates skipped because every particle had likelihood zero.
    #[getter]
    fn failed_updates(&self) -> usize {
        self.failed_updates
    }

    /// Resamplings so far.
    #[getter]
    fn resamplings(&self) -> usize {
        self.resamplings
    }

    /// The sensor model's label (`reflection [table]`, …), as `raypath localize` prints it.
    #[getter]
    fn model(&self) -> String {
        self.label.clone()
    }

    fn __len__(&self) -> usize {
        self.filter.len()
    }

    fn __repr__(&self) -> String {
        let p = self.filter.estimate(self.config.estimator);
        format!(
            "Localizer({} particles, model {}, pose=({:.3}, {:.3}, {:.3}), {} updates)",
            self.filter.len(),
            self.label,
            p.x(),
            p.y(),
            p.theta(),
            self.updates
        )
    }
}
