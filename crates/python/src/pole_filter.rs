//! `raypath.poles.PoleFilter`: the pole particle filter, localization on a pole map.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use raypath_poles::Pole;

use crate::arrays::{floats, pose_vector, pose2, poses2, vector};
use crate::errors::{input_error, value_error};
use crate::poles::{Poles, preset_of};

/// The pole particle filter (Schaefer 2020, §12.4.3): localization on a pole map from
/// odometry increments and the poles seen around the robot.
///
/// `map`: the reference poles, a `Poles` (`raypath.poles.map`, `extract`) or an `(M, 2)`
/// array of pole centres. `start`: `(x, y, theta)`; particles are drawn uniformly around it
/// (the preset's radius and heading range). `preset`: the filter settings of `"kitti"` or
/// `"nclt"`. `particles`: overrides the preset's count. Same seed, same particles.
#[pyclass(module = "raypath.poles", name = "PoleFilter")]
pub struct PoleFilter {
    filter: raypath_poles::PoleFilter,
}

#[pymethods]
impl PoleFilter {
    #[new]
    #[pyo3(signature = (map, start, *, preset = "kitti", particles = None, seed = 0))]
    fn new(
        map: &Bound<'_, PyAny>,
        start: &Bound<'_, PyAny>,
        preset: &str,
        particles: Option<usize>,
        seed: u64,
    ) -> PyResult<Self> {
        let map: Vec<Pole> = match map.downcast::<Poles>() {
            Ok(poles) => poles.get().poles.clone(),
            Err(_) => {
                let f = floats(map, "map", "an array of shape (M, 2)")?;
                if f.shape.len() != 2 || f.shape[1] != 2 || f.shape[0] == 0 {
                    return Err(value_error(
                        "map",
                        format!(
                            "expected Poles or an array of shape (M, 2) with M ≥ 1, got shape {:?}",
                            f.shape
                        ),
                    ));
                }
                if !f.values.iter().all(|v| v.is_finite()) {
                    return Err(value_error("map", "not finite"));
                }
                f.values
                    .chunks_exact(2)
                    .map(|p| Pole {
                        x: p[0],
                        y: p[1],
                        z_start: 0.0,
                        z_end: 0.0,
                        width: 0.0,
                        score: 1.0,
                    })
                    .collect()
            }
        };
        let start = pose2(start, "start")?;
        let mut params = preset_of(preset)?.filter;
        if let Some(n) = particles {
            params.particles = n;
        }
        params.validate().map_err(|e| value_error("particles", e))?;
        let filter = raypath_poles::PoleFilter::new(&map, params, start, seed)
            .map_err(|e| value_error("PoleFilter", e))?;
        Ok(Self { filter })
    }

    /// Motion update: `increment` `(x, y, theta)` of the odometry in the previous pose's
    /// frame, with standard deviations `std` `(x m, y m, theta rad)`.
    fn predict(&mut self, increment: &Bound<'_, PyAny>, std: &Bound<'_, PyAny>) -> PyResult<()> {
        let increment = pose2(increment, "increment")?;
        let s = vector(std, "std", 0, true)?;
        let [sx, sy, st] = s[..] else {
            return Err(value_error(
                "std",
                format!("expected shape (3,), got ({},)", s.len()),
            ));
        };
        self.filter
            .predict(&increment, [sx, sy, st])
            .map_err(|e| value_error("std", e))
    }

    /// Measurement update with the poles seen, `(K, 2)` centres in the robot frame (metres);
    /// resamples when the effective sample size is low. No poles: nothing changes.
    fn update(&mut self, py: Python<'_>, poles: &Bound<'_, PyAny>) -> PyResult<()> {
        let f = floats(poles, "poles", "an array of shape (K, 2)")?;
        if f.shape.len() != 2 || f.shape[1] != 2 {
            return Err(value_error(
                "poles",
                format!("expected an array of shape (K, 2), got shape {:?}", f.shape),
            ));
        }
        if !f.values.iter().all(|v| v.is_finite()) {
            return Err(value_error("poles", "not finite"));
        }
        let seen: Vec<nalgebra::Point2<f64>> = f
            .values
            .chunks_exact(2)
            .map(|p| nalgebra::Point2::new(p[0], p[1]))
            .collect();
        let filter = &mut self.filter;
        py.allow_threads(|| filter.update(&seen))
            .map_err(input_error)
    }

    /// The estimate `(x, y, theta)`: weighted mean of the best particles.
    #[getter]
    fn pose<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        pose_vector(py, self.filter.estimate())
    }

    /// The particles, `(N, 3)`.
    #[getter]
    fn particles<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        poses2(py, self.filter.particles().iter().copied())
    }

    /// Resamplings so far.
    #[getter]
    fn resamples(&self) -> usize {
        self.filter.resamples()
    }

    fn __len__(&self) -> usize {
        self.filter.particles().len()
    }
}
