//! `raypath score-model`: score every sensor model on a corrected CARMEN log or a rosbag2 bag
//! with reference poses (Schaefer 2020, Tables 7.3, 8.2, 8.3).
//!
//! The scans are read through `raypath_io::sequence` (`--laser` picks the laser of a CARMEN
//! log, front by default; a bag's LaserScan topic at its reference poses, else at its logged
//! poses). The scans are split into a mapping set and a disjoint test set (default: even
//! scans map, odd scans are scored), the maps are built with the reference poses, and each
//! model is scored by `D'` (Eq. 7.28: summed −ln p of the test rays at the true poses) and by
//! the inverse KL (Eq. 7.29: 50 positions in a 2.5 m disc, averaged over test scans). See
//! [`raypath_sensor_models::scoring`] for the details.
//!
//! `--json` prints `{"rows": [{"model", "posterior", "neg_log_likelihood", "inverse_kl"}, …]}`
//! plus the top-level keys `log`, `scans`, `mapping_scans`, `test_scans`, `test_rays`,
//! `resolution_m`, `max_range_m`, `grid`, `seed`, `split`, `beam_step`, `kl_ground_truth`
//! (per row, in row order) and `timing`.

use std::path::PathBuf;

use raypath_geometry::{Pose2, Scan2};
use raypath_sensor_models::scoring::{ScoreReport, ScoringConfig, Split, score_log};
use serde_json::json;

use super::Failure;
use super::source_args::{SourceArgs, reference_track};

/// `--split`: which scans build the maps and which are scored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SplitArg {
    /// Even scans build the maps, odd scans are scored.
    Alternate,
    /// The first half builds the maps, the second half is scored.
    Halves,
}

impl From<SplitArg> for Split {
    fn from(split: SplitArg) -> Self {
        match split {
            SplitArg::Alternate => Split::Alternate,
            SplitArg::Halves => Split::Halves,
        }
    }
}

/// Arguments of `raypath score-model`.
#[derive(clap::Args)]
pub struct Args {
    /// A CARMEN log with reference poses (a `*-corrected.log`, plain, .gz or .bz2), or a
    /// rosbag2 bag (directory with metadata.yaml, or .mcap file) with LaserScan and reference
    /// poses.
    pub log: PathBuf,
    /// Cell edge of the maps in metres.
    #[arg(long, default_value_t = 0.1, value_name = "M")]
    pub resolution: f64,
    /// Seed of the pose samples of the inverse KL.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Mapping / test split.
    #[arg(long, value_enum, default_value_t = SplitArg::Alternate, value_name = "NAME")]
    pub split: SplitArg,
    /// Score every k-th beam of a test scan.
    #[arg(long, default_value_t = 1, value_name = "K")]
    pub beam_step: usize,
    /// Score at most this many test scans (evenly spaced).
    #[arg(long, value_name = "N")]
    pub max_test_scans: Option<usize>,
    /// Perturbed poses per test scan.
    #[arg(long, default_value_t = 50, value_name = "M")]
    pub poses: usize,
    /// Maximum range in metres (default: the no-return threshold inferred from the log).
    #[arg(long, value_name = "M")]
    pub max_range: Option<f64>,
    /// How to read the log.
    #[command(flatten)]
    pub source: SourceArgs,
}

/// Runs `raypath score-model`.
pub fn run(args: &Args) -> Result<(), Failure> {
    let config = ScoringConfig {
        resolution_m: args.resolution,
        split: args.split.into(),
        max_range_m: args.max_range,
        poses_per_scan: args.poses,
        seed: args.seed,
        beam_step: args.beam_step,
        max_test_scans: args.max_test_scans,
        ..ScoringConfig::default()
    };
    config.validate().map_err(Failure::input)?;
    let scans = read_scans(args)?;
    if scans.len() < 2 {
        return Err(Failure::input(format!(
            "{}: {} laser scan(s); scoring needs at least 2 (one to map, one to test)",
            args.log.display(),
            scans.len()
        )));
    }
    let report = score_log(&scans, &config)
        .map_err(|e| Failure::input(format!("{}: {e}", args.log.display())))?;
    if super::console::json() {
        let text = serde_json::to_string_pretty(&to_json(args, &config, scans.len(), &report))
            .map_err(|e| Failure::internal(e.to_string()))?;
        println!("{text}");
    } else {
        print!("{}", render_text(args, scans.len(), &report));
    }
    Ok(())
}

