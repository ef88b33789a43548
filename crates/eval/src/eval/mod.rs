//! The evaluation registry and the report writer shared by all evaluations.
//!
//! Every evaluation is a function `run(&EvalContext) -> Result<EvalReport>`. The framework
//! prints the report, writes `docs/results/<name>.md` (with the command, date, machine and
//! data directory) and `target/eval/<name>.json`.

mod carmen_angles;
mod comparable;
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
mod scan_matching;
mod segcomp;
mod sensor_models;
mod sim;
mod slam;
mod slam_map;
pub mod stages;
mod synpeb;

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
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

/// The result of one evaluation.
pub struct EvalReport {
    /// Short name (`io`, `geometry`, …): file names and `cargo xtask eval <name>`.
    pub name: &'static str,
    /// A one-line title.
    pub title: String,
    /// The markdown body: tables beside the thesis figures, notes on what is real and what is
    /// simulated.
    pub markdown: String,
    /// Machine-readable results.
    pub json: serde_json::Value,
    /// The run's figures in one line, real rows first (simulated ones named so): written at
    /// the top of the results page and, after a full run, into the README's headline table
    /// ([`crate::readme`]).
    pub headline: Option<String>,
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

fn context(quick: bool) -> EvalContext {
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

fn write_report(ctx: &EvalContext, report: &EvalReport, seconds: f64) -> Result<()> {
    let command = format!(
        "cargo xtask eval {}{}",
        report.name,
        if ctx.quick { " --quick" } else { "" }
    );
    let header = format!(
        "# {}\n\n<!-- Written by `{command}`; do not edit by hand. -->\n\n\
         - Command: `{command}`\n- Date (UTC): {}\n- Machine: {}\n- Data: `{}`\n- Run time: {seconds:.1} s\n\n",
        report.title,
        utc_date(),
        machine(),
        ctx.data_dir.display(),
    );
    let headline = match &report.headline {
        Some(text) if ctx.quick => format!("**Headline (quick run).** {text}\n\n"),
        Some(text) => format!("{}{text}\n\n", crate::readme::PREFIX),
        None => String::new(),
    };
    let markdown = format!("{header}{headline}{}", report.markdown.trim_end());
    println!("{markdown}\n");

    let docs = ctx.out_dir.join("docs/results");
    std::fs::create_dir_all(&docs)?;
    let md_path = docs.join(format!("{}.md", report.name));
    std::fs::write(&md_path, format!("{markdown}\n"))
        .with_context(|| format!("writing {}", md_path.display()))?;

    let json_dir = ctx.out_dir.join("target/eval");
    std::fs::create_dir_all(&json_dir)?;
    let json_path = json_dir.join(format!("{}.json", report.name));
    let json = serde_json::json!({
        "name": report.name,
        "title": report.title,
        "command": command,
        "quick": ctx.quick,
        "date_utc": utc_date(),
        "machine": machine(),
        "data_dir": ctx.data_dir.display().to_string(),
        "seconds": seconds,
        "results": report.json,
    });
    std::fs::write(&json_path, serde_json::to_string_pretty(&json)?)
        .with_context(|| format!("writing {}", json_path.display()))?;
    eprintln!("wrote {} and {}", md_path.display(), json_path.display());
    if report.headline.is_some() && !ctx.quick && ctx.out_dir == ctx.workspace_root {
        crate::readme::update(&ctx.workspace_root)?;
    }
    Ok(())
}

/// The workspace root: the parent of the xtask crate.
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
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

/// CPU model and core count, for report headers.
pub fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|info| {
            info.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_owned())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_owned());
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    format!("{cpu}, {cores} cores available")
}

/// Today's date in UTC as `YYYY-MM-DD HH:MM`.
pub fn utc_date() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let days = (secs / 86_400) as i64;
    let (hour, minute) = ((secs % 86_400) / 3600, (secs % 3600) / 60);
    // Civil-from-days (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02} {hour:02}:{minute:02}")
}

/// Median of a slice (sorted in place); NaN for none.
pub fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}
