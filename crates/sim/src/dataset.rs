//! What every data-set generator returns and how it reports progress.

use std::path::{Path, PathBuf};

use serde::Serialize;

/// Progress callback: called with `(done, total)` work units as a generator proceeds (from any
/// thread). Binaries draw a progress bar with it; pass `&|_, _| {}` to ignore.
pub type Progress<'a> = &'a (dyn Fn(u64, u64) + Sync);

/// A progress callback that ignores all reports.
pub fn no_progress() -> Progress<'static> {
    &|_, _| {}
}

/// The manifest at the root of a generated set (seed, mode, files, statistics), written by
/// `cargo xtask datasets generate`.
pub const SET_MANIFEST: &str = "set.json";

/// Whether the sequence directory `sequence` belongs to a generated set: `<set>/sequences/NN`
/// (or `<set>/NN`) with the [`SET_MANIFEST`] in `<set>`. Such KITTI-layout scans are measured
/// from one pose, not de-skewed sweeps.
pub fn in_generated_set(sequence: &Path) -> bool {
    sequence
        .ancestors()
        .skip(1)
        .take(2)
        .any(|dir| dir.join(SET_MANIFEST).is_file())
}

/// What a generator wrote.
#[derive(Clone, Debug, Default, Serialize)]
pub struct GeneratedSet {
    /// Name of the set (its directory under `datasets/generated/`).
    pub name: String,
    /// What it stands in for and which real format it uses, in one sentence.
    pub description: String,
    /// The files written, relative to the output directory, sorted.
    pub files: Vec<PathBuf>,
    /// Statistics of the set (counts, ranges, distributions) for `docs/results/sim.md`.
    pub stats: serde_json::Value,
}
