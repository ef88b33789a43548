//! `raypath.poles.extract`: pole landmarks from a registered 3-D scan.

use std::path::PathBuf;

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use raypath_geometry::Pose3;
use raypath_io::sequence::{SweepOptions, SweepSequence};
use raypath_poles::{
    Drive, DriveFormat, Pole, Preset, SweepTiming, extract_poles, local_maps, reference_map,
};

use crate::arrays::{matrix, point_cloud, pose3, vec1};
use crate::errors::{input_error, io_error, value_error};
use crate::io::SweepLog;

/// Poles found by `raypath.poles.extract`, in the world frame (metres).
#[pyclass(module = "raypath.poles", name = "Poles", frozen)]
pub struct Poles {
    pub(crate) poles: Vec<Pole>,
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

pub(crate) fn preset_of(name: &str) -> PyResult<Preset> {
    match name {
        "kitti" => Ok(Preset::kitti()),
        "nclt" => Ok(Preset::nclt()),
        other => Err(value_error(
            "preset",
            format!("expected \"kitti\" or \"nclt\", got {other:?}"),
        )),
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
    let preset = preset_of(preset)?;
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

/// The sweep timing of `sweep_timing` for `drive` (`"auto"`: KITTI's de-skewed sweeps for a
/// KITTI sequence that is not a `raypath simulate` set, as `raypath poles`).
fn sweep_timing(drive: &Drive, path: &std::path::Path, name: &str) -> PyResult<bool> {
    Ok(match name {
        "kitti" => true,
        "origin" => false,
        "auto" => {
            let simulated = path
                .ancestors()
                .skip(1)
                .take(2)
                .any(|dir| dir.join("set.json").is_file());
            drive.format() == DriveFormat::Kitti && !simulated
        }
        other => {
            return Err(value_error(
                "sweep_timing",
                format!("expected \"auto\", \"kitti\" or \"origin\", got {other:?}"),
            ));
        }
    })
}

/// A pole map of a whole drive, as `raypath poles map SEQUENCE`: local maps along the
/// reference trajectory (the odometry when there is none), their poles merged into one
/// reference map (world frame).
///
/// `sequence`: a `SweepLog` (KITTI sequence, NCLT session, bag) or its path. `preset`:
/// `"kitti"`, `"nclt"`, or None for the sequence's format. `sweep_timing`: `"auto"`,
/// `"kitti"` (rays start where the sensor was when it fired) or `"origin"`. `start`,
/// `scans`: the scans used (`--from`, `--max-scans`). The GIL is released while it maps.
#[pyfunction(name = "map")]
#[pyo3(signature = (sequence, *, preset = None, sweep_timing = "auto", start = 0, scans = None))]
pub fn pole_map(
    py: Python<'_>,
    sequence: &Bound<'_, PyAny>,
    preset: Option<&str>,
    sweep_timing: &str,
    start: usize,
    scans: Option<usize>,
) -> PyResult<Poles> {
    let path: PathBuf = match sequence.downcast::<SweepLog>() {
        Ok(log) => log.get().path_buf(),
        Err(_) => sequence.extract().map_err(|_| {
            value_error(
                "sequence",
                "expected a raypath.SweepLog or the path of a sequence",
            )
        })?,
    };
    let sweeps = py
        .allow_threads(|| SweepSequence::open(&path, &SweepOptions::default()))
        .map_err(io_error)?;
    let mut drive = Drive::new(sweeps).map_err(input_error)?;
    if self::sweep_timing(&drive, &path, sweep_timing)? {
        drive.sweep_timing = Some(SweepTiming::kitti());
    }
    let preset = match preset {
        Some(name) => preset_of(name)?,
        None => match drive.format() {
            DriveFormat::Kitti => Preset::kitti(),
            DriveFormat::Nclt => Preset::nclt(),
        },
    };
    if start >= drive.len() {
        return Err(value_error(
            "start",
            format!("{start} but the sequence has {} scans", drive.len()),
        ));
    }
    let end = scans.map_or(drive.len(), |n| (start + n).min(drive.len()));
    let track: Vec<Pose3> = drive
        .sweeps
        .reference
        .clone()
        .unwrap_or_else(|| drive.odometry().to_vec());
    let poles = py
        .allow_threads(|| {
            local_maps(&drive, &track, start..end, &preset, |_, _| {})
                .map(|(maps, _)| reference_map(&maps, &preset))
        })
        .map_err(input_error)?;
    Ok(Poles { poles })
}
