//! `cargo xtask eval memory`: peak resident memory (the kernel's `VmHWM`) of the three
//! speed-critical workloads — the Rtree grid beside OctoMap, pole extraction, PPE — each in a
//! process of its own, so one workload's peak does not hide another's.
//!
//! Every workload runs in a child (`cargo xtask memory-probe <workload>`, this binary) that
//! loads its input, notes `VmHWM` (the input's share), runs, and prints `VmHWM` again with the
//! workload's own size figure (the grid's `stats().bytes`); OctoMap runs in its driver on the
//! same `.graph` file and reports `VmHWM` and `OcTree::memoryUsage()` the same way.

use std::fmt::Write;
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use raypath_planes::PpeParams;
use raypath_poles::{LabelledLocalMap, PoleParams};
use raypath_rtree_grid::{FusionRule, GridConfig, RtreeGrid, Selection, SensorModel};
use serde_json::{Value, json};

use super::octomap::{Dataset, build_peer, dataset, run_peer};
use super::{EvalContext, EvalReport, comparable};
use crate::table::{Table, fmt_num};

const NAME: &str = "memory";

/// The real scan sets of the grid rows (names of `eval octomap`).
const GRID_SETS: [&str; 2] = ["scan.dat", "kitti-00"];

/// The peak resident set of this process so far (`VmHWM`), KiB; `None` off Linux.
pub fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line["VmHWM:".len()..]
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()
}

/// `cargo xtask memory-probe <workload> [--quick]`: runs one workload and prints its JSON
/// line (input share, peak, seconds, size figure).
pub fn probe(workload: &str, quick: bool) -> Result<()> {
    let ctx = super::context(quick);
    let (set, rule) = match workload.split_once('/') {
        Some((set, rule)) => (set, rule),
        None => (workload, ""),
    };
    let result = match (set, rule) {
        ("poles", _) => poles(&ctx)?,
        ("ppe", _) => ppe(&ctx)?,
        (set, "thesis" | "equal" | "equal-batched") => grid(&ctx, set, rule)?,
        _ => bail!("memory-probe: no workload {workload:?}"),
    };
    println!("{result}");
    Ok(())
}

/// The grid on a real scan set with fusion `rule` (`thesis`; `equal`: equal-value, the
/// thesis' seeds, per scan; `equal-batched`: equal-value from every updated cell, fused every
/// 10 scans): `(input KiB, seconds, grid bytes)` in the JSON line.
fn grid(ctx: &EvalContext, set: &str, rule: &str) -> Result<Value> {
    let data = dataset(ctx, set)?.with_context(|| format!("{set}: data absent"))?;
    let input = peak_rss_kib();
    let mut config = GridConfig::with(0.2, 8, SensorModel::BeamBased);
    if rule != "thesis" {
        config.fusion_rule = FusionRule::EqualValue;
    }
    if rule == "equal-batched" {
        config.selection = Selection::UpdatedCells;
        config.fusion_interval_scans = 10;
    }
    let started = Instant::now();
    let mut grid = RtreeGrid::new(config)?;
    grid.insert_clouds(
        data.graph
            .nodes
            .iter()
            .map(|n| (&n.world_from_sensor, &n.points)),
    );
    grid.shrink_to_fit();
    let seconds = started.elapsed().as_secs_f64();
    Ok(
        json!({ "input_kib": input, "peak_kib": peak_rss_kib(), "seconds": seconds,
               "structure_bytes": grid.stats().bytes, "points": data.graph.num_points() }),
    )
}

/// Pole extraction from the local map of the ten real KITTI 00 frames.
fn poles(ctx: &EvalContext) -> Result<Value> {
    let dir = ctx.data("kitti/sequences/00");
    let map = LabelledLocalMap::read_kitti(&dir, 0..10)
        .with_context(|| format!("reading {}", dir.display()))?;
    let input = peak_rss_kib();
    let started = Instant::now();
    let (poles, stats) = map.extract(&map.all(), &PoleParams::kitti())?;
    let seconds = started.elapsed().as_secs_f64();
    Ok(
        json!({ "input_kib": input, "peak_kib": peak_rss_kib(), "seconds": seconds,
               "points": stats.rays, "poles": poles.len() }),
    )
}

