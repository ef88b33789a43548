//! What an evaluation gets ([`EvalContext`]: the workspace, the data, quick or full, where the
//! outputs go) and where things are: the workspace root, the data directory, the SLAM
//! benchmark's logs.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};

/// What an evaluation gets: where things are and how much work to do.
pub struct EvalContext {
    /// The workspace root (where `Cargo.toml` and `docs/` are).
    pub workspace_root: PathBuf,
    /// The data directory (`RAYPATH_DATA`, default `datasets/`).
    pub data_dir: PathBuf,
    /// Smaller workloads for CI and first runs.
    pub quick: bool,
    /// Where the outputs go: `docs/results/`, `target/eval/` (and shards) under it. The
    /// workspace root, or `RAYPATH_EVAL_OUT` when set (tests and cluster runs that must not
    /// write into the checkout; the README's headline table is then left alone).
    pub out_dir: PathBuf,
}

impl EvalContext {
    /// A quick context rooted at a scratch directory `root` (tests): data under `root/data`,
    /// outputs under `root`.
    #[cfg(test)]
    pub fn scratch(root: &Path) -> Self {
        Self {
            workspace_root: root.to_path_buf(),
            data_dir: root.join("data"),
            quick: true,
            out_dir: root.to_path_buf(),
        }
    }

    /// A progress bar for `len` steps, drawn on stderr (hidden when stderr is not a terminal).
    pub fn progress(&self, len: u64, message: &str) -> ProgressBar {
        let bar = ProgressBar::new(len);
        bar.set_style(
            ProgressStyle::with_template(
                "{msg:>14} [{bar:30}] {pos}/{len} {elapsed_precise} (eta {eta})",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        bar.set_message(message.to_owned());
        bar
    }

    /// Path of a data file, relative to the data directory.
    pub fn data(&self, relative: &str) -> PathBuf {
        self.data_dir.join(relative)
    }

    /// The semi-synthetic KITTI drive of `kitti-poles/<sequence>` (its real trajectory, times
    /// and pole map) cut to its first `max_scans` scans (`None`: all); `None` when the
    /// directory is absent.
    pub fn semi_kitti_config(
        &self,
        sequence: &str,
        max_scans: Option<usize>,
    ) -> Result<Option<raypath_sim::semi_kitti::SemiKittiConfig>> {
        let dir = self.data(&format!("kitti-poles/{sequence}"));
        if !dir.join("poses.txt").is_file() || !dir.join("poles.csv").is_file() {
            return Ok(None);
        }
        let mut config = raypath_sim::semi_kitti::SemiKittiConfig::from_files(
            &dir.join("poses.txt"),
            &dir.join("times.txt"),
            &dir.join("poles.csv"),
        )
        .with_context(|| format!("reading {}", dir.display()))?;
        config.sequence = sequence.to_owned();
        config.max_scans = max_scans;
        Ok(Some(config))
    }

    /// Where an evaluation may write pictures that belong to its report
    /// (`docs/results/<name>/`), created on demand.
    pub fn figure_dir(&self, name: &str) -> Result<PathBuf> {
        let dir = self.out_dir.join("docs/results").join(name);
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        Ok(dir)
    }
}

/// The SLAM benchmark's raw logs that have a corrected log in the data set: name, raw log,
/// corrected log (under the data directory).
pub(crate) const BENCHMARK_LOGS: [(&str, &str, &str); 3] = [
    (
        "intel",
        "carmen/raw/intel.clf.bz2",
        "carmen/corrected/intel-corrected.log.gz",
    ),
    (
        "fr079",
        "carmen/raw/fr079.clf.bz2",
        "carmen/corrected/freiburg-079-corrected.log.gz",
    ),
    (
        "mit-csail",
        "carmen/raw/mit-csail.clf.bz2",
        "carmen/corrected/csail-corrected.log.gz",
    ),
];

/// The context of a run from the environment (`RAYPATH_EVAL_OUT`, `RAYPATH_DATA`).
pub(crate) fn context(quick: bool) -> EvalContext {
    let out_dir = match std::env::var_os("RAYPATH_EVAL_OUT") {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => workspace_root(),
    };
    EvalContext {
        workspace_root: workspace_root(),
        data_dir: data_dir(),
        quick,
        out_dir,
    }
}

/// The workspace root: two levels above this crate (`crates/eval`).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .and_then(Path::parent)
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

/// `RAYPATH_DATA`, or `datasets/` in the workspace.
pub fn data_dir() -> PathBuf {
    match std::env::var_os("RAYPATH_DATA") {
        Some(dir) if !dir.is_empty() => {
            let dir = PathBuf::from(dir);
            std::fs::canonicalize(&dir).unwrap_or(dir)
        }
        _ => workspace_root().join("datasets"),
    }
}
