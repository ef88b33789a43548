//! `raypath.dct_map.fit`: a continuous DCT decay-rate map (Schaefer 2020, ch. 9) and its grid
//! baseline, fitted to the rays of a planar log as `raypath dct-map` does.

use std::collections::BTreeMap;
use std::path::PathBuf;

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use raypath_dct_map::experiment::{Comparison, GroundTruth, auto_patch, compare, draw_rays};
use raypath_dct_map::{DctMap as Map, FitConfig, GridRateMap, Patch, RangeLimits, Shape};
use raypath_geometry::Ray2;

use crate::arrays::{floats, matrix, vec1};
use crate::errors::{input_error, value_error};
use crate::io::PlanarLog;

/// Held-back rays scored by both maps (`raypath dct-map`'s, Sec. 9.5.2).
const HELD_BACK: usize = 500;
/// Ground-truth cell edge (Sec. 9.5.1), and the default lattice cell of `rates`.
const TRUTH_CELL_M: f64 = 0.05;

/// A fitted DCT decay-rate map over a rectangular patch, with the `L × M` grid map fitted to
/// the same rays and the scores of both on held-back rays.
#[pyclass(module = "raypath.dct_map", name = "DctMap", frozen)]
pub struct DctMap {
    map: Map,
    grid: GridRateMap,
    patch: Patch,
    comparison: Comparison,
    rays: usize,
    held_back: usize,
}

#[pymethods]
impl DctMap {
    /// The coefficients `a`, `(L, M)` float64 (`λ = g²`, `g` the inverse DCT of `a`).
    #[getter]
    fn coefficients<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let s = self.map.shape();
        matrix(py, self.map.coefficients().to_vec(), s.l, s.m)
    }

    /// The patch `(x0, y0, X, Y)` in the world frame, metres.
    #[getter]
    fn patch(&self) -> (f64, f64, f64, f64) {
        let [x, y] = self.patch.extent_m;
        (self.patch.min[0], self.patch.min[1], x, y)
    }

    /// The decay rate `λ` (1/m) at world points `(N, 2)`; NaN outside the patch.
    fn rate_at<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let expected = "an array of shape (N, 2)";
        let f = floats(points, "points", expected)?;
        if f.shape.len() != 2 || f.shape[1] != 2 {
            return Err(value_error(
                "points",
                format!("expected {expected}, got shape {:?}", f.shape),
            ));
        }
        let [xe, ye] = self.patch.extent_m;
        let rates = f
            .values
            .chunks_exact(2)
            .map(|p| {
                let (x, y) = (p[0] - self.patch.min[0], p[1] - self.patch.min[1]);
                if (0.0..=xe).contains(&x) && (0.0..=ye).contains(&y) {
                    self.map.rate_at([x, y])
                } else {
                    f64::NAN
                }
            })
            .collect();
        Ok(vec1(py, rates))
    }

    /// `λ` at the centres of square cells of edge about `cell` metres over the patch,
    /// `(ny, nx)` float64, row 0 the lowest y (the lattice of `raypath dct-map --out x.png`
    /// for the default 5 cm).
    #[pyo3(signature = (cell = TRUTH_CELL_M))]
    fn rates<'py>(&self, py: Python<'py>, cell: f64) -> PyResult<Bound<'py, PyArray2<f64>>> {
        if !(cell.is_finite() && cell > 0.0) {
            return Err(value_error("cell", format!("must be positive, got {cell}")));
        }
        let [xe, ye] = self.map.extent_m();
        let (nx, ny) = (
            ((xe / cell).round() as usize).max(1),
            ((ye / cell).round() as usize).max(1),
        );
        if nx.saturating_mul(ny) > 100_000_000 {
            return Err(value_error(
                "cell",
                format!("{nx} × {ny} cells are too many"),
            ));
        }
        // `rates_on_lattice` is x-major (`ix · ny + iy`); the array is row by row.
        let lattice = py.allow_threads(|| self.map.rates_on_lattice(nx, ny));
        let rows = (0..ny)
            .flat_map(|iy| (0..nx).map(move |ix| ix * ny + iy))
            .map(|k| lattice.get(k).copied().unwrap_or(f64::NAN))
            .collect();
        Ok(matrix(py, rows, ny, nx))
    }

    /// The grid baseline's decay rates (1/m) with as many parameters as the DCT map, square
    /// cells from the patch's lower-left corner, `(rows, cols)` float64, row 0 the lowest y;
    /// the cell edge is `baseline_cell`.
    #[getter]
    fn baseline<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let [w, h] = self.grid.grid().dims();
        matrix(py, self.grid.rates().to_vec(), h, w)
    }

    /// The cell edge of `baseline`, metres.
    #[getter]
    fn baseline_cell(&self) -> f64 {
        self.grid.grid().cell_size()
    }

    /// The scores of `raypath dct-map --json`: `log_likelihood`, `grid_log_likelihood` (of the
    /// held-back rays), `rmse_p_ref`, `grid_rmse_p_ref` (against the 5 cm ground truth),
    /// `iterations`, `time_s`, `grid_time_s`, `rays`, `held_back_rays`.
    #[getter]
    fn scores(&self) -> BTreeMap<&'static str, f64> {
        let c = &self.comparison;
        BTreeMap::from([
            ("log_likelihood", c.log_likelihood),
            ("grid_log_likelihood", c.grid_log_likelihood),
            ("rmse_p_ref", c.rmse_p_ref),
            ("grid_rmse_p_ref", c.grid_rmse_p_ref),
            ("iterations", c.iterations as f64),
            ("time_s", c.time_s),
            ("grid_time_s", c.grid_time_s),
            ("rays", self.rays as f64),
            ("held_back_rays", self.held_back as f64),
        ])
    }

    /// Writes the coefficients as JSON (the file of `raypath dct-map --out map.json`).
    fn save(&self, path: PathBuf) -> PyResult<()> {
        let text = serde_json::to_string_pretty(&self.map).map_err(input_error)?;
        std::fs::write(&path, text).map_err(|e| input_error(format!("{}: {e}", path.display())))
    }

    fn __repr__(&self) -> String {
        let s = self.map.shape();
        let [x, y] = self.patch.extent_m;
        format!("DctMap({} × {} coefficients over {x} × {y} m)", s.l, s.m)
    }
}

