//! `raypath.registration.register`: 3-D scan registration by point-to-plane ICP.

use numpy::{PyArray2, PyArray3};
use pyo3::prelude::*;
use raypath_geometry::Pose3;
use raypath_registration::{Kernel, OdometryConfig, RegistrationConfig, register as icp};

use crate::arrays::{point_cloud, pose3, pose3_matrix, poses3};
use crate::errors::{input_error, value_error};

/// What `raypath.registration.register` found.
#[pyclass(module = "raypath.registration", name = "Registration", frozen)]
pub struct Registration {
    found: raypath_registration::Registration,
}

#[pymethods]
impl Registration {
    /// `target_from_source`, `(4, 4)` float64: maps source points into the target frame.
    #[getter]
    fn pose<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        pose3_matrix(py, &self.found.target_from_source)
    }

    /// Share of the thinned source points that are inliers at the final pose, in [0, 1].
    #[getter]
    fn fitness(&self) -> f64 {
        self.found.fitness
    }

    /// Root mean square point-to-plane residual of the inliers, metres.
    #[getter]
    fn rmse(&self) -> f64 {
        self.found.rmse_m
    }

    /// Gauss–Newton iterations run.
    #[getter]
    fn iterations(&self) -> usize {
        self.found.iterations
    }

    /// True when the last update was below the convergence thresholds.
    #[getter]
    fn converged(&self) -> bool {
        self.found.converged
    }

    /// Correspondences within the gate at the final pose.
    #[getter]
    fn correspondences(&self) -> usize {
        self.found.correspondences
    }

    /// Number of down-sampled source points.
    #[getter]
    fn source_points(&self) -> usize {
        self.found.source_points
    }

    fn __repr__(&self) -> String {
        let t = self.found.target_from_source.translation();
        format!(
            "Registration(translation=({:.3}, {:.3}, {:.3}), fitness={:.3}, rmse={:.4}, converged={})",
            t.x, t.y, t.z, self.found.fitness, self.found.rmse_m, self.found.converged
        )
    }
}

/// The registration settings of `raypath register`'s flags.
fn settings(
    voxel_size: f64,
    max_range: f64,
    min_range: f64,
    kernel: &str,
) -> PyResult<RegistrationConfig> {
    let kernel = match kernel {
        "gm" | "geman-mcclure" => Kernel::GemanMcClure,
        "huber" => Kernel::Huber,
        "none" => Kernel::None,
        other => {
            return Err(value_error(
                "kernel",
                format!("expected \"gm\", \"huber\" or \"none\", got {other:?}"),
            ));
        }
    };
    let config = RegistrationConfig {
        voxel_size_m: voxel_size,
        max_range_m: max_range,
        min_range_m: min_range,
        kernel,
        ..RegistrationConfig::default()
    };
    config.validate().map_err(|e| value_error("register", e))?;
    Ok(config)
}

/// Registers `source` to `target` (Chen–Medioni point-to-plane ICP with KISS-ICP's voxel
/// thinning and a robust kernel), as `raypath register SOURCE TARGET`.
///
/// `source`, `target`: `(N, 3)` or `(N, 4)` float32/float64 points, each in its sensor frame
/// (the range crop is about the origin; a fourth column is ignored). `initial`: the initial
/// guess of `target_from_source` as a `(4, 4)` array (default identity). `voxel_size`: `v`,
/// metres (map grid `v/2`, source grid `1.5 v`). `max_range`, `min_range`: returns outside are
/// dropped, metres. `kernel`: `"gm"` (Geman–McClure), `"huber"` or `"none"`. The GIL is
/// released while it runs.
#[pyfunction]
#[pyo3(signature = (source, target, initial = None, *, voxel_size = 1.0, max_range = 100.0, min_range = 0.0, kernel = "gm"))]
#[allow(clippy::too_many_arguments)]
pub fn register(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    target: &Bound<'_, PyAny>,
    initial: Option<&Bound<'_, PyAny>>,
    voxel_size: f64,
    max_range: f64,
    min_range: f64,
    kernel: &str,
) -> PyResult<Registration> {
    let config = settings(voxel_size, max_range, min_range, kernel)?;
    let source = point_cloud(source, "source")?;
    let target = point_cloud(target, "target")?;
    let initial = pose3(initial, "initial")?.unwrap_or_else(Pose3::identity);
    let found = py
        .allow_threads(|| icp(&source, &target, &initial, &config))
        .map_err(input_error)?;
    Ok(Registration { found })
}

/// A scan's pose `(4, 4)` and its registration to the local map.
type PoseAndRegistration<'py> = (Bound<'py, PyArray2<f64>>, Option<Registration>);

/// KISS-ICP-style lidar odometry (as `raypath register SEQUENCE`): each scan is registered to
/// a local voxel map of the previous ones from a constant-velocity guess, with an adaptive
/// correspondence threshold; the world frame is the first scan's sensor frame. The settings
/// are those of `register`.
#[pyclass(module = "raypath.registration", name = "Odometry")]
pub struct Odometry {
    odometry: raypath_registration::Odometry,
}

#[pymethods]
impl Odometry {
    #[new]
    #[pyo3(signature = (*, voxel_size = 1.0, max_range = 100.0, min_range = 0.0, kernel = "gm"))]
    fn new(voxel_size: f64, max_range: f64, min_range: f64, kernel: &str) -> PyResult<Self> {
        let registration = settings(voxel_size, max_range, min_range, kernel)?;
        let odometry = raypath_registration::Odometry::new(OdometryConfig {
            registration,
            ..OdometryConfig::default()
        })
        .map_err(|e| value_error("Odometry", e))?;
        Ok(Self { odometry })
    }

    /// Registers the next scan, `(N, 3)` or `(N, 4)` points in its sensor frame. Returns
    /// `(pose, registration)`: `world_from_sensor` `(4, 4)` and the `Registration` to the local
    /// map (None for the first scan, which defines the frame).
    fn register_frame<'py>(
        &mut self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<PoseAndRegistration<'py>> {
        let cloud = point_cloud(points, "points")?;
        let odometry = &mut self.odometry;
        let step = py
            .allow_threads(|| odometry.register_frame(&cloud))
            .map_err(input_error)?;
        Ok((
            pose3_matrix(py, &step.world_from_sensor),
            step.registration.map(|found| Registration { found }),
        ))
    }

    /// `world_from_sensor` of every scan registered, `(N, 4, 4)`.
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        poses3(py, self.odometry.poses())
    }

    fn __len__(&self) -> usize {
        self.odometry.poses().len()
    }
}