/// The laser scans of the log with their reference poses (scans without one are left out).
fn read_scans(args: &Args) -> Result<Vec<(Pose2, Scan2)>, Failure> {
    let frames = args.source.read_frames(&args.log).map_err(Failure::input)?;
    let track = reference_track(&frames);
    Ok(frames
        .into_iter()
        .zip(track)
        .filter_map(|(f, pose)| Some((pose?, f.scan)))
        .collect())
}

/// The JSON document: `rows` with exactly the four contract keys, the rest top-level.
fn to_json(
    args: &Args,
    config: &ScoringConfig,
    scans: usize,
    report: &ScoreReport,
) -> serde_json::Value {
    let rows: Vec<_> = report
        .rows
        .iter()
        .map(|r| {
            json!({
                "model": r.model,
                "posterior": r.posterior,
                "neg_log_likelihood": r.neg_log_likelihood,
                "inverse_kl": r.inverse_kl,
            })
        })
        .collect();
    let kl: Vec<_> = report
        .rows
        .iter()
        .map(|r| json!({ "model": r.model, "posterior": r.posterior, "kl": r.kl_ground_truth }))
        .collect();
    let timing: Vec<_> = report
        .rows
        .iter()
        .map(|r| {
            json!({
                "model": r.model, "posterior": r.posterior,
                "evaluations": r.evaluations, "seconds": r.seconds,
                "evaluations_per_second": r.evaluations_per_second(),
            })
        })
        .collect();
    json!({
        "log": args.log.display().to_string(),
        "scans": scans,
        "mapping_scans": report.mapping_scans,
        "test_scans": report.test_scans,
        "test_rays": report.test_rays,
        "resolution_m": report.resolution_m,
        "max_range_m": report.max_range_m,
        "grid": report.grid_dims,
        "seed": config.seed,
        "split": config.split.name(),
        "beam_step": config.beam_step,
        "poses_per_scan": config.poses_per_scan,
        "rows": rows,
        "kl_ground_truth": kl,
        "timing": {
            "mapping_rays": report.mapping_rays,
            "mapping_seconds": report.mapping_seconds,
            "mapping_rays_per_second": report.mapping_rays_per_second(),
            "models": timing,
        },
    })
}

/// The human-readable table.
fn render_text(args: &Args, scans: usize, report: &ScoreReport) -> String {
    let mut out = format!(
        "log: {}\nscans: {scans} ({} mapping, {} scored, {} rays per pose)\n\
         grid: {}×{} cells of {} m, r_max {:.2} m\n\n",
        args.log.display(),
        report.mapping_scans,
        report.test_scans,
        report.test_rays,
        report.grid_dims[0],
        report.grid_dims[1],
        report.resolution_m,
        report.max_range_m,
    );
    out.push_str(&format!(
        "{:<17} {:>9} {:>16} {:>11} {:>14} {:>12}\n",
        "model", "posterior", "D' (nats)", "inverse KL", "KL to truth", "evals/s"
    ));
    for r in &report.rows {
        out.push_str(&format!(
            "{:<17} {:>9} {:>16.1} {:>11.3} {:>14.1} {:>12.3e}\n",
            r.model,
            r.posterior,
            r.neg_log_likelihood,
            r.inverse_kl,
            r.kl_ground_truth,
            r.evaluations_per_second()
        ));
    }
    out.push_str(
        "\nD' = −Σ ln p(z | true pose) over the scored rays (Eq. 7.28, lower is better); inverse \
         KL averaged over scans (Eq. 7.29, 2.5 m disc, σ = 0.05 m); KL to truth summed over scans \
         (Eq. 8.24).\n",
    );
    out
}