/// Fits a DCT decay-rate map of `coefficients = (L, M)` and an `L × M` grid map to the rays
/// of a planar log at its reference poses (a corrected CARMEN log's laser poses), as
/// `raypath dct-map LOG --coefficients L,M`: rays clipped to `patch` (`(x0, y0, X, Y)`, or
/// None for the 10 m × 10 m patch with the most ray path length), shuffled with `seed`,
/// `rays` of them for mapping and 500 held back for the scores. The GIL is released while it
/// fits.
#[pyfunction]
#[pyo3(signature = (log, coefficients, *, patch = None, rays = 10_000, seed = 9))]
pub fn fit(
    py: Python<'_>,
    log: &Bound<'_, PlanarLog>,
    coefficients: (usize, usize),
    patch: Option<(f64, f64, f64, f64)>,
    rays: usize,
    seed: u64,
) -> PyResult<DctMap> {
    let (l, m) = coefficients;
    if !(1..=200).contains(&l) || !(1..=200).contains(&m) {
        return Err(value_error(
            "coefficients",
            format!("L and M must be in 1..=200, got ({l}, {m})"),
        ));
    }
    if rays == 0 {
        return Err(value_error("rays", "must be positive"));
    }
    let log = log.get();
    let mut all: Vec<Ray2> = Vec::new();
    let with_reference = log.frames.iter().any(|f| f.reference.is_some());
    for frame in log.frames.iter() {
        let pose = if with_reference {
            frame.reference
        } else {
            Some(frame.world_from_laser)
        };
        if let Some(pose) = pose {
            all.extend(frame.scan.rays(pose));
        }
    }
    if all.is_empty() {
        return Err(input_error(format!(
            "{}: no laser scans",
            log.path.display()
        )));
    }
    let patch = match patch {
        None => auto_patch(&all, 10.0).ok_or_else(|| {
            input_error(format!(
                "{}: no rays to choose a patch from",
                log.path.display()
            ))
        })?,
        Some((x0, y0, x, y)) => {
            if ![x0, y0, x, y].iter().all(|v| v.is_finite()) || x <= 0.0 || y <= 0.0 {
                return Err(value_error(
                    "patch",
                    format!(
                        "expected finite (x0, y0, X, Y) with X, Y > 0, got ({x0}, {y0}, {x}, {y})"
                    ),
                ));
            }
            Patch {
                min: [x0, y0],
                extent_m: [x, y],
            }
        }
    };
    let shape = Shape { l, m };
    let (map, grid, comparison, used, held_back) = py
        .allow_threads(|| {
            let (mapping, held) =
                draw_rays(&all, &patch, &RangeLimits::default(), rays, HELD_BACK, seed);
            if mapping.is_empty() {
                return Err(format!("no ray reaches the patch {patch:?}"));
            }
            let truth = GroundTruth::new(patch.extent_m, TRUTH_CELL_M, &mapping)
                .map_err(|e| e.to_string())?;
            let (map, grid, c) = compare(
                patch.extent_m,
                shape,
                &mapping,
                &held,
                &truth,
                &FitConfig::default(),
            )
            .map_err(|e| e.to_string())?;
            Ok((map, grid, c, mapping.len(), held.len()))
        })
        .map_err(|e| input_error(format!("{}: {e}", log.path.display())))?;
    Ok(DctMap {
        map,
        grid,
        patch,
        comparison,
        rays: used,
        held_back,
    })
}
