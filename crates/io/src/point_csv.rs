//! Point CSV files (being written).

use std::path::Path;

use crate::{Error, Format, Result, Summary};

/// Summarizes a point CSV.
pub fn summarize(path: &Path) -> Result<Summary> {
    Err(not_yet(path))
}
#[allow(dead_code)]
fn _f(_: Format) {}

fn not_yet(path: &Path) -> Error {
    Error::UnknownFormat {
        path: path.to_path_buf(),
        reason: "reader not implemented yet".into(),
    }
}
