//! `raypath.open`: every input the command line reads, as NumPy arrays.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::{PyArray1, PyArray2, PyArray3};
use pyo3::exceptions::PyIndexError;
use pyo3::prelude::*;
use raypath_geometry::PointCloud;
use raypath_io::Format;
use raypath_io::sequence::{PlanarFrame, PlanarOptions, SweepOptions, SweepSequence};

use crate::arrays::{matrix, poses2, poses3, vec1};
use crate::errors::{input_error, io_error};

/// One point cloud (a PCD file, a KITTI `.bin`, an `x y z` file, or one sweep of a sequence),
/// in the sensor frame, metres.
#[pyclass(module = "raypath", frozen)]
pub struct Cloud {
    pub(crate) cloud: PointCloud,
}

#[pymethods]
impl Cloud {
    /// The points, `(N, 3)` float32 (NaN rows mark missing points of an organized cloud).
    #[getter]
    fn points<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f32>> {
        let flat: Vec<f32> = self
            .cloud
            .points
            .iter()
            .flat_map(|p| [p.x, p.y, p.z])
            .collect();
        matrix(py, flat, self.cloud.points.len(), 3)
    }

    /// Per-point intensity, `(N,)` float32, or None.
    #[getter]
    fn intensity<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f32>>> {
        self.cloud.intensity.clone().map(|v| vec1(py, v))
    }

    /// Per-point integer labels, `(N,)` uint32, or None.
    #[getter]
    fn labels<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<u32>>> {
        self.cloud.label.clone().map(|v| vec1(py, v))
    }

    /// Columns of an organized cloud (the number of points otherwise).
    #[getter]
    fn width(&self) -> usize {
        self.cloud.width
    }

    /// Rows of an organized cloud (1 otherwise).
    #[getter]
    fn height(&self) -> usize {
        self.cloud.height
    }

    /// True for an organized cloud (a range image: height > 1).
    #[getter]
    fn is_organized(&self) -> bool {
        self.cloud.is_organized()
    }

    /// The points as an `(H, W, 3)` float32 grid (for `raypath.planes.ppe`).
    fn organized<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let (w, h) = (self.cloud.width, self.cloud.height);
        if w * h != self.cloud.points.len() {
            return Err(input_error(format!(
                "the cloud is not organized: {w} × {h} for {} points",
                self.cloud.points.len()
            )));
        }
        let flat: Vec<f32> = self
            .cloud
            .points
            .iter()
            .flat_map(|p| [p.x, p.y, p.z])
            .collect();
        numpy::ndarray::Array3::from_shape_vec((h, w, 3), flat)
            .map(|a| numpy::IntoPyArray::into_pyarray(a, py))
            .map_err(|e| input_error(e.to_string()))
    }

    fn __len__(&self) -> usize {
        self.cloud.points.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Cloud({} points, {} × {})",
            self.cloud.points.len(),
            self.cloud.width,
            self.cloud.height
        )
    }
}

/// One planar laser scan of a log.
#[pyclass(module = "raypath", frozen)]
pub struct Scan {
    pub(crate) frame: PlanarFrame,
}

#[pymethods]
impl Scan {
    /// Ranges, `(B,)` float64, metres (no-returns at or above `max_range`).
    #[getter]
    fn ranges<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.frame.scan.ranges.clone())
    }

    /// Beam angles, `(B,)` float64, radians in the laser frame.
    #[getter]
    fn angles<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let s = &self.frame.scan;
        vec1(py, (0..s.len()).map(|i| s.angle(i)).collect())
    }

    /// Intensities, `(B,)` float64, or None.
    #[getter]
    fn intensities<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.frame.scan.intensities.clone().map(|v| vec1(py, v))
    }

    /// Readings at or above this range are no-returns, metres.
    #[getter]
    fn max_range(&self) -> f64 {
        self.frame.scan.max_range_m
    }

    /// The logged laser pose `(x, y, theta)` (odometry in a raw log).
    #[getter]
    fn pose<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let p = self.frame.world_from_laser;
        vec1(py, vec![p.x(), p.y(), p.theta()])
    }

    /// The logged robot pose `(x, y, theta)` (the odometry in a raw log).
    #[getter]
    fn odometry<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        crate::arrays::pose_vector(py, self.frame.world_from_robot)
    }

    /// The laser's mounting `robot_from_laser` `(x, y, theta)`.
    #[getter]
    fn robot_from_laser<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        crate::arrays::pose_vector(py, self.frame.robot_from_laser())
    }

    /// The sensor time stamp, seconds.
    #[getter]
    fn stamp(&self) -> f64 {
        self.frame.sensor_stamp_secs()
    }

    fn __len__(&self) -> usize {
        self.frame.scan.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Scan({} beams at t = {})",
            self.frame.scan.len(),
            self.frame.sensor_stamp_secs()
        )
    }
}

