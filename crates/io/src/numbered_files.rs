//! Directories of numbered binary files: the `.bin` files of a directory whose names are
//! numbers (KITTI's `velodyne/000042.bin`, NCLT's `velodyne_sync/1326030975726043.bin`),
//! listed in the order of their numbers.

use std::path::{Path, PathBuf};

use crate::{Error, Location, Result};

/// The `.bin` files of `dir` with the numbers their names hold (`000042.bin` → 42), sorted
/// by number (files of equal numbers in the order `read_dir` gives them). Other files are
/// skipped; a `.bin` file not named by a number fails with `reason`, as does an unreadable
/// directory.
pub(crate) fn numbered_bin_files(dir: &Path, reason: &str) -> Result<Vec<(u64, PathBuf)>> {
    let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, Location::File, e))?;
    let mut files = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| Error::io(dir, Location::File, e))?;
        let path = entry.path();
        if path.extension().is_none_or(|e| e != "bin") {
            continue;
        }
        let number = path
            .file_stem()
            .and_then(|s| s.to_str())
            .and_then(|s| s.parse::<u64>().ok());
        let Some(number) = number else {
            return Err(Error::UnknownFormat {
                path,
                reason: reason.into(),
            });
        };
        files.push((number, path));
    }
    files.sort_by_key(|&(number, _)| number);
    Ok(files)
}
