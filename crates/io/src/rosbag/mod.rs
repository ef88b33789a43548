//! rosbag2 recordings with MCAP storage (stub: filled in by the MCAP reader).

use std::path::Path;

use crate::error::{Error, Result};
use crate::sequence::{PlanarSource, SweepSequence, Topics};

/// True when `path` is a rosbag2 recording: a directory with `metadata.yaml`, or a file that
/// starts with the MCAP magic.
pub fn is_bag(path: &Path) -> Result<bool> {
    if path.is_dir() {
        return Ok(path.join("metadata.yaml").is_file());
    }
    Ok(path.extension().is_some_and(|e| e == "mcap"))
}

/// The laser scans of a bag.
pub fn open_planar(path: &Path, _topics: &Topics) -> Result<Box<dyn PlanarSource>> {
    Err(Error::UnknownFormat {
        path: path.to_path_buf(),
        reason: "rosbag2 reading is not implemented yet".into(),
    })
}

/// The point-cloud sweeps of a bag.
pub fn open_sweeps(path: &Path, _topics: &Topics) -> Result<SweepSequence> {
    Err(Error::UnknownFormat {
        path: path.to_path_buf(),
        reason: "rosbag2 reading is not implemented yet".into(),
    })
}