/// A log of planar laser scans: a CARMEN log or a rosbag2 bag's LaserScan topic. Index it
/// for a `Scan`; pass it to `raypath.slam`.
#[pyclass(module = "raypath", frozen)]
pub struct PlanarLog {
    pub(crate) path: PathBuf,
    pub(crate) format: &'static str,
    pub(crate) frames: Arc<Vec<PlanarFrame>>,
}

#[pymethods]
impl PlanarLog {
    /// The file or bag.
    #[getter]
    fn path(&self) -> String {
        self.path.display().to_string()
    }

    /// The format's name (`carmen`, `rosbag2`).
    #[getter]
    fn format(&self) -> &'static str {
        self.format
    }

    /// Sensor time stamps, `(N,)` float64 seconds (the CARMEN ipc time stamp where the log
    /// has one, the message header stamp in a bag).
    #[getter]
    fn stamps<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(
            py,
            self.frames
                .iter()
                .map(PlanarFrame::sensor_stamp_secs)
                .collect(),
        )
    }

    /// The logged laser poses `(N, 3)` (`x, y, theta`): odometry in raw logs and bags, the
    /// corrected poses in a corrected log.
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        poses2(py, self.frames.iter().map(|f| f.world_from_laser))
    }

    /// The logged robot poses `(N, 3)`.
    #[getter]
    fn odometry<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        poses2(py, self.frames.iter().map(|f| f.world_from_robot))
    }

    fn __len__(&self) -> usize {
        self.frames.len()
    }

    fn __getitem__(&self, index: isize) -> PyResult<Scan> {
        let i = normalize(index, self.frames.len())?;
        Ok(Scan {
            frame: self.frames[i].clone(),
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "PlanarLog({:?}, {} scans)",
            self.path.display().to_string(),
            self.frames.len()
        )
    }
}

/// A sequence of 3-D sweeps: a KITTI sequence, an NCLT session, a bag's PointCloud2 topic or
/// an Ouster capture. Sweeps are read when indexed.
#[pyclass(module = "raypath", frozen)]
pub struct SweepLog {
    sequence: SweepSequence,
    format: &'static str,
}

impl SweepLog {
    /// The directory or file it was opened from.
    pub(crate) fn path_buf(&self) -> PathBuf {
        self.sequence.name.clone()
    }
}

#[pymethods]
impl SweepLog {
    /// The directory or file.
    #[getter]
    fn path(&self) -> String {
        self.sequence.name.display().to_string()
    }

    /// The format's name.
    #[getter]
    fn format(&self) -> &'static str {
        self.format
    }

    /// Sweep times, `(N,)` float64 seconds.
    #[getter]
    fn stamps<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.sequence.stamps_secs.clone())
    }

    /// Reference `world_from_sensor` per sweep, `(N, 4, 4)`, or None.
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray3<f64>>> {
        self.sequence.reference.as_deref().map(|p| poses3(py, p))
    }

    /// Odometry `odom_from_sensor` per sweep, `(N, 4, 4)`, or None.
    #[getter]
    fn odometry<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray3<f64>>> {
        self.sequence.odometry.as_deref().map(|p| poses3(py, p))
    }

    fn __len__(&self) -> usize {
        self.sequence.len()
    }

    fn __getitem__(&self, py: Python<'_>, index: isize) -> PyResult<Cloud> {
        let i = normalize(index, self.sequence.len())?;
        let cloud = py
            .allow_threads(|| self.sequence.sweep(i))
            .map_err(io_error)?;
        Ok(Cloud { cloud })
    }

    fn __repr__(&self) -> String {
        format!(
            "SweepLog({:?}, {} sweeps)",
            self.sequence.name.display().to_string(),
            self.sequence.len()
        )
    }
}

