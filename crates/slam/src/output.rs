//! What a SLAM run returns: the optimised pose of every scan, the pose graph, the submaps and
//! the loop closures, with writers for TUM trajectories and corrected CARMEN logs.

use std::path::Path;

use raypath_geometry::Pose2;
use raypath_io::sequence::PlanarFrame;

use crate::error::{Result, SlamError};
use crate::graph::PoseGraph;
use crate::loops::{LoopClosure, LoopSource, LoopStats};
use crate::report::SlamFiles;
use crate::submap::Submap;

/// One processed scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanPose {
    /// Time of the scan, seconds: the sensor's time stamp when the scan came through
    /// [`crate::Slam::process`] (the CARMEN ipc time stamp, a bag's header stamp; see
    /// [`PlanarFrame::sensor_stamp_secs`]).
    pub stamp_secs: f64,
    /// The front-end's pose of the scan in its local (never corrected) frame.
    pub local: Pose2,
    /// The latest node at or before this scan.
    pub node: usize,
    /// Whether this scan is that node.
    pub is_node: bool,
}

/// Timings and counters of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct SlamStats {
    /// Time in scan matching and submap insertion, seconds.
    pub frontend_seconds: f64,
    /// Time in loop search and verification, seconds.
    pub loop_seconds: f64,
    /// Time in pose-graph optimisation, seconds.
    pub optimise_seconds: f64,
    /// Time in the final polishing ([`crate::SlamConfig::polish`]), seconds.
    pub polish_seconds: f64,
    /// ICP edges of the final polishing.
    pub polish_edges: usize,
    /// Number of optimisations.
    pub optimisations: usize,
    /// Final χ² of the last optimisation.
    pub final_chi2: f64,
    /// Loop-search counters.
    pub loops: LoopStats,
    /// Counters of the front-end's guards.
    pub tracking: crate::guard::TrackingStats,
    /// Counters of the loop consistency test.
    pub consistency: crate::consistency::ConsistencyStats,
}

/// The result of [`crate::Slam::finish`].
#[derive(Debug)]
pub struct SlamOutput {
    /// Every processed scan, in input order.
    pub scans: Vec<ScanPose>,
    /// The optimised `world_from_sensor` of every scan (index-aligned with `scans`); the world
    /// frame is the first scan's sensor frame.
    pub world_from_sensor: Vec<Pose2>,
    /// The optimised node poses (`world_from_sensor` of the node scans).
    pub nodes: Vec<Pose2>,
    /// The scan index of each node.
    pub node_scan: Vec<usize>,
    /// The finished submaps, in the order they were finished.
    pub submaps: Vec<Submap>,
    /// Accepted loop closures (robust weight at the final optimisation at least
    /// [`crate::SlamConfig::reject_weight`]).
    pub loop_closures: Vec<LoopClosure>,
    /// Loop closures whose robust weight ended below [`crate::SlamConfig::reject_weight`];
    /// they were switched off before the last optimisation.
    pub rejected_loop_closures: Vec<LoopClosure>,
    /// The final pose graph.
    pub graph: PoseGraph,
    /// Timings and counters.
    pub stats: SlamStats,
}

impl SlamOutput {
    /// The trajectory as TUM lines (`t x y z qx qy qz qw`, z = 0, a yaw quaternion), each
    /// pose at its scan's own time stamp ([`ScanPose::stamp_secs`]: the sensor's time), so
    /// `evo` and the SLAM benchmark's relation files join on it.
    pub fn tum(&self) -> String {
        raypath_io::tum::planar_tum_lines(
            self.scans
                .iter()
                .zip(&self.world_from_sensor)
                .map(|(s, p)| (s.stamp_secs, *p)),
        )
    }

    /// Writes the TUM trajectory to `path`.
    pub fn write_tum(&self, path: &Path) -> Result<()> {
        std::fs::write(path, self.tum())
            .map_err(|e| SlamError::BadInput(format!("{}: cannot write: {e}", path.display())))
    }

    /// `frames` (the processed frames, in order) with the optimised laser poses: world and
    /// laser poses replaced, the robot pose moved with the laser (its mounting kept). Written
    /// with [`raypath_io::convert::write_carmen`] they are a corrected log.
    pub fn corrected_frames(&self, frames: &[PlanarFrame]) -> Result<Vec<PlanarFrame>> {
        if frames.len() != self.world_from_sensor.len() {
            return Err(SlamError::BadInput(format!(
                "{} frames given for a run of {} scans",
                frames.len(),
                self.world_from_sensor.len()
            )));
        }
        Ok(frames
            .iter()
            .zip(&self.world_from_sensor)
            .map(|(f, &pose)| {
                let robot_from_laser = f.robot_from_laser();
                PlanarFrame {
                    world_from_laser: pose,
                    world_from_robot: pose * robot_from_laser.inverse(),
                    ..f.clone()
                }
            })
            .collect())
    }

    /// Writes `frames` with the optimised poses as a CARMEN corrected log.
    pub fn write_corrected_log(&self, frames: &[PlanarFrame], path: &Path) -> Result<()> {
        raypath_io::convert::write_carmen(path, &self.corrected_frames(frames)?)?;
        Ok(())
    }

    /// The accepted loop closures as CSV, one per line under the header
    /// `scan,anchor_scan,node,submap,x,y,theta,score,source` (`x y theta`: the scan's sensor
    /// in the submap's frame; `source`: `nearby`, `place-recognition` or `global`).
    pub fn loop_closures_csv(&self) -> String {
        let mut text = String::from("scan,anchor_scan,node,submap,x,y,theta,score,source\n");
        for c in &self.loop_closures {
            let scan = self.node_scan.get(c.node).copied().unwrap_or(usize::MAX);
            let anchor = self.node_scan.get(c.anchor).copied().unwrap_or(usize::MAX);
            let p = c.submap_from_sensor;
            let source = match c.source {
                LoopSource::Nearby => "nearby",
                LoopSource::PlaceRecognition => "place-recognition",
                LoopSource::Global => "global",
            };
            text.push_str(&format!(
                "{scan},{anchor},{},{},{},{},{},{},{source}\n",
                c.node,
                c.submap,
                p.x(),
                p.y(),
                p.theta(),
                c.score
            ));
        }
        text
    }

    /// Writes the run's files into the directory `dir` (which must exist): `trajectory.txt`
    /// ([`Self::tum`]), `corrected.log` ([`Self::write_corrected_log`] of `frames`) and
    /// `loop_closures.csv` ([`Self::loop_closures_csv`]).
    pub fn write_files(&self, dir: &Path, frames: &[PlanarFrame]) -> Result<SlamFiles> {
        let trajectory = dir.join("trajectory.txt");
        self.write_tum(&trajectory)?;
        let corrected_log = dir.join("corrected.log");
        self.write_corrected_log(frames, &corrected_log)?;
        let loop_closures = dir.join("loop_closures.csv");
        std::fs::write(&loop_closures, self.loop_closures_csv()).map_err(|e| {
            SlamError::BadInput(format!("{}: cannot write: {e}", loop_closures.display()))
        })?;
        Ok(SlamFiles {
            trajectory,
            corrected_log,
            loop_closures,
        })
    }
}
