//! A typed report of polyline extraction over a log: the JSON document of
//! `raypath polylines --json` (the keys are a contract).

use serde::Serialize;

use crate::{Method, PolylineConfig, Polylines};

/// The polylines of one scan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ScanPolylines {
    /// The scan's index in the log.
    pub index: usize,
    /// Each polyline's vertices `[x, y]`, laser frame.
    pub polylines: Vec<Vec<[f64; 2]>>,
    /// RMS distance of the returns from the polylines, metres.
    pub rmse: f64,
    /// The objective value.
    pub f: f64,
}

impl ScanPolylines {
    /// The report of `map`, extracted from scan `index`.
    pub fn new(index: usize, map: &Polylines, rmse: f64, f: f64) -> Self {
        Self {
            index,
            polylines: map
                .lines
                .iter()
                .map(|l| l.vertices.iter().map(|v| [v.x, v.y]).collect())
                .collect(),
            rmse,
            f,
        }
    }
}

/// Polylines of a log's scans with the settings that made them.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PolylinesReport {
    /// Every scan.
    pub scans: Vec<ScanPolylines>,
    /// The log's name.
    pub log: String,
    /// The method ([`Method::name`]).
    pub method: &'static str,
    /// The PLE+ optimiser (`None` for other methods).
    pub optimizer: Option<&'static str>,
    /// [`PolylineConfig::max_vertices`].
    pub max_vertices: usize,
    /// [`PolylineConfig::max_edge_m`].
    pub max_edge_m: f64,
    /// [`PolylineConfig::removed_residual_m`].
    pub removed_residual_m: f64,
    /// Per scan, per polyline: whether it is closed.
    pub closed: Vec<Vec<bool>>,
}

impl PolylinesReport {
    /// The report of the scans of the log `log`: per scan its index, polylines, RMSE and
    /// objective value.
    pub fn new(
        log: String,
        config: &PolylineConfig,
        extracted: &[(usize, &Polylines, f64, f64)],
    ) -> Self {
        Self {
            scans: extracted
                .iter()
                .map(|&(index, map, rmse, f)| ScanPolylines::new(index, map, rmse, f))
                .collect(),
            log,
            method: config.method.name(),
            optimizer: (config.method == Method::PlePlus).then(|| config.optimizer.name()),
            max_vertices: config.max_vertices,
            max_edge_m: config.max_edge_m,
            removed_residual_m: config.removed_residual_m,
            closed: extracted
                .iter()
                .map(|(_, m, _, _)| m.lines.iter().map(|l| l.closed).collect())
                .collect(),
        }
    }
}
