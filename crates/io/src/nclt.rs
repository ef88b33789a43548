//! NCLT (being written).

use std::path::Path;

use crate::{Error, Format, Result, Summary};

/// Magic number of a `velodyne_hits.bin` packet header.
pub const HITS_MAGIC: u64 = 0xad9c_ad9c_ad9c_ad9c;
/// Summarizes an NCLT file or directory.
pub fn summarize(path: &Path, _format: Format) -> Result<Summary> {
    Err(not_yet(path))
}

fn not_yet(path: &Path) -> Error {
    Error::UnknownFormat {
        path: path.to_path_buf(),
        reason: "reader not implemented yet".into(),
    }
}
