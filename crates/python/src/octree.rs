//! `raypath.OccupancyTree`: the Rtree variable-resolution occupancy grid, exported as an
//! OctoMap `.bt` file.

use std::path::PathBuf;

use numpy::PyArray1;
use pyo3::prelude::*;
use raypath_rtree_grid::{GridConfig, RtreeGrid};

use crate::arrays::vec1;
use crate::errors::{io_error, value_error};

/// A 3-D occupancy map (the Rtree grid of Khan 2017, ch. 2, on OctoMap's key lattice with
/// OctoMap's log-odds update), written as an OctoMap `.bt` file.
///
/// `resolution`: edge of the base cubes, metres. `max_range`: beams longer than this are cut
/// and their end is not marked occupied (None keeps every beam whole).
#[pyclass(module = "raypath")]
pub struct OccupancyTree {
    grid: RtreeGrid,
}

#[pymethods]
impl OccupancyTree {
    #[new]
    #[pyo3(signature = (resolution = 0.2, max_range = None))]
    fn new(resolution: f64, max_range: Option<f64>) -> PyResult<Self> {
        if !(resolution.is_finite() && resolution > 0.0) {
            return Err(value_error(
                "resolution",
                format!("must be a positive number of metres, got {resolution}"),
            ));
        }
        if let Some(r) = max_range
            && (r.is_nan() || r <= 0.0)
        {
            return Err(value_error(
                "max_range",
                format!("must be positive, got {r}"),
            ));
        }
        let config = GridConfig {
            resolution_m: resolution,
            max_range_m: max_range,
            ..GridConfig::default()
        };
        let grid = RtreeGrid::new(config).map_err(|e| value_error("OccupancyTree", e))?;
        Ok(Self { grid })
    }

    /// Inserts one scan: `points` `(N, 3)` float32/float64 endpoints in the world frame,
    /// `origin` `(3,)` the sensor position. Cells along each beam become freer, the end cells
    /// more occupied. Returns the number of beams inserted.
    fn insert(
        &mut self,
        py: Python<'_>,
        points: &Bound<'_, PyAny>,
        origin: &Bound<'_, PyAny>,
    ) -> PyResult<usize> {
        let (rows, _) = crate::arrays::points(points, "points", &[3])?;
        let o = crate::arrays::vector(origin, "origin", 3, true)?;
        if o.len() != 3 || !o.iter().all(|v| v.is_finite()) {
            return Err(value_error(
                "origin",
                format!("expected 3 finite values, got {o:?}"),
            ));
        }
        let origin = nalgebra::Point3::new(o[0], o[1], o[2]);
        let pts: Vec<nalgebra::Point3<f64>> = rows
            .iter()
            .map(|p| nalgebra::Point3::new(p[0], p[1], p[2]))
            .collect();
        let grid = &mut self.grid;
        let update = py.allow_threads(|| grid.insert_scan(&origin, &pts));
        Ok(update.beams)
    }

    /// Occupancy probability at each of `points` `(N, 3)`; NaN where unknown.
    fn occupancy<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let (rows, _) = crate::arrays::points(points, "points", &[3])?;
        let values = rows
            .iter()
            .map(|p| {
                self.grid
                    .occupancy_at(&nalgebra::Point3::new(p[0], p[1], p[2]))
                    .unwrap_or(f64::NAN)
            })
            .collect();
        Ok(vec1(py, values))
    }

    /// Writes the map as an OctoMap binary tree (`.bt`, readable by `octovis` and OctoMap).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let tree = py.allow_threads(|| self.grid.to_octree());
        raypath_io::octomap::write_bt_file(&path, &tree).map_err(io_error)
    }

    /// Leaves of the R-tree (cells and fused cuboids).
    #[getter]
    fn leaves(&self) -> usize {
        self.grid.num_leaves()
    }

    /// Scans inserted.
    #[getter]
    fn scans(&self) -> u64 {
        self.grid.scans()
    }

    /// Bytes of memory the map holds.
    #[getter]
    fn memory_bytes(&self) -> usize {
        self.grid.memory_bytes()
    }

    /// The edge of the base cubes, metres.
    #[getter]
    fn resolution(&self) -> f64 {
        self.grid.config().resolution_m
    }

    fn __repr__(&self) -> String {
        format!(
            "OccupancyTree(resolution={}, {} scans, {} leaves)",
            self.grid.config().resolution_m,
            self.grid.scans(),
            self.grid.num_leaves()
        )
    }
}