/// PPE on the first scan of the generated SynPEB-style test split (σ = 2 cm, 500 × 500).
fn ppe(ctx: &EvalContext) -> Result<Value> {
    let dir = crate::generate::ensure("synpeb", ctx.quick)?.join("test/2.0");
    let path = super::synpeb::pcd_files(&dir)
        .into_iter()
        .next()
        .with_context(|| format!("no scan under {}", dir.display()))?;
    let cloud = raypath_io::pcd::read_pcd(&path, &raypath_io::pcd::ReadOptions::synpeb())
        .with_context(|| format!("reading {}", path.display()))?
        .cloud;
    let input = peak_rss_kib();
    let started = Instant::now();
    let segmentation = raypath_planes::extract(&cloud, &PpeParams::synpeb())?;
    let seconds = started.elapsed().as_secs_f64();
    Ok(
        json!({ "input_kib": input, "peak_kib": peak_rss_kib(), "seconds": seconds,
               "points": cloud.points.len(), "planes": segmentation.planes.len(),
               "size": [cloud.width, cloud.height] }),
    )
}

/// Runs `workload` in a child process and returns its JSON line.
fn child(ctx: &EvalContext, workload: &str) -> Result<Value> {
    let exe = std::env::current_exe().context("locating this binary")?;
    let mut command = Command::new(exe);
    command.args(["memory-probe", workload]);
    if ctx.quick {
        command.arg("--quick");
    }
    let output = command
        .output()
        .with_context(|| format!("running the {workload} probe"))?;
    if !output.status.success() {
        bail!(
            "{workload} probe failed: {}",
            String::from_utf8_lossy(&output.stderr)
        );
    }
    let text = String::from_utf8_lossy(&output.stdout);
    let line = text
        .lines()
        .rev()
        .find(|l| l.starts_with('{'))
        .context("the probe printed no JSON")?;
    serde_json::from_str(line).context("parsing the probe's JSON")
}

/// MiB of a KiB figure (`-` when absent).
fn mib(kib: Option<u64>) -> String {
    kib.map_or("-".into(), |k| fmt_num(k as f64 / 1024.0, 1))
}

/// MiB of a byte figure.
fn mib_bytes(bytes: Option<u64>) -> String {
    bytes.map_or("-".into(), |b| fmt_num(b as f64 / 1_048_576.0, 2))
}

