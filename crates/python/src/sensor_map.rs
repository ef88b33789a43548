//! `raypath.sensor_models`: the per-cell ray statistics maps of the sensor models (decay
//! rate, reflection, log-odds; Schaefer 2020, ch. 7), built from a planar log at its poses
//! or read from a `raypath map` file.

use std::path::PathBuf;

use numpy::PyArray2;
use pyo3::prelude::*;
use raypath_geometry::{Aabb2, Grid2, Pose2};
use raypath_io::sequence::PlanarFrame;
use raypath_sensor_models::export::{MapFile, MapKind, MapPicture, StoredStats, picture_values};
use raypath_sensor_models::{CellStats, DenseStats2, MappingConfig};

use crate::arrays::{floats_as, matrix};
use crate::errors::{input_error, value_error};
use crate::io::PlanarLog;

/// Largest map `build` allocates, cells (as `raypath map`).
const MAX_CELLS: usize = 200_000_000;

/// A 2-D sensor-model map: per cell the hits `H`, misses `M` and path length `R` of the rays
/// that entered it, with the model it is meant for. The decay-rate model reads `λ = H / R`,
/// the reflection model `μ = H / (H + M)`.
#[pyclass(module = "raypath.sensor_models", name = "SensorMap", frozen)]
pub struct SensorMap {
    pub(crate) file: MapFile,
}

impl SensorMap {
    /// The planar statistics (every `SensorMap` holds 2-D statistics).
    pub(crate) fn stats(&self) -> &DenseStats2 {
        match &self.file.stats {
            StoredStats::Planar(stats) => stats,
            // `load` and `build` only make planar maps.
            StoredStats::Spatial(_) => unreachable!("SensorMap holds planar statistics"),
        }
    }

    fn per_cell<'py>(
        &self,
        py: Python<'py>,
        value: impl Fn(&CellStats) -> f64,
    ) -> Bound<'py, PyArray2<f64>> {
        let stats = self.stats();
        let [w, h] = stats.grid().dims();
        matrix(py, stats.cells().iter().map(value).collect(), h, w)
    }
}

fn kind_name(kind: MapKind) -> &'static str {
    match kind {
        MapKind::Statistics => "statistics",
        MapKind::DecayRate => "decay-rate",
        MapKind::Reflection => "reflection",
        MapKind::LogOdds => "log-odds",
        MapKind::LikelihoodField => "likelihood-field",
    }
}

fn picture_of(name: Option<&str>, kind: MapKind) -> PyResult<MapPicture> {
    Ok(match name {
        None => match kind {
            MapKind::Reflection => MapPicture::Reflection,
            MapKind::LogOdds | MapKind::LikelihoodField => MapPicture::Occupancy,
            MapKind::Statistics | MapKind::DecayRate => MapPicture::DecayRate,
        },
        Some("reflection") => MapPicture::Reflection,
        Some("decay-rate") => MapPicture::DecayRate,
        Some("occupancy" | "log-odds") => MapPicture::Occupancy,
        Some(other) => {
            return Err(value_error(
                "picture",
                format!("expected \"reflection\", \"decay-rate\" or \"occupancy\", got {other:?}"),
            ));
        }
    })
}

