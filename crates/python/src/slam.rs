//! `raypath.slam`: 2-D lidar SLAM of a planar log, with the map rebuilt from the optimised
//! poses.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use raypath_geometry::{Grid2, Pose2};
use raypath_sensor_models::export::{RosMapOptions, write_ros_map};
use raypath_slam::benchmark::{file_relation_errors, match_relation_file};
use raypath_slam::{Slam, SlamConfig};

use crate::arrays::{matrix, poses2, vec1};
use crate::errors::{input_error, io_error, value_error};
use crate::io::{PlanarLog, read_planar};
use crate::pipeline::rebuild_map;

/// Scans processed between two progress calls (and checks for Ctrl-C).
const PROGRESS_EVERY: usize = 100;

/// A 2-D occupancy map: per cell the reflection probability `H / (H + M)` of the rays that
/// crossed it, NaN where no ray did.
#[pyclass(module = "raypath", frozen)]
pub struct OccupancyMap {
    grid: Grid2,
    values: Vec<Option<f64>>,
}

#[pymethods]
impl OccupancyMap {
    /// The map, `(H, W)` float64 in [0, 1], NaN for unknown cells. Row 0 is the lowest y
    /// (`origin[1]`), column 0 the lowest x: `array[i, j]` is the cell whose lower corner is
    /// `origin + (j, i) · resolution`.
    #[getter]
    fn array<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let [w, h] = self.grid.dims();
        let flat = self.values.iter().map(|v| v.unwrap_or(f64::NAN)).collect();
        matrix(py, flat, h, w)
    }

    /// Cell edge, metres.
    #[getter]
    fn resolution(&self) -> f64 {
        self.grid.cell_size()
    }

    /// The lower corner `(x, y)` of cell `[0, 0]`, metres.
    #[getter]
    fn origin(&self) -> (f64, f64) {
        let o = self.grid.origin();
        (o.x, o.y)
    }

    /// `(H, W)`.
    #[getter]
    fn shape(&self) -> (usize, usize) {
        let [w, h] = self.grid.dims();
        (h, w)
    }

    /// Writes the map as ROS `map_server` files: `path` with the extension `.pgm` (the
    /// picture, top row = highest y) and `.yaml` (resolution, origin, thresholds). Returns
    /// both paths.
    fn save(&self, path: PathBuf) -> PyResult<(String, String)> {
        let (pgm, yaml) = write_ros_map(&path, &self.grid, &self.values, &RosMapOptions::default())
            .map_err(input_error)?;
        Ok((pgm.display().to_string(), yaml.display().to_string()))
    }

    fn __repr__(&self) -> String {
        let [w, h] = self.grid.dims();
        format!(
            "OccupancyMap({h} × {w} cells of {} m)",
            self.grid.cell_size()
        )
    }
}

/// What `raypath.slam` returns.
#[pyclass(module = "raypath", frozen)]
pub struct SlamResult {
    poses: Vec<Pose2>,
    stamps: Vec<f64>,
    ipc_stamps: Vec<Option<f64>>,
    loops: Vec<[i64; 2]>,
    loop_scores: Vec<f64>,
    nodes: usize,
    submaps: usize,
    seconds: f64,
    map: Py<OccupancyMap>,
}

#[pymethods]
impl SlamResult {
    /// The optimised laser pose of every scan, `(N, 3)` float64 (`x, y, theta`; the world
    /// frame is the first scan's).
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        poses2(py, self.poses.iter().copied())
    }

    /// The sensor time stamp of every scan, `(N,)` float64 seconds.
    #[getter]
    fn stamps<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.stamps.clone())
    }

    /// The map rebuilt from the optimised poses.
    #[getter]
    fn map(&self, py: Python<'_>) -> Py<OccupancyMap> {
        self.map.clone_ref(py)
    }

    /// Accepted loop closures, `(K, 2)` int64: the scan closing the loop and the scan of the
    /// node it was tied to.
    #[getter]
    fn loops<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        let flat = self.loops.iter().flatten().copied().collect();
        matrix(py, flat, self.loops.len(), 2)
    }

    /// The branch-and-bound score of each accepted loop closure, `(K,)`.
    #[getter]
    fn loop_scores<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.loop_scores.clone())
    }

    /// Nodes of the pose graph.
    #[getter]
    fn nodes(&self) -> usize {
        self.nodes
    }

    /// Finished submaps.
    #[getter]
    fn submaps(&self) -> usize {
        self.submaps
    }

    /// Seconds of SLAM (map rebuild excluded).
    #[getter]
    fn seconds(&self) -> f64 {
        self.seconds
    }

    /// Relation errors (Kümmerle et al. 2009) of the trajectory over a SLAM-benchmark relation
    /// file (`t1 t2 x y z roll pitch yaw`, scans named by their CARMEN ipc time stamps), as
    /// `raypath slam --relations` reports them: a dict with `trans_error_m`,
    /// `trans_error_std_m`, `rot_error_deg`, `rot_error_std_deg`, `relations` and
    /// `unmatched`.
    fn relation_errors<'py>(&self, py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
        let relations = raypath_io::relations::read_relations(&path).map_err(io_error)?;
        let matched = match_relation_file(&self.ipc_stamps, &relations);
        if matched.relations.is_empty() {
            return Err(input_error(format!(
                "{}: none of its {} relations names two scans of this run by their ipc time stamps",
                path.display(),
                relations.len()
            )));
        }
        let s = file_relation_errors(&self.poses, &matched);
        let d = PyDict::new(py);
        d.set_item("trans_error_m", s.trans_error_m)?;
        d.set_item("trans_error_std_m", s.trans_error_std_m)?;
        d.set_item("rot_error_deg", s.rot_error_deg)?;
        d.set_item("rot_error_std_deg", s.rot_error_std_deg)?;
        d.set_item("relations", s.relations)?;
        d.set_item("unmatched", matched.unmatched)?;
        Ok(d)
    }

    fn __len__(&self) -> usize {
        self.poses.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "SlamResult({} scans, {} nodes, {} loop closures)",
            self.poses.len(),
            self.nodes,
            self.loops.len()
        )
    }
}

