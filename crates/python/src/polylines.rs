//! `raypath.polylines.ple`: maximum-likelihood polyline extraction from a planar scan.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use raypath_polylines::{Method, PolylineConfig, extract};

use crate::arrays::{matrix, scan2, vec1};
use crate::errors::{input_error, value_error};

/// One polyline (open) or polygon (closed), vertices in the scan frame.
#[pyclass(module = "raypath.polylines", name = "Polyline", frozen)]
pub struct Polyline {
    vertices: Vec<[f64; 2]>,
    rays: Vec<usize>,
    closed: bool,
}

#[pymethods]
impl Polyline {
    /// `(V, 2)` float64 vertices, metres.
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let flat = self.vertices.iter().flatten().copied().collect();
        matrix(py, flat, self.vertices.len(), 2)
    }

    /// `(V,)` int64: the beam whose endpoint created each vertex.
    #[getter]
    fn rays<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        vec1(py, self.rays.iter().map(|&r| r as i64).collect())
    }

    /// True for a closed polygon (the last vertex connects back to the first).
    #[getter]
    fn closed(&self) -> bool {
        self.closed
    }

    fn __len__(&self) -> usize {
        self.vertices.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Polyline({} vertices, closed={})",
            self.vertices.len(),
            if self.closed { "True" } else { "False" }
        )
    }
}

/// Polyline extraction from one planar scan (Schaefer 2020, ch. 10).
///
/// `ranges`, `angles`: `(B,)` float arrays, B ≥ 2; the angles evenly spaced and increasing
/// (radians). Ranges at or above `max_range` (default: infinity) and infinite ranges are
/// no-returns; NaN is refused. `max_vertices`: `J_max` (20, as `raypath polylines`). `method`: `"ple"` (default),
/// `"ple+"` (vertex optimization), or the baselines `"vvl"`, `"ief"`, `"sam"`. `max_edge`:
/// `l_max`, metres. Returns the polylines, in the scan frame.
#[pyfunction]
#[pyo3(signature = (ranges, angles, max_vertices = 20, method = "ple", max_edge = 1.0, max_range = None))]
pub fn ple(
    py: Python<'_>,
    ranges: &Bound<'_, PyAny>,
    angles: &Bound<'_, PyAny>,
    max_vertices: usize,
    method: &str,
    max_edge: f64,
    max_range: Option<f64>,
) -> PyResult<Vec<Polyline>> {
    let method = match method.to_ascii_lowercase().as_str() {
        "ple" => Method::Ple,
        "ple+" | "ple_plus" => Method::PlePlus,
        "vvl" => Method::Vvl,
        "ief" => Method::Ief,
        "sam" => Method::Sam,
        other => {
            return Err(value_error(
                "method",
                format!(
                    "expected one of \"ple\", \"ple+\", \"vvl\", \"ief\", \"sam\", got {other:?}"
                ),
            ));
        }
    };
    let scan = scan2(ranges, angles, max_range)?;
    let config = PolylineConfig {
        max_edge_m: max_edge,
        ..PolylineConfig::new(method, max_vertices)
    };
    config.validate().map_err(|e| value_error("ple", e))?;
    let result = py
        .allow_threads(|| extract(&scan, &config))
        .map_err(input_error)?;
    Ok(result
        .lines
        .iter()
        .map(|p| Polyline {
            vertices: p.vertices.iter().map(|v| [v.x, v.y]).collect(),
            rays: p.rays.clone(),
            closed: p.closed,
        })
        .collect())
}