#[pymethods]
impl SensorMap {
    /// The map as probabilities, `(H, W)` float64, NaN where no ray entered (row 0 is the
    /// lowest y). `picture`: `"reflection"` (`μ = H / (H + M)`), `"decay-rate"` (`1 − e^{−λ c}`
    /// over one cell edge `c`) or `"occupancy"` (log-odds); default the map's model — the
    /// values of `raypath map`'s pictures.
    #[pyo3(signature = (picture = None))]
    fn array<'py>(
        &self,
        py: Python<'py>,
        picture: Option<&str>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let picture = picture_of(picture, self.file.kind)?;
        let stats = self.stats();
        let [w, h] = stats.grid().dims();
        let values = picture_values(stats, picture)
            .into_iter()
            .map(|v| v.unwrap_or(f64::NAN))
            .collect();
        Ok(matrix(py, values, h, w))
    }

    /// Hits `H` per cell, `(H, W)` float64.
    #[getter]
    fn hits<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.per_cell(py, |c| f64::from(c.hits()))
    }

    /// Misses `M` per cell, `(H, W)` float64.
    #[getter]
    fn misses<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.per_cell(py, |c| f64::from(c.misses()))
    }

    /// Path length `R` of the rays inside each cell, metres, `(H, W)` float64.
    #[getter]
    fn path_length<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.per_cell(py, CellStats::path_length_m)
    }

    /// Cell edge, metres.
    #[getter]
    fn resolution(&self) -> f64 {
        self.stats().grid().cell_size()
    }

    /// The lower corner `(x, y)` of cell `[0, 0]`, metres.
    #[getter]
    fn origin(&self) -> (f64, f64) {
        let o = self.stats().grid().origin();
        (o.x, o.y)
    }

    /// `(H, W)`.
    #[getter]
    fn shape(&self) -> (usize, usize) {
        let [w, h] = self.stats().grid().dims();
        (h, w)
    }

    /// The model the map is for: `"decay-rate"`, `"reflection"`, `"log-odds"`, ….
    #[getter]
    fn model(&self) -> &'static str {
        kind_name(self.file.kind)
    }

    /// True for the full-posterior variant of the model.
    #[getter]
    fn posterior(&self) -> bool {
        self.file.posterior
    }

    /// `(min_range, max_range)` of the mapping, metres.
    #[getter]
    fn range(&self) -> (f64, f64) {
        let r = self.file.mapping.range;
        (r.min_range_m, r.max_range_m)
    }

    /// Writes the binary map `raypath localize --map` reads (`.rpmap`).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.allow_threads(|| self.file.write_file(&path))
            .map_err(|e| input_error(format!("{}: {e}", path.display())))
    }

    fn __repr__(&self) -> String {
        let [w, h] = self.stats().grid().dims();
        format!(
            "SensorMap({}, {h} × {w} cells of {} m)",
            kind_name(self.file.kind),
            self.stats().grid().cell_size()
        )
    }
}

/// Reads a 2-D map written by `raypath map` (`PREFIX.rpmap`) or `SensorMap.save`.
#[pyfunction]
pub fn load(py: Python<'_>, path: PathBuf) -> PyResult<SensorMap> {
    if !path.exists() {
        return Err(pyo3::exceptions::PyFileNotFoundError::new_err(format!(
            "{}: no such file",
            path.display()
        )));
    }
    let file = py
        .allow_threads(|| MapFile::read_file(&path))
        .map_err(|e| crate::errors::format_error(&path, e))?;
    if !matches!(file.stats, StoredStats::Planar(_)) {
        return Err(input_error(format!(
            "{}: a 3-D map; raypath.sensor_models handles 2-D maps",
            path.display()
        )));
    }
    Ok(SensorMap { file })
}

/// The poses the map is built at: `poses` `(N, 3)` when given, else the log's reference
/// poses (a bag's), else its logged laser poses (a corrected CARMEN log's).
fn poses_of(
    frames: &[PlanarFrame],
    poses: Option<&Bound<'_, PyAny>>,
) -> PyResult<Vec<Option<Pose2>>> {
    let Some(poses) = poses.filter(|p| !p.is_none()) else {
        return Ok(if frames.iter().any(|f| f.reference.is_some()) {
            frames.iter().map(|f| f.reference).collect()
        } else {
            frames.iter().map(|f| Some(f.world_from_laser)).collect()
        });
    };
    let expected = format!("an array of shape ({}, 3)", frames.len());
    let f = floats_as(poses, "poses", &expected, true)?;
    if f.shape != [frames.len(), 3] {
        return Err(value_error(
            "poses",
            format!(
                "expected {expected} (one laser pose per scan), got shape {:?}",
                f.shape
            ),
        ));
    }
    f.values
        .chunks_exact(3)
        .enumerate()
        .map(|(i, p)| {
            if p.iter().all(|v| v.is_finite()) {
                Ok(Some(Pose2::new(p[0], p[1], p[2])))
            } else {
                Err(value_error("poses", format!("row {i} is not finite")))
            }
        })
        .collect()
}

