//! The evaluation registry: one table of every evaluation (name, what it measures, how it
//! runs) in the order `all` runs them, and the entry points that run one, all, a shard or a
//! merge by name.
//!
//! Every evaluation is a function `run(&EvalContext) -> Result<EvalReport>` or written in
//! stages ([`stages`]); either way the quick or full run is the context's `quick` flag. The
//! runner prints the report and writes `docs/results/<name>.md` (with the command, date,
//! machine and data directory) and `target/eval/<name>.json` ([`report`]).

mod carmen_angles;
mod comparable;
mod context;
mod corridor;
mod dct;
mod geometry;
mod io;
mod mcl;
pub mod memory;
mod octomap;
mod place_recognition;
mod planes;
mod poles_kitti;
mod poles_nclt;
mod polylines;
mod registration;
mod report;
mod scan_matching;
mod segcomp;
mod sensor_models;
mod sim;
mod slam;
mod slam_map;
pub mod stages;
mod synpeb;

use std::time::Instant;

use anyhow::{Context, Result, bail};

pub(crate) use crate::stats::median;
pub(crate) use context::{BENCHMARK_LOGS, context};
pub use context::{EvalContext, data_dir, workspace_root};
pub use report::EvalReport;
use report::write_report;

/// How an evaluation runs: one function, or in stages (then `--shard` and `merge` work).
enum Runner {
    /// The whole evaluation in one call (still measure, then a tested report function).
    /// Kept for `io`, `geometry`, `sim` and `memory`: they take seconds to a few minutes, and
    /// `geometry` and `memory` measure the machine itself (throughput, peak memory beside
    /// OctoMap in the same run), which shards on other machines would mix.
    Whole(fn(&EvalContext) -> Result<EvalReport>),
    /// Units, then the report ([`stages::run_all`]).
    Staged(&'static stages::Staged),
}

impl Runner {
    fn run(&self, ctx: &EvalContext) -> Result<EvalReport> {
        match self {
            Runner::Whole(run) => run(ctx),
            Runner::Staged(staged) => stages::run_all(staged, ctx),
        }
    }
}

/// All evaluations in the order `all` runs them.
const EVALUATIONS: &[(&str, &str, Runner)] = &[
    (
        "io",
        "read every file under RAYPATH_DATA: counts and throughput per format",
        Runner::Whole(io::run),
    ),
    (
        "geometry",
        "exact ray traversal throughput in 2-D and 3-D (cells per second)",
        Runner::Whole(geometry::run),
    ),
    (
        "sim",
        "simulated data sets: contents, statistics beside real samples, pictures",
        Runner::Whole(sim::run),
    ),
    (
        "carmen-angles",
        "CARMEN beam-angle convention checked by map sharpness on the corrected logs",
        Runner::Staged(&carmen_angles::STAGED),
    ),
    (
        "sensor-models",
        "sensor models scored at the true pose and by inverse KL (Schaefer Tables 7.3, 8.2, 8.3)",
        Runner::Staged(&sensor_models::STAGED),
    ),
    (
        "mcl",
        "Monte-Carlo localization error per sensor model (Table 7.2), ch. 8 corridor, filter speed",
        Runner::Staged(&mcl::STAGED),
    ),
    (
        "polylines",
        "PLE, PLE+ and the VVL/IEF/SAM baselines on real and simulated scans (Fig. 10.4, Table 10.2)",
        Runner::Staged(&polylines::STAGED),
    ),
    (
        "synpeb",
        "PPE plane extraction on SynPEB-style scans at five noise levels (Table 11.1)",
        Runner::Staged(&synpeb::STAGED),
    ),
    (
        "segcomp",
        "PPE, PEAC-style and MSAC grid-searched on SegComp Perceptron (when installed) and a simulated stand-in (Table 11.1)",
        Runner::Staged(&segcomp::STAGED),
    ),
    (
        "octomap",
        "Rtree variable-resolution occupancy grid beside OctoMap measured in the same run (Khan ch. 2)",
        Runner::Staged(&octomap::STAGED),
    ),
    (
        "memory",
        "peak resident memory of the Rtree grid (beside OctoMap), pole extraction and PPE",
        Runner::Whole(memory::run),
    ),
    (
        "poles-kitti",
        "pole extraction and pole-based localization on semi-synthetic KITTI drives (Table 12.2)",
        Runner::Staged(&poles_kitti::STAGED),
    ),
    (
        "poles-nclt",
        "pole-based localization over simulated NCLT-style sessions (Table 12.1)",
        Runner::Staged(&poles_nclt::STAGED),
    ),
    (
        "dct",
        "continuous DCT decay-rate maps against grid maps on the real logs (Tables 9.2-9.4)",
        Runner::Staged(&dct::STAGED),
    ),
    (
        "scan-matching",
        "intensity calibration and Hector-style scan matching with occupancy/reflectivity residuals (Khan ch. 3)",
        Runner::Staged(&scan_matching::STAGED),
    ),
    (
        "slam",
        "2-D SLAM (submaps, branch-and-bound loop closure, robust pose graph) on the SLAM-benchmark logs",
        Runner::Staged(&slam::STAGED),
    ),
    (
        "place-recognition",
        "IBuILD loop closure and lidar place recognition beside DBoW2, Scan Context, HOG, GIST, SHOT (Khan ch. 4)",
        Runner::Staged(&place_recognition::STAGED),
    ),
    (
        "registration",
        "3-D point-to-plane ICP and KISS-ICP-style odometry on the real KITTI and Ouster frames",
        Runner::Staged(&registration::STAGED),
    ),
];

/// The names of all evaluations in the order `all` runs them.
pub fn names() -> impl Iterator<Item = &'static str> {
    EVALUATIONS.iter().map(|(name, _, _)| *name)
}

