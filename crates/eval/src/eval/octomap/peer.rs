//! The OctoMap side: builds `crates/eval/octomap/driver.cpp` against the installed liboctomap and
//! runs it on a `.graph` file.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};

/// What the driver reports for one run (the query classes are not written back: a unit's
/// result keeps the agreement computed from them).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PeerRun {
    /// Points inserted.
    pub points: usize,
    /// Wall time of the insertion of all scans, seconds.
    pub insert_secs: f64,
    /// Nodes (inner + leaves) after prune().
    pub nodes: usize,
    /// Leaves after prune().
    pub leaves: usize,
    /// Inner nodes after prune().
    pub inner_nodes: usize,
    /// Leaves as built (before the final prune()).
    pub leaves_built: usize,
    /// OcTree::memoryUsage() after prune(), bytes.
    pub memory_bytes: usize,
    /// Occupied leaves.
    pub occupied_leaves: usize,
    /// Time to visit all leaves and test occupancy, seconds.
    pub access_secs: f64,
    /// Peak resident set of the driver process (`VmHWM`), KiB; absent from older drivers.
    #[serde(default)]
    pub peak_rss_kib: Option<u64>,
    /// Classification of the query points: u, f, o.
    #[serde(default, skip_serializing)]
    pub classes: String,
}

/// Builds the driver into `target/octomap-driver` (rebuilt when the source is newer), or
/// explains why OctoMap is unavailable.
pub fn build(root: &Path) -> Result<PathBuf, String> {
    let source = root.join("crates/eval/octomap/driver.cpp");
    let binary = root.join("target/octomap-driver");
    if !Path::new("/usr/include/octomap/OcTree.h").exists() {
        return Err(
            "OctoMap headers not found (/usr/include/octomap; install liboctomap-dev)".into(),
        );
    }
    let fresh = |b: &Path| -> Option<bool> {
        let built = b.metadata().ok()?.modified().ok()?;
        let src = source.metadata().ok()?.modified().ok()?;
        Some(built >= src)
    };
    if fresh(&binary) == Some(true) {
        return Ok(binary);
    }
    // Built under a name of this process and renamed: shards on one machine may build at once.
    let building = binary.with_extension(format!("building-{}", std::process::id()));
    let output = Command::new("g++")
        .args(["-O2", "-std=c++17"])
        .arg(&source)
        .arg("-o")
        .arg(&building)
        .args(["-loctomap", "-loctomath"])
        .output()
        .map_err(|e| format!("cannot run g++: {e}"))?;
    if !output.status.success() {
        return Err(format!(
            "g++ failed to build the OctoMap driver: {}",
            String::from_utf8_lossy(&output.stderr)
        ));
    }
    std::fs::rename(&building, &binary)
        .map_err(|e| format!("cannot move the OctoMap driver into place: {e}"))?;
    Ok(binary)
}

/// Runs the driver on `graph` at `resolution_m`.
pub fn run(
    driver: &Path,
    graph: &Path,
    resolution_m: f64,
    endpoint: bool,
    queries: Option<&Path>,
) -> Result<PeerRun> {
    let output = Command::new(driver)
        .arg(graph)
        .arg(format!("{resolution_m}"))
        .arg(if endpoint { "endpoint" } else { "beam" })
        .arg(queries.map_or_else(|| PathBuf::from("-"), Path::to_path_buf))
        .output()
        .with_context(|| format!("running {}", driver.display()))?;
    if !output.status.success() {
        bail!(
            "OctoMap driver failed on {}: {}",
            graph.display(),
            String::from_utf8_lossy(&output.stderr)
        );
    }
    let text = String::from_utf8_lossy(&output.stdout);
    let line = text
        .lines()
        .find(|l| l.starts_with('{'))
        .context("OctoMap driver printed no JSON")?;
    serde_json::from_str(line).context("parsing the OctoMap driver's JSON")
}