/// Runs the evaluation.
pub fn run(ctx: &EvalContext) -> Result<EvalReport> {
    let mut table = Table::new([
        "workload",
        "data",
        "peak RSS [MiB]",
        "input loaded [MiB]",
        "structure [MiB]",
        "time [s]",
        "peer",
        "peer peak RSS [MiB]",
        "peer structure [MiB]",
        comparable::HEADER,
    ]);
    let mut rows = Vec::new();
    let driver = build_peer(&ctx.workspace_root);
    for set in GRID_SETS {
        let Some(data) = dataset(ctx, set)? else {
            continue;
        };
        let peer = match &driver {
            Ok(d) => Some(run_peer(d, &data.path, 0.2, false, None)?),
            Err(why) => {
                eprintln!("memory: OctoMap unavailable: {why}");
                None
            }
        };
        for (rule, label) in [
            ("thesis", "thesis rule"),
            ("equal", "equal-value"),
            (
                "equal-batched",
                "equal-value, every cell, fused every 10 scans",
            ),
        ] {
            let ours = child(ctx, &format!("{set}/{rule}"))?;
            table.row(grid_row(&data, label, &ours, peer.as_ref()));
            rows.push(
                json!({ "workload": format!("rtree-grid {label}"), "data": set,
                              "ours": ours, "octomap": peer }),
            );
        }
    }
    let poles = child(ctx, "poles")?;
    table.row([
        "pole extraction".into(),
        "real KITTI 00 frames 0–9, one local map".into(),
        mib(poles["peak_kib"].as_u64()),
        mib(poles["input_kib"].as_u64()),
        "-".into(),
        fmt_num(poles["seconds"].as_f64().unwrap_or(f64::NAN), 2),
        "thesis: Python + GPU (not run)".into(),
        "-".into(),
        "-".into(),
        comparable::no("no peer run here; the thesis reports no memory"),
    ]);
    rows.push(json!({ "workload": "pole extraction", "data": "kitti-00", "ours": poles }));
    let ppe = child(ctx, "ppe")?;
    table.row([
        "PPE".into(),
        "simulated SynPEB-style 500 × 500 (σ = 2 cm), first test scan".into(),
        mib(ppe["peak_kib"].as_u64()),
        mib(ppe["input_kib"].as_u64()),
        "-".into(),
        fmt_num(ppe["seconds"].as_f64().unwrap_or(f64::NAN), 2),
        "PCL organized multi-plane segmentation (not installed, not run)".into(),
        "-".into(),
        "-".into(),
        comparable::no("no PCL peer in this workspace; the thesis reports no memory"),
    ]);
    rows.push(json!({ "workload": "PPE", "data": "synpeb test 2.0", "ours": ppe }));
    let mut md = String::new();
    writeln!(
        md,
        "Peak resident memory (`VmHWM` of `/proc/self/status`) of each workload in a process \
         of its own: `input loaded` is the peak after reading the input, before the \
         workload; `structure` is the data structure's own size (our grid's \
         `stats().bytes`, OctoMap's `memoryUsage()` after `prune()`). OctoMap runs in its \
         driver (`crates/eval/octomap/driver.cpp`, liboctomap 1.9) on the same `.graph` file, \
         beam-based, r = 0.2 m, the same sensor model; our grid: r = 0.2 m, M = 8. The \
         processes differ (Rust binary with every evaluation linked vs a small C++ driver), \
         so the peaks include different fixed costs; the structure columns compare the maps \
         alone.\n\n{}",
        table.to_markdown()?
    )?;
    Ok(EvalReport {
        name: NAME,
        title: "Peak memory of the Rtree grid (beside OctoMap), pole extraction and PPE".into(),
        markdown: md,
        json: json!({ "rows": rows }),
        headline: None,
    })
}

/// A grid row: ours (`label` rule) on `data` beside OctoMap's run on the same file.
fn grid_row(
    data: &Dataset,
    label: &str,
    ours: &Value,
    peer: Option<&super::octomap::PeerRun>,
) -> Vec<String> {
    vec![
        format!("Rtree grid, {label}"),
        format!("real {} ({} points)", data.name, data.graph.num_points()),
        mib(ours["peak_kib"].as_u64()),
        mib(ours["input_kib"].as_u64()),
        mib_bytes(ours["structure_bytes"].as_u64()),
        fmt_num(ours["seconds"].as_f64().unwrap_or(f64::NAN), 2),
        "OctoMap 1.9 (pruned)".into(),
        mib(peer.and_then(|p| p.peak_rss_kib)),
        mib_bytes(peer.map(|p| p.memory_bytes as u64)),
        match peer {
            Some(_) => comparable::yes("same scans, resolution and sensor model, same machine"),
            None => comparable::no("OctoMap unavailable in this run"),
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The kernel reports this process' peak, at least a touched 64 MiB block (the counts
    /// are approximate per thread, so only a lower bound is asserted).
    #[test]
    fn peak_rss_covers_a_touched_block() {
        let block = vec![1u8; 64 << 20];
        std::hint::black_box(&block);
        let during = peak_rss_kib().expect("Linux reports VmHWM");
        drop(block);
        assert!(during >= 60 * 1024, "{during}");
        assert_eq!(mib(Some(1536)), "1.5");
        assert_eq!(mib(None), "-");
    }
}
