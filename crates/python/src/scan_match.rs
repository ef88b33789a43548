//! `raypath.scan_match`: Hector-style multi-resolution scan-to-map matching of planar scans
//! (the matcher of `raypath scan-match`), step by step or over a whole log.

use std::sync::Arc;

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use raypath_geometry::Pose2;
use raypath_io::sequence::PlanarFrame;
use raypath_reflectivity::benchmark::run_matcher;
use raypath_reflectivity::{
    MapConfig, MatcherConfig, PointFilter, ScanMatcher as Matcher, ScanPoints,
};

use crate::arrays::{matrix, pose_vector, pose2, poses2, scan2};
use crate::errors::{input_error, value_error};
use crate::io::PlanarLog;

/// A pose `(3,)` and its covariance `(3, 3)`.
type PoseAndCovariance<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>);

/// The matcher and point filter of the arguments (`raypath scan-match`'s flags and defaults).
fn settings(
    resolution: f64,
    levels: usize,
    size: f64,
    max_range: f64,
) -> PyResult<(MatcherConfig, PointFilter)> {
    if !(max_range.is_finite() && max_range > 0.0) {
        return Err(value_error(
            "max_range",
            format!("must be a positive number of metres, got {max_range}"),
        ));
    }
    let config = MatcherConfig {
        map: MapConfig {
            finest_resolution_m: resolution,
            levels,
            size_m: size,
            ..MapConfig::default()
        },
        ..MatcherConfig::default()
    };
    config
        .validate()
        .map_err(|e| value_error("ScanMatcher", e))?;
    let filter = PointFilter {
        max_range_m: max_range,
        ..PointFilter::default()
    };
    Ok((config, filter))
}

/// Hector-style scan-to-map matching (Kohlbrecher et al. 2011; Khan 2017, ch. 3) with the
/// occupancy residual: each scan is matched coarse to fine against the multi-resolution map
/// built so far, and the map is updated after enough motion. The map frame is the first
/// scan's.
///
/// `resolution`: finest cell, metres. `levels`: map levels (each coarser level doubles the
/// cell). `size`: side of the mapped square, metres, centred on the first scan.
/// `max_range`: readings at or above it are not used, metres.
#[pyclass(module = "raypath.scan_match", name = "ScanMatcher")]
pub struct ScanMatcher {
    matcher: Matcher,
    filter: PointFilter,
    points: ScanPoints,
}

#[pymethods]
impl ScanMatcher {
    #[new]
    #[pyo3(signature = (resolution = 0.05, levels = 3, size = 160.0, max_range = 30.0))]
    fn new(resolution: f64, levels: usize, size: f64, max_range: f64) -> PyResult<Self> {
        let (config, filter) = settings(resolution, levels, size, max_range)?;
        let matcher = Matcher::new(config).map_err(|e| value_error("ScanMatcher", e))?;
        Ok(Self {
            matcher,
            filter,
            points: ScanPoints::new(),
        })
    }

    /// Matches one scan: `ranges`, `angles` `(B,)` (angles evenly spaced and increasing,
    /// radians in the laser frame). `odometry_delta`: the odometry motion `(x, y, theta)`
    /// since the previous scan (`previous⁻¹ · current`), the initial guess; None starts from
    /// the previous estimate. The first scan only builds the map. Returns
    /// `(pose, covariance)`: the laser pose `(3,)` in the map frame and the `(3, 3)`
    /// covariance over `x, y, theta` (infinite diagonal when unconstrained).
    #[pyo3(signature = (ranges, angles, odometry_delta = None))]
    fn match_scan<'py>(
        &mut self,
        py: Python<'py>,
        ranges: &Bound<'py, PyAny>,
        angles: &Bound<'py, PyAny>,
        odometry_delta: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<PoseAndCovariance<'py>> {
        let scan = scan2(ranges, angles, None)?;
        let delta = match odometry_delta.filter(|d| !d.is_none()) {
            Some(d) => Some(pose2(d, "odometry_delta")?),
            None => None,
        };
        let (matcher, points, filter) = (&mut self.matcher, &mut self.points, &self.filter);
        let result = py.allow_threads(|| {
            points.fill_from_scan(&scan, filter, None);
            matcher.process(points, delta)
        });
        let covariance = result.covariance.transpose().iter().copied().collect();
        Ok((
            pose_vector(py, result.world_from_sensor),
            matrix(py, covariance, 3, 3),
        ))
    }

    /// The current laser pose `(x, y, theta)`, `(3,)`.
    #[getter]
    fn pose<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        pose_vector(py, self.matcher.pose())
    }

    /// The finest map level as occupancy probabilities, `(H, W)` float64 (0.5 = unknown;
    /// row 0 is the lowest y).
    #[getter]
    fn map<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        match self.matcher.map().levels().first() {
            Some(level) => {
                let (w, h) = (level.width(), level.height());
                let mut flat = Vec::with_capacity(w * h);
                for j in 0..h {
                    for i in 0..w {
                        flat.push(raypath_reflectivity::probability(level.log_odds(i, j)));
                    }
                }
                matrix(py, flat, h, w)
            }
            None => matrix(py, Vec::new(), 0, 0),
        }
    }

    /// The lower corner `(x, y)` of the finest level's cell `[0, 0]` and its cell edge,
    /// metres: `(x0, y0, resolution)`.
    #[getter]
    fn map_origin(&self) -> (f64, f64, f64) {
        match self.matcher.map().levels().first() {
            Some(level) => {
                let o = level.origin();
                (o[0], o[1], level.resolution_m())
            }
            None => (0.0, 0.0, 0.0),
        }
    }

    /// Map updates so far.
    #[getter]
    fn updates(&self) -> u32 {
        self.matcher.map().updates()
    }

    fn __repr__(&self) -> String {
        let p = self.matcher.pose();
        format!(
            "ScanMatcher(pose=({:.3}, {:.3}, {:.3}), {} map updates)",
            p.x(),
            p.y(),
            p.theta(),
            self.matcher.map().updates()
        )
    }
}

/// Matches every scan of a planar log in order, as `raypath scan-match LOG` (occupancy
/// residual): returns the laser poses `(N, 3)` in the map frame (the first scan's).
///
/// `odometry=True` uses the logged odometry as the initial guess of each match
/// (`--odometry`). `scans`: only the first N scans (`--scans`). The other arguments are
/// those of `ScanMatcher`. The GIL is released while it runs.
#[pyfunction]
#[pyo3(signature = (log, *, resolution = 0.05, levels = 3, size = 160.0, max_range = 30.0, odometry = false, scans = None))]
#[allow(clippy::too_many_arguments)]
pub fn match_log<'py>(
    py: Python<'py>,
    log: &Bound<'py, PlanarLog>,
    resolution: f64,
    levels: usize,
    size: f64,
    max_range: f64,
    odometry: bool,
    scans: Option<usize>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (config, filter) = settings(resolution, levels, size, max_range)?;
    let frames: Arc<Vec<PlanarFrame>> = Arc::clone(&log.get().frames);
    let count = scans.map_or(frames.len(), |n| n.max(1).min(frames.len()));
    if count == 0 {
        return Err(input_error(format!(
            "{}: no laser scans",
            log.get().path.display()
        )));
    }
    let poses: Vec<Pose2> = py
        .allow_threads(|| run_matcher(&frames[..count], config, &filter, None, odometry))
        .map_err(input_error)?
        .1
        .iter()
        .map(|r| r.world_from_sensor)
        .collect();
    Ok(poses2(py, poses.into_iter()))
}