/// 2-D lidar SLAM of a raw log (the `raypath slam` pipeline): Hector-style submap front-end,
/// branch-and-bound loop closure, robust pose graph; then the map rebuilt from the optimised
/// poses with the reflection model.
///
/// `log`: a `PlanarLog` from `raypath.open`, or the path of a CARMEN log or rosbag2 bag.
/// `resolution`: finest submap cell and cell of the map, metres. `max_range`: readings at or
/// above it are not used, metres. `loops=False`: no loop closure. `odometry=False`: do not use
/// the logged odometry as the initial guess. `scans`: process only the first N scans.
/// `progress`: called as `progress(done, total)` every few scans; an exception it raises
/// stops the run. The GIL is released while scans are processed.
#[pyfunction]
#[pyo3(signature = (log, *, resolution = 0.05, max_range = 30.0, loops = true, odometry = true, scans = None, progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn slam(
    py: Python<'_>,
    log: &Bound<'_, PyAny>,
    resolution: f64,
    max_range: f64,
    loops: bool,
    odometry: bool,
    scans: Option<usize>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<SlamResult> {
    let (name, frames) = if let Ok(planar) = log.downcast::<PlanarLog>() {
        let planar = planar.get();
        (planar.path.clone(), Arc::clone(&planar.frames))
    } else if let Ok(path) = log.extract::<PathBuf>() {
        let frames = py.allow_threads(|| read_planar(&path)).map_err(io_error)?;
        (path, Arc::new(frames))
    } else {
        return Err(value_error(
            "log",
            format!(
                "expected a PlanarLog (raypath.open) or a path, got {}",
                log.get_type().name()?
            ),
        ));
    };
    if !(resolution.is_finite() && resolution > 0.0) {
        return Err(value_error(
            "resolution",
            format!("must be a positive number of metres, got {resolution}"),
        ));
    }
    if !(max_range.is_finite() && max_range > 0.0) {
        return Err(value_error(
            "max_range",
            format!("must be a positive number of metres, got {max_range}"),
        ));
    }
    let mut config = SlamConfig::default();
    config.matcher.map.finest_resolution_m = resolution;
    config.filter.max_range_m = max_range;
    config.use_odometry = odometry;
    if !loops {
        config.loops = None;
    }
    config.validate().map_err(|e| value_error("slam", e))?;
    let count = scans.map_or(frames.len(), |n| {
        n.clamp(1, frames.len().max(1)).min(frames.len())
    });
    let frames = &frames[..count];
    if frames.is_empty() {
        return Err(input_error(format!("{}: no laser scans", name.display())));
    }
    let started = Instant::now();
    let mut slam = Slam::new(config).map_err(|e| value_error("slam", e))?;
    for start in (0..frames.len()).step_by(PROGRESS_EVERY) {
        let end = (start + PROGRESS_EVERY).min(frames.len());
        py.allow_threads(|| {
            for (k, frame) in frames[start..end].iter().enumerate() {
                slam.process(frame).map_err(|e| (start + k, e))?;
            }
            Ok(())
        })
        .map_err(|(k, e): (usize, raypath_slam::SlamError)| {
            input_error(format!("{}: scan {k}: {e}", name.display()))
        })?;
        if let Some(callback) = &progress {
            callback.call1((end, frames.len()))?;
        }
        py.check_signals()?;
    }
    let output = py.allow_threads(|| slam.finish()).map_err(input_error)?;
    let seconds = started.elapsed().as_secs_f64();
    let (grid, values) = py
        .allow_threads(|| rebuild_map(frames, &output.world_from_sensor, resolution, max_range))
        .map_err(|e| input_error(format!("{}: {e}", name.display())))?;
    let scan_of = |node: usize| output.node_scan.get(node).map_or(-1, |&s| s as i64);
    Ok(SlamResult {
        poses: output.world_from_sensor.clone(),
        stamps: output.scans.iter().map(|s| s.stamp_secs).collect(),
        ipc_stamps: frames.iter().map(|f| f.ipc_stamp_secs).collect(),
        loops: output
            .loop_closures
            .iter()
            .map(|c| [scan_of(c.node), scan_of(c.anchor)])
            .collect(),
        loop_scores: output.loop_closures.iter().map(|c| c.score).collect(),
        nodes: output.nodes.len(),
        submaps: output.submaps.len(),
        seconds,
        map: Py::new(py, OccupancyMap { grid, values })?,
    })
}
