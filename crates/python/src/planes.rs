//! `raypath.planes.ppe`: probabilistic plane extraction from an organized scan.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use raypath_planes::{PpeParams, extract_grid};

use crate::arrays::{floats, matrix, vec1};
use crate::errors::{input_error, value_error};

/// One plane found by `raypath.planes.ppe`.
#[pyclass(module = "raypath.planes", name = "Plane", frozen)]
pub struct Plane {
    normal: [f64; 3],
    distance: f64,
    rmse: f64,
    indices: Vec<usize>,
}

#[pymethods]
impl Plane {
    /// Unit normal, `(3,)`.
    #[getter]
    fn normal<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.normal.to_vec())
    }

    /// Distance of the plane from the sensor, metres.
    #[getter]
    fn distance(&self) -> f64 {
        self.distance
    }

    /// Radial RMSE of its points, metres.
    #[getter]
    fn rmse(&self) -> f64 {
        self.rmse
    }

    /// Number of points.
    #[getter]
    fn points(&self) -> usize {
        self.indices.len()
    }

    /// Linear indices `row * W + col` of its points, `(n,)` int64.
    #[getter]
    fn indices<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        vec1(py, self.indices.iter().map(|&i| i as i64).collect())
    }

    fn __repr__(&self) -> String {
        format!(
            "Plane(normal=[{:.4}, {:.4}, {:.4}], distance={:.4}, points={}, rmse={:.4})",
            self.normal[0],
            self.normal[1],
            self.normal[2],
            self.distance,
            self.indices.len(),
            self.rmse
        )
    }
}

/// Probabilistic plane extraction (PPE, Schaefer 2020, ch. 11) from an organized scan.
///
/// `organized_xyz`: `(H, W, 3)` float32/float64 points in the sensor frame, metres; NaN rows
/// (or the origin) mark no-returns, infinite values are refused. `preset`: the parameters
/// (`"synpeb"` — the default, as `raypath planes` —, `"synpeb-0.0"` … `"synpeb-4.0"`,
/// `"segcomp"`, `"kitti"`, `"default"`). Returns `(labels, planes)`: `labels` `(H, W)` int32,
/// the index into `planes` of each point's plane or -1; `planes` largest first.
#[pyfunction]
#[pyo3(signature = (organized_xyz, preset = "synpeb"))]
pub fn ppe<'py>(
    py: Python<'py>,
    organized_xyz: &Bound<'py, PyAny>,
    preset: &str,
) -> PyResult<(Bound<'py, PyArray2<i32>>, Vec<Plane>)> {
    let params = PpeParams::preset(preset).ok_or_else(|| {
        value_error(
            "preset",
            format!(
                "unknown preset {preset:?}; one of {}",
                PpeParams::PRESETS.join(", ")
            ),
        )
    })?;
    let expected = "an organized scan of shape (H, W, 3)";
    let f = floats(organized_xyz, "organized_xyz", expected)?;
    let [h, w, 3] = f.shape[..] else {
        return Err(value_error(
            "organized_xyz",
            format!("expected {expected}, got shape {:?}", f.shape),
        ));
    };
    if h == 0 || w == 0 {
        return Err(value_error(
            "organized_xyz",
            format!("expected {expected} with H, W ≥ 1, got shape ({h}, {w}, 3)"),
        ));
    }
    if let Some(i) = f.values.iter().position(|v| v.is_infinite()) {
        let (row, col) = (i / 3 / w, i / 3 % w);
        return Err(value_error(
            "organized_xyz",
            format!("point [{row}, {col}] is infinite (use NaN for no-returns)"),
        ));
    }
    let points: Vec<nalgebra::Vector3<f64>> = f
        .values
        .chunks_exact(3)
        .map(|p| nalgebra::Vector3::new(p[0], p[1], p[2]))
        .collect();
    let seg = py
        .allow_threads(|| extract_grid(&points, w, h, &params))
        .map_err(input_error)?;
    let labels = seg
        .labels
        .iter()
        .map(|l| l.map_or(-1, |l| l as i32))
        .collect();
    let planes = seg
        .planes
        .iter()
        .map(|p| {
            let n = p.fit.normal();
            Plane {
                normal: [n.x, n.y, n.z],
                distance: p.fit.distance_m(),
                rmse: p.fit.rmse_m(),
                indices: p.index.clone(),
            }
        })
        .collect();
    Ok((matrix(py, labels, h, w), planes))
}