pub(crate) fn normalize(index: isize, len: usize) -> PyResult<usize> {
    let i = if index < 0 {
        index + len as isize
    } else {
        index
    };
    if i < 0 || i as usize >= len {
        return Err(PyIndexError::new_err(format!(
            "index {index} out of range for {len} items"
        )));
    }
    Ok(i as usize)
}

/// Reads every planar frame of `path` (a CARMEN log or a bag's LaserScan topic).
pub fn read_planar(path: &std::path::Path) -> Result<Vec<PlanarFrame>, raypath_io::Error> {
    raypath_io::sequence::read_planar(path, &PlanarOptions::default())
}

/// Opens any input the `raypath` command line reads, detected from its content:
///
/// * a CARMEN log (`.log`, `.clf`; plain, `.gz` or `.bz2`) → `PlanarLog`;
/// * a rosbag2 bag (its directory with `metadata.yaml`, or its `.mcap` file) → `PlanarLog` for
///   its LaserScan topic, else `SweepLog` for its PointCloud2 topic;
/// * a KITTI sequence directory, an NCLT session directory, an Ouster `.pcap` with its
///   metadata JSON beside it → `SweepLog`;
/// * an OctoMap occupancy tree `.bt` → `OctreeMap`, a scan graph `.graph` → `ScanGraph`;
/// * a PCD file, a KITTI velodyne `.bin` or an `x y z` text file → `Cloud`.
///
/// Raises `FileNotFoundError` for a missing path and `raypath.FormatError` (with `path`,
/// `line`, `byte`) for a malformed or unsupported file.
#[pyfunction]
pub fn open(py: Python<'_>, path: PathBuf) -> PyResult<PyObject> {
    let format = py
        .allow_threads(|| Format::detect(&path))
        .map_err(io_error)?;
    let name = format.name();
    match format {
        Format::Carmen => {
            let frames = py.allow_threads(|| read_planar(&path)).map_err(io_error)?;
            planar(py, path, name, frames)
        }
        Format::Rosbag2 => match py.allow_threads(|| read_planar(&path)) {
            Ok(frames) if !frames.is_empty() => planar(py, path, name, frames),
            planar_result => {
                let sweeps =
                    py.allow_threads(|| SweepSequence::open(&path, &SweepOptions::default()));
                match (sweeps, planar_result) {
                    (Ok(sequence), _) => sweep_log(py, sequence, name),
                    (Err(_), Err(e)) | (Err(e), Ok(_)) => Err(io_error(e)),
                }
            }
        },
        Format::OctomapBt => {
            let tree = py
                .allow_threads(|| raypath_io::octomap::read_bt(&path))
                .map_err(io_error)?;
            Ok(crate::octomap::OctreeMap { tree }
                .into_pyobject(py)?
                .into_any()
                .unbind())
        }
        Format::OctomapGraph => {
            let graph = py
                .allow_threads(|| raypath_io::octomap::read_graph(&path))
                .map_err(io_error)?;
            Ok(crate::octomap::ScanGraph { graph }
                .into_pyobject(py)?
                .into_any()
                .unbind())
        }
        Format::KittiSequence | Format::NcltSession | Format::OusterPcap => {
            let sequence = py
                .allow_threads(|| SweepSequence::open(&path, &SweepOptions::default()))
                .map_err(io_error)?;
            sweep_log(py, sequence, name)
        }
        _ => {
            let cloud = py
                .allow_threads(|| raypath_io::read_cloud(&path))
                .map_err(io_error)?;
            Ok(Cloud { cloud }.into_pyobject(py)?.into_any().unbind())
        }
    }
}

fn planar(
    py: Python<'_>,
    path: PathBuf,
    format: &'static str,
    frames: Vec<PlanarFrame>,
) -> PyResult<PyObject> {
    Ok(PlanarLog {
        path,
        format,
        frames: Arc::new(frames),
    }
    .into_pyobject(py)?
    .into_any()
    .unbind())
}

fn sweep_log(py: Python<'_>, sequence: SweepSequence, format: &'static str) -> PyResult<PyObject> {
    Ok(SweepLog { sequence, format }
        .into_pyobject(py)?
        .into_any()
        .unbind())
}