/// The evaluations written in stages: `--shard i/n` and `eval merge` work for these.
fn staged_evaluations() -> impl Iterator<Item = &'static stages::Staged> {
    EVALUATIONS
        .iter()
        .filter_map(|(_, _, runner)| match runner {
            Runner::Staged(staged) => Some(*staged),
            Runner::Whole(_) => None,
        })
}

fn staged(name: &str) -> Result<&'static stages::Staged> {
    staged_evaluations()
        .find(|s| s.name == name)
        .with_context(|| {
            let names: Vec<_> = staged_evaluations().map(|s| s.name).collect();
            let what = if EVALUATIONS.iter().any(|(n, _, _)| *n == name) {
                "runs whole (not in stages)"
            } else {
                "is no evaluation"
            };
            format!(
                "{name:?} {what}; --shard and merge work for: {}",
                names.join(", ")
            )
        })
}

/// `cargo xtask eval <name> --shard i/n`: the shard's units, written to
/// `target/eval/shards/<name>/`.
pub fn run_shard(name: &str, quick: bool, shard: stages::Shard) -> Result<()> {
    let staged = staged(name)?;
    let path = stages::run_shard(staged, &context(quick), shard)?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// `cargo xtask eval merge <name>`: the report of the shards in `target/eval/shards/<name>/`,
/// written as a single run writes it.
pub fn merge(name: &str, quick: bool) -> Result<()> {
    let staged = staged(name)?;
    let ctx = context(quick);
    let (results, seconds) = stages::merge(staged, &ctx, &stages::shard_dir(&ctx, name))?;
    let report = (staged.report)(&ctx, &results)?;
    write_report(&ctx, &report, seconds)
}

/// Runs `name` (or `all`, or `list`).
pub fn run(name: &str, quick: bool) -> Result<()> {
    if name == "list" {
        for (name, about, _) in EVALUATIONS {
            println!("{name:<16} {about}");
        }
        return Ok(());
    }
    let ctx = context(quick);
    let selected: Vec<_> = if name == "all" {
        EVALUATIONS.iter().collect()
    } else {
        let found: Vec<_> = EVALUATIONS.iter().filter(|(n, _, _)| *n == name).collect();
        if found.is_empty() {
            let names: Vec<_> = EVALUATIONS.iter().map(|(n, _, _)| *n).collect();
            bail!(
                "no evaluation named {name:?}; choose one of {} or all",
                names.join(", ")
            );
        }
        found
    };
    let mut failures = Vec::new();
    for (name, _, runner) in selected {
        eprintln!("== eval {name}{}", if quick { " (quick)" } else { "" });
        let started = Instant::now();
        match runner.run(&ctx) {
            Ok(report) => write_report(&ctx, &report, started.elapsed().as_secs_f64())?,
            Err(error) => {
                eprintln!("eval {name} failed: {error:#}");
                failures.push(*name);
            }
        }
    }
    if !failures.is_empty() {
        bail!("evaluations failed: {}", failures.join(", "));
    }
    Ok(())
}