/// Builds a 2-D sensor-model map from a planar log, as `raypath map LOG --model MODEL
/// --resolution R`: every ray of every scan (every `ray_step`-th) traced through a grid
/// covering the laser positions and the returns within `max_range`, plus one cell.
///
/// `log`: a `PlanarLog` (a corrected CARMEN log: its laser poses are the map poses; a bag:
/// its reference poses). `poses`: `(N, 3)` laser poses `x, y, theta` to use instead.
/// `model`: `"decay-rate"`, `"reflection"` or `"log-odds"` (what `array()` shows and the
/// localizer uses). `max_range`: returns at or beyond it and no-returns are traced to it as
/// misses (unless `skip_no_returns`). The GIL is released while rays are traced.
#[pyfunction]
#[pyo3(signature = (log, poses = None, *, model = "reflection", resolution = 0.05, max_range = 80.0, min_range = 0.0, ray_step = 1, skip_no_returns = false, posterior = false))]
#[allow(clippy::too_many_arguments)]
pub fn build(
    py: Python<'_>,
    log: &Bound<'_, PlanarLog>,
    poses: Option<&Bound<'_, PyAny>>,
    model: &str,
    resolution: f64,
    max_range: f64,
    min_range: f64,
    ray_step: usize,
    skip_no_returns: bool,
    posterior: bool,
) -> PyResult<SensorMap> {
    let kind = match model {
        "decay-rate" => MapKind::DecayRate,
        "reflection" => MapKind::Reflection,
        "log-odds" => MapKind::LogOdds,
        other => {
            return Err(value_error(
                "model",
                format!("expected \"decay-rate\", \"reflection\" or \"log-odds\", got {other:?}"),
            ));
        }
    };
    if posterior && kind == MapKind::LogOdds {
        return Err(value_error(
            "posterior",
            "not defined for the log-odds model (only decay-rate and reflection)",
        ));
    }
    if !(resolution.is_finite() && resolution > 0.0) {
        return Err(value_error(
            "resolution",
            format!("must be a positive number of metres, got {resolution}"),
        ));
    }
    if ray_step == 0 {
        return Err(value_error("ray_step", "must be at least 1"));
    }
    let mut config =
        MappingConfig::with_range(min_range, max_range).map_err(|e| value_error("max_range", e))?;
    config.include_no_returns = !skip_no_returns;
    let log = log.get();
    let frames = &log.frames;
    if frames.is_empty() {
        return Err(input_error(format!(
            "{}: no laser scans",
            log.path.display()
        )));
    }
    let poses = poses_of(frames, poses)?;
    let stats = py
        .allow_threads(|| map_scans(frames, &poses, resolution, ray_step, &config))
        .map_err(|e| input_error(format!("{}: {e}", log.path.display())))?;
    Ok(SensorMap {
        file: MapFile {
            kind,
            posterior,
            mapping: config,
            stats: StoredStats::Planar(stats),
        },
    })
}

/// The statistics of the scans at their poses (scans without a pose are left out), on a grid
/// covering the poses and the returns below the maximum range.
fn map_scans(
    frames: &[PlanarFrame],
    poses: &[Option<Pose2>],
    resolution: f64,
    step: usize,
    config: &MappingConfig,
) -> Result<DenseStats2, String> {
    let max_range = config.range.max_range_m;
    let mut bounds = Aabb2::empty();
    let mut scans = Vec::with_capacity(frames.len());
    for (frame, pose) in frames.iter().zip(poses) {
        let Some(pose) = *pose else { continue };
        if !pose.is_finite() {
            return Err("a laser pose is not finite".into());
        }
        bounds.extend(&nalgebra::Point2::new(pose.x(), pose.y()));
        for ray in frame.scan.rays(pose) {
            if let Some(t) = ray.range.hit().filter(|&t| t < max_range) {
                bounds.extend(&ray.at(t));
            }
        }
        scans.push((pose, &frame.scan));
    }
    let grid = Grid2::covering(&bounds, resolution).map_err(|e| e.to_string())?;
    if grid.num_cells() > MAX_CELLS {
        return Err(format!(
            "the map would have {} cells of {resolution} m (at most {MAX_CELLS})",
            grid.num_cells()
        ));
    }
    let mut stats = DenseStats2::planar(grid);
    stats.insert_par(&scans, config, |(pose, scan), sink| {
        for ray in scan.rays(*pose).step_by(step) {
            sink(&ray);
        }
    });
    Ok(stats)
}
