//! `raypath segcomp-eval`: scores a segmentation against ground-truth labels with the
//! protocol of Hoover et al. (1996), tolerance T = 0.8 (Schaefer 2020 § 11.4).
//!
//! `--truth` is a PCD file with labels (the `label` field, else `intensity` as in SynPEB;
//! labels ≥ 10 are planes); `--labels` a text file with one integer per point in file
//! order (`0` = no plane), as `raypath planes --out` writes.
//!
//! `--json` prints `{"f", "k", "n_o", "n_u", "n_m", "n_s", "correct", "gt_planes",
//! "segments", "tolerance"}` (f and k as fractions in [0, 1]).

use std::io::BufRead;
use std::path::PathBuf;

use raypath_io::pcd::{LabelSource, ReadOptions, read_pcd, read_pcd_header};
use raypath_planes::report::HooverReport;
use raypath_planes::{HooverParams, compare};

use super::Failure;

/// Arguments of `raypath segcomp-eval`.
#[derive(clap::Args)]
pub struct Args {
    /// PCD file with ground-truth labels (`label` field, else `intensity`).
    #[arg(long, value_name = "PCD")]
    pub truth: PathBuf,
    /// Segmentation: one integer label per point (0 = none).
    #[arg(long, value_name = "FILE")]
    pub labels: PathBuf,
    /// Compare tolerance T in (0.5, 1].
    #[arg(long, default_value_t = 0.8, value_name = "T")]
    pub tolerance: f64,
    /// Use strict `>` comparisons (the reference evaluator).
    #[arg(long)]
    pub strict: bool,
}

fn read_labels(args: &Args) -> Result<Vec<Option<u32>>, Failure> {
    let path = &args.labels;
    let file = std::fs::File::open(path)
        .map_err(|e| Failure::input(format!("{}: {e}", path.display())))?;
    let mut out = Vec::new();
    for (i, line) in std::io::BufReader::new(file).lines().enumerate() {
        let line =
            line.map_err(|e| Failure::input(format!("{}:{}: {e}", path.display(), i + 1)))?;
        let t = line.trim();
        if t.is_empty() {
            continue;
        }
        let v: u32 = t.parse().map_err(|_| {
            Failure::input(format!(
                "{}:{}: not a non-negative integer label: {t:?}",
                path.display(),
                i + 1
            ))
        })?;
        out.push((v != 0).then_some(v));
    }
    Ok(out)
}

/// Runs the command.
pub fn run(args: &Args) -> Result<(), Failure> {
    let header = read_pcd_header(&args.truth).map_err(Failure::input)?;
    let label_from = if header.field("label").is_some() {
        LabelSource::LabelField
    } else {
        LabelSource::Intensity
    };
    let pcd = read_pcd(&args.truth, &ReadOptions { label_from }).map_err(Failure::input)?;
    let Some(truth) = pcd.cloud.label else {
        return Err(Failure::input(format!(
            "{}: no label or intensity field",
            args.truth.display()
        )));
    };
    let gt: Vec<Option<u32>> = truth.into_iter().map(Some).collect();
    let ms = read_labels(args)?;
    if ms.len() != gt.len() {
        return Err(Failure::input(format!(
            "{}: {} labels, but {} has {} points",
            args.labels.display(),
            ms.len(),
            args.truth.display(),
            gt.len()
        )));
    }
    let params = HooverParams {
        tolerance: args.tolerance,
        strict: args.strict,
        ..HooverParams::default()
    };
    let r = compare(&gt, &ms, &params).map_err(Failure::input)?;
    if super::console::json() {
        super::print_json(&HooverReport::new(&r, args.tolerance))?;
    } else {
        println!(
            "GT planes {}, segments {}: correct {} (f = {:.1} %, k = {:.1} %), over {}, under {}, missed {}, noise {}",
            r.gt_regions,
            r.ms_regions,
            r.correct.len(),
            100.0 * r.fraction_correct(),
            100.0 * r.k_value(),
            r.over,
            r.under,
            r.missed,
            r.noise
        );
    }
    Ok(())
}
