//! The real 2-D data: corrected CARMEN logs (front-laser scans with their SLAM-corrected poses
//! as ground truth) and the raw Intel log for the speed test.

use std::path::Path;

use anyhow::{Context, Result};
use raypath_geometry::{Pose2, Scan2};
use raypath_io::sequence::{LaserChoice, PlanarFrame, PlanarOptions, read_planar};

/// The corrected logs with loops: name and path under `RAYPATH_DATA`.
pub const LOGS: [(&str, &str); 10] = [
    ("intel", "carmen/corrected/intel-corrected.log.gz"),
    (
        "freiburg-079",
        "carmen/corrected/freiburg-079-corrected.log.gz",
    ),
    ("csail", "carmen/corrected/csail-corrected.log.gz"),
    ("aces", "carmen/corrected/aces-corrected.log.gz"),
    (
        "freiburg-campus",
        "carmen/corrected/freiburg-campus-corrected.log.gz",
    ),
    (
        "infinite-corridor",
        "carmen/corrected/infinite-corridor-corrected.log.gz",
    ),
    ("fhw", "carmen/corrected/fhw-corrected.log.gz"),
    ("acapulco", "carmen/corrected/acapulco-corrected.log.gz"),
    ("belgioioso", "carmen/corrected/belgioioso-corrected.log.gz"),
    (
        "freiburg-101",
        "carmen/corrected/freiburg-101-corrected.log.gz",
    ),
];

/// The raw Intel log (13 631 scans) for the speed test.
pub const RAW_INTEL: &str = "carmen/raw/intel.clf.bz2";

/// One planar log: scans and reference places, in log order.
pub struct Log2 {
    /// The scans (sensor frame).
    pub scans: Vec<Scan2>,
    /// The reference pose of each scan.
    pub poses: Vec<Pose2>,
    /// Every `stride`-th scan of the log was kept.
    pub stride: usize,
}

/// The front-laser scans of a log.
fn front_laser(path: &Path) -> Result<Vec<PlanarFrame>> {
    let options = PlanarOptions {
        laser: LaserChoice::Front,
        ..PlanarOptions::default()
    };
    read_planar(path, &options).with_context(|| format!("reading {}", path.display()))
}

/// Reads a log, keeping every `stride`-th scan.
pub fn load(path: &Path, stride: usize) -> Result<Log2> {
    let (scans, poses) = front_laser(path)?
        .into_iter()
        .step_by(stride.max(1))
        .map(|f| (f.scan, f.world_from_laser))
        .unzip();
    Ok(Log2 {
        scans,
        poses,
        stride: stride.max(1),
    })
}

impl Log2 {
    /// Every `stride`-th scan of this log.
    pub fn subsample(self, stride: usize) -> Self {
        let stride = stride.max(1);
        Self {
            scans: self.scans.into_iter().step_by(stride).collect(),
            poses: self.poses.into_iter().step_by(stride).collect(),
            stride: self.stride * stride,
        }
    }
}

/// Reads up to `max` scans of a raw log (no reference poses needed: speed only).
pub fn load_scans(path: &Path, max: usize) -> Result<Vec<Scan2>> {
    let mut all = front_laser(path)?;
    all.truncate(max);
    Ok(all.into_iter().map(|f| f.scan).collect())
}
