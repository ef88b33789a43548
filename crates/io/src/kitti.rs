//! KITTI (being written).

use std::path::Path;

use crate::{Error, Format, Result, Summary};

/// Summarizes a KITTI file or directory.
pub fn summarize(path: &Path, _format: Format) -> Result<Summary> {
    Err(not_yet(path))
}

fn not_yet(path: &Path) -> Error {
    Error::UnknownFormat {
        path: path.to_path_buf(),
        reason: "reader not implemented yet".into(),
    }
}
