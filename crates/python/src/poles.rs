//! `raypath.poles.extract`: pole landmarks from a registered 3-D scan.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use raypath_geometry::Pose3;
use raypath_poles::{Pole, Preset, extract_poles};

use crate::arrays::{matrix, point_cloud, pose3, vec1};
use crate::errors::{input_error, value_error};

/// Poles found by `raypath.poles.extract`, in the world frame (metres).
#[pyclass(module = "raypath.poles", name = "Poles", frozen)]
pub struct Poles {
    poles: Vec<Pole>,
}

#[pymethods]
impl Poles {
    /// `(M, 3)` float64: `x, y, radius` of each pole (radius = half the footprint width).
    #[getter]
    fn array<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let flat = self
            .poles
            .iter()
            .flat_map(|p| [p.x, p.y, p.width / 2.0])
            .collect();
        matrix(py, flat, self.poles.len(), 3)
    }

    /// `(M, 2)` float64: the pole centres.
    #[getter]
    fn xy<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let flat = self.poles.iter().flat_map(|p| [p.x, p.y]).collect();
        matrix(py, flat, self.poles.len(), 2)
    }

    /// `(M,)` footprint edge lengths, metres.
    #[getter]
    fn width<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.poles.iter().map(|p| p.width).collect())
    }

    /// `(M,)` radii (half the widths), metres.
    #[getter]
    fn radius<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.poles.iter().map(|p| p.width / 2.0).collect())
    }

    /// `(M,)` heights of the voxel stacks, metres.
    #[getter]
    fn height<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.poles.iter().map(Pole::height).collect())
    }

    /// `(M,)` pole scores in [0, 1].
    #[getter]
    fn score<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.poles.iter().map(|p| p.score).collect())
    }

    fn __len__(&self) -> usize {
        self.poles.len()
    }

    fn __repr__(&self) -> String {
        format!("Poles({} poles)", self.poles.len())
    }
}

/// Extracts poles from one 3-D scan (Schaefer 2020, ch. 12): a local hit/miss voxel map
/// traced from the sensor, Beta-posterior occupancy, pole scores, mean-shift centres.
///
/// `points`: `(N, 3)` or `(N, 4)` float32/float64 in the sensor frame (a fourth column, such
/// as KITTI's reflectance, is ignored); every row finite. `pose`: `world_from_sensor` as a
/// `(4, 4)` array (default identity); the local map is centred at the sensor and the poles
/// are returned in the world frame. `preset`: `"kitti"` (0.1 m voxels) or `"nclt"` (0.2 m).
/// The same as `raypath poles extract --max-scans 1 --sweep-timing origin` on the scan.
#[pyfunction]
#[pyo3(signature = (points, pose = None, preset = "kitti"))]
pub fn extract(
    py: Python<'_>,
    points: &Bound<'_, PyAny>,
    pose: Option<&Bound<'_, PyAny>>,
    preset: &str,
) -> PyResult<Poles> {
    let preset = match preset {
        "kitti" => Preset::kitti(),
        "nclt" => Preset::nclt(),
        other => {
            return Err(value_error(
                "preset",
                format!("expected \"kitti\" or \"nclt\", got {other:?}"),
            ));
        }
    };
    let cloud = point_cloud(points, "points")?;
    let pose = pose3(pose, "pose")?.unwrap_or_else(Pose3::identity);
    let poles = py
        .allow_threads(|| {
            let center = nalgebra::Point3::from(pose.translation());
            extract_poles(&[(pose, &cloud)], &center, &preset.extraction)
        })
        .map_err(input_error)?
        .0;
    Ok(Poles { poles })
}
