//! Small helpers the 2-D generators share: directories, files and JSON with errors that name
//! the path.

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::error::{Result, SimError};

/// Creates `dir` and its parents.
pub(crate) fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|source| SimError::File {
        path: dir.to_path_buf(),
        source,
    })
}

/// Writes `bytes` to `path` (created or truncated).
pub(crate) fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    std::fs::write(path, bytes).map_err(|source| SimError::File {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes `value` as pretty-printed JSON with a final newline. serde_json prints floats with
/// the shortest round-trip representation and keeps struct field order, so the bytes are
/// deterministic.
pub(crate) fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    let mut bytes = serde_json::to_vec_pretty(value).map_err(|e| SimError::File {
        path: path.to_path_buf(),
        source: std::io::Error::other(e),
    })?;
    bytes.push(b'\n');
    write_file(path, &bytes)
}

/// Maps a raypath-io error of an in-memory writer.
pub(crate) fn io_error(e: raypath_io::Error) -> SimError {
    SimError::Io(e)
}

/// The relative paths, sorted (what [`crate::GeneratedSet::files`] lists).
pub(crate) fn sorted(mut files: Vec<PathBuf>) -> Vec<PathBuf> {
    files.sort();
    files
}

/// Reports progress from parallel workers: counts finished items and calls the callback.
pub(crate) struct Counter<'a> {
    done: std::sync::atomic::AtomicU64,
    total: u64,
    progress: crate::Progress<'a>,
}

impl<'a> Counter<'a> {
    pub(crate) fn new(total: u64, progress: crate::Progress<'a>) -> Self {
        progress(0, total);
        Self {
            done: std::sync::atomic::AtomicU64::new(0),
            total,
            progress,
        }
    }

    pub(crate) fn tick(&self) {
        let done = self.done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        (self.progress)(done, self.total);
    }
}
