//! What a run of `raypath slam` reports: [`SlamReport`] (its JSON keys are a contract of
//! `raypath slam --json`).

use std::path::PathBuf;

use raypath_sensor_models::export::MapReport;
use serde::Serialize;

use crate::benchmark::{ReferenceScore, RelationFileScore};
use crate::{SlamOutput, SlamStats};

/// The files of [`SlamOutput::write_files`].
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct SlamFiles {
    /// The TUM trajectory.
    pub trajectory: PathBuf,
    /// The corrected CARMEN log.
    pub corrected_log: PathBuf,
    /// One accepted loop closure per line ([`SlamOutput::loop_closures_csv`]).
    pub loop_closures: PathBuf,
}

/// A run, its files and map, and its scores where a reference was given.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SlamReport {
    /// Scans processed.
    pub scans: usize,
    /// Pose-graph nodes.
    pub nodes: usize,
    /// Finished submaps.
    pub submaps: usize,
    /// Accepted loop closures.
    pub loop_closures: usize,
    /// Rejected loop closures.
    pub rejected_loop_closures: usize,
    /// Time of the run (processing and finishing), seconds.
    pub seconds: f64,
    /// Scans per second of the run.
    pub scans_per_second: f64,
    /// Timings and counters.
    pub timing: SlamStats,
    /// The files written.
    pub outputs: SlamFiles,
    /// The map rebuilt from the optimised poses ([`crate::rebuild_map`]).
    pub map: MapReport,
    /// The scores against a reference trajectory (its keys at the top level).
    #[serde(flatten)]
    pub reference: Option<ReferenceScore>,
    /// The score against the benchmark's relation file.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub relations_file: Option<RelationFileScore>,
}

impl SlamReport {
    /// The report of `out`, which took `seconds`, written to `outputs` with its `map`.
    pub fn new(out: &SlamOutput, seconds: f64, outputs: SlamFiles, map: MapReport) -> Self {
        Self {
            scans: out.scans.len(),
            nodes: out.nodes.len(),
            submaps: out.submaps.len(),
            loop_closures: out.loop_closures.len(),
            rejected_loop_closures: out.rejected_loop_closures.len(),
            seconds,
            scans_per_second: out.scans.len() as f64 / seconds.max(1e-9),
            timing: out.stats,
            outputs,
            map,
            reference: None,
            relations_file: None,
        }
    }
}
