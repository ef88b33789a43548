//! Section 1: real 2-D revisits on the corrected CARMEN logs (real scans, real SLAM-corrected
//! poses as ground truth): IBuILD and DBoW2-style on rasterised scans, planar polar context;
//! online loop closure and kidnapped mode.
//!
//! In stages: one unit per fold of the vocabulary training ([`run_fold`]: the fold's
//! DBoW2-style vocabulary, trained once on the other fold's logs, then each of its logs), the
//! section ([`page::section`]) from both folds' results. The fold and not the log is the unit
//! because its logs share the vocabulary: per-log units would train it once per log (five times
//! per fold in a full run).

mod page;

use std::path::Path;
use std::sync::Arc;

use anyhow::{Result, ensure};
use rayon::prelude::*;
use raypath_place_recognition::{BinaryVocabulary, Frame};
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use super::data2d::{LOGS, Log2, load};
use super::report::{is_sweep, pr_figures, result_cells, sweep_rows};
use super::runner::{Features, Input, MethodResult, Sample};
use super::{FIGURES, aim_row, methods, truth};
use crate::eval::EvalContext;

pub use page::section;

/// The folds (units of the section).
pub const FOLD_COUNT: usize = FOLDS.len();

/// Scans rasterised and described at once (in parallel) before they are fed to the methods.
const CHUNK: usize = 16;
/// Full mode: logs longer than this are subsampled to at most this many scans (the kidnapped
/// similarity matrix grows with the square).
const MAX_SCANS: usize = 1200;
/// Training images per log for the vocabularies (evenly spaced).
const TRAIN_IMAGES: usize = 150;
const TRAIN_IMAGES_QUICK: usize = 40;
/// The two folds of the vocabulary training: a log of fold `k` is evaluated with the
/// vocabulary trained on the logs of the other fold.
const FOLDS: [[&str; 5]; 2] = [
    ["intel", "csail", "fhw", "acapulco", "freiburg-101"],
    [
        "freiburg-079",
        "aces",
        "freiburg-campus",
        "infinite-corridor",
        "belgioioso",
    ],
];
/// Quick: the training logs of each fold (the smaller ones).
const FOLDS_QUICK: [[&str; 2]; 2] = [["csail", "fhw"], ["aces", "belgioioso"]];

fn fold_of(name: &str) -> usize {
    usize::from(FOLDS[1].contains(&name))
}

/// The logs of this run with their strides.
fn plan(quick: bool) -> Vec<(&'static str, &'static str, Option<usize>)> {
    LOGS.iter()
        .filter(|(name, _)| !quick || matches!(*name, "intel" | "freiburg-079"))
        .map(|&(name, path)| {
            let stride = if quick && name == "freiburg-079" {
                Some(16)
            } else {
                None
            };
            (name, path, stride)
        })
        .collect()
}

/// Trains the vocabulary of `fold`'s logs on the other fold's logs; returns it (`None` when
/// no training log is found) with the note for the report.
fn vocabulary(ctx: &EvalContext, fold: usize) -> Result<(Option<Arc<BinaryVocabulary>>, String)> {
    let per_log = if ctx.quick {
        TRAIN_IMAGES_QUICK
    } else {
        TRAIN_IMAGES
    };
    let train: Vec<&str> = if ctx.quick {
        FOLDS_QUICK[1 - fold].to_vec()
    } else {
        FOLDS[1 - fold].to_vec()
    };
    let mut images = Vec::new();
    let mut used = Vec::new();
    for name in &train {
        let Some((_, path)) = LOGS.iter().find(|(n, _)| n == name) else {
            continue;
        };
        let file = ctx.data(path);
        if !file.exists() {
            continue;
        }
        let log = load(&file, 1)?;
        let step = log.scans.len().div_ceil(per_log).max(1);
        let scans: Vec<_> = log.scans.iter().step_by(step).collect();
        let described: Vec<Vec<_>> = scans
            .par_iter()
            .map(|s| Ok(methods::planar_features(s)?.descriptors))
            .collect::<Result<_>>()?;
        used.push(format!("{name} ({} scans)", described.len()));
        images.extend(described);
    }
    if images.is_empty() {
        return Ok((
            None,
            format!(
                "No training log of fold {} found: no DBoW2-style vocabulary.",
                1 - fold
            ),
        ));
    }
    let descriptors: usize = images.iter().map(Vec::len).sum();
    let vocabulary = methods::train_vocabulary(&images)?;
    let note = format!(
        "Vocabulary for the logs {{{}}}: trained on {} — {descriptors} descriptors, {} words.",
        FOLDS[fold].join(", "),
        used.join(", "),
        vocabulary.word_count()
    );
    Ok((Some(vocabulary), note))
}

/// Runs every method on one log.
fn evaluate_log(
    log: &Log2,
    vocabulary: Option<&Arc<BinaryVocabulary>>,
) -> Result<(Vec<MethodResult>, raypath_place_recognition::GroundTruth)> {
    let truth = truth::planar(&log.poses)?;
    let mut runners = methods::planar(vocabulary)?;
    let limits = truth::online_limits(log.scans.len(), None);
    // Features once per scan (shared by IBuILD and DBoW2-style), in parallel chunks.
    for (c, chunk) in log.scans.chunks(CHUNK).enumerate() {
        let features: Vec<Features> = chunk
            .par_iter()
            .map(methods::planar_features)
            .collect::<Result<_>>()?;
        for (k, (scan, f)) in chunk.iter().zip(&features).enumerate() {
            let sample = Sample::default()
                .with(Input::Planar, Frame::Planar(scan))
                .with_features(Input::Planar, Some(f));
            runners
                .par_iter_mut()
                .for_each(|r| r.step(&sample, limits[c * CHUNK + k]));
        }
    }
    let results = runners
        .par_iter_mut()
        .map(|r| r.evaluate(&truth, true))
        .collect();
    Ok((results, truth))
}

/// What one fold's unit measured: the note on its vocabulary and its logs in plan order.
#[derive(Serialize, Deserialize)]
pub struct FoldResult {
    /// How the fold's DBoW2-style vocabulary was trained (or why there is none).
    pub vocabulary_note: String,
    /// The logs of the fold in this run.
    pub logs: Vec<LogOutcome>,
}

/// One log of a fold: its rows, or the note that it is missing.
#[derive(Serialize, Deserialize)]
pub enum LogOutcome {
    /// The log ran.
    Done(Box<LogRows>),
    /// The log's file is absent.
    Missing {
        /// The log.
        name: String,
        /// Its path under the data directory.
        path: String,
    },
}

impl LogOutcome {
    /// The log's name.
    pub fn name(&self) -> &str {
        match self {
            LogOutcome::Done(rows) => &rows.name,
            LogOutcome::Missing { name, .. } => name,
        }
    }
}

/// The table rows, pictures and JSON of one log (the cells as the page prints them).
#[derive(Serialize, Deserialize)]
pub struct LogRows {
    /// The log.
    pub name: String,
    /// Rows of the results table (one per method, the δ sweep left out).
    pub results: Vec<Vec<String>>,
    /// Rows of the δ-sweep table.
    pub sweep: Vec<Vec<String>>,
    /// The aim row (IBuILD against DBoW2-style).
    pub aim: Vec<String>,
    /// The same for the symmetric IBuILD (shown, not counted in the summary).
    pub symmetric_aim: Vec<String>,
    /// The aim rows of the geometric check ([`checked_aims`]).
    #[serde(default)]
    pub checked_aims: Vec<Vec<String>>,
    /// Rows of the δ sweep of the symmetric IBuILD on scan shapes ([`shape_sweep_rows`]).
    #[serde(default)]
    pub shape_sweep: Vec<Vec<String>>,
    /// The PR pictures (markdown; the PNGs are written by the unit).
    pub pictures: String,
    /// The log's figures for the JSON.
    pub json: Value,
}

/// The IBuILD variants measured against the baselines with and without the geometric check
/// (full labels), each a fixed choice for every log (none picked per log after the fact).
pub fn aim_variants() -> Vec<String> {
    use methods::{CHECKED, SHAPE_IBUILD, SHAPE_SYMMETRIC, SYMMETRIC_IBUILD};
    vec![
        format!("IBuILD{CHECKED}"),
        format!("{SYMMETRIC_IBUILD}{CHECKED}"),
        SHAPE_SYMMETRIC.to_string(),
        format!("{SHAPE_IBUILD}{CHECKED}"),
        format!("{SHAPE_SYMMETRIC}{CHECKED}"),
    ]
}

/// Recall at 100 % precision of the method labelled `label` on the rasterised scans.
fn recall_at_100(results: &[MethodResult], label: &str, online: bool) -> Option<f64> {
    let key = format!("{label} ({})", Input::Planar.name());
    let r = results.iter().find(|r| r.key() == key)?;
    let summary = if online {
        r.online_summary()
    } else {
        r.kidnapped_summary()
    };
    summary.map(|s| s.recall_at_100_precision)
}

/// "yes", "tie at 0" or "**no**": `ours` ≥ every one of `baselines`.
fn holds(ours: Option<f64>, baselines: &[Option<f64>]) -> String {
    let Some(a) = ours else {
        return "—".into();
    };
    let known: Vec<f64> = baselines.iter().flatten().copied().collect();
    if known.is_empty() {
        "—".into()
    } else if a == 0.0 && known.iter().all(|&b| b == 0.0) {
        "tie at 0".into()
    } else if known.iter().all(|&b| a >= b) {
        "yes".into()
    } else {
        "**no**".into()
    }
}

/// Per IBuILD variant and mode: the variant with the geometric check against DBoW2-style and
/// polar context with the same check (like for like) and without it.
fn checked_aims(name: &str, results: &[MethodResult]) -> Vec<Vec<String>> {
    use methods::CHECKED;
    let mut rows = Vec::new();
    for variant in aim_variants() {
        for online in [true, false] {
            let r = |label: &str| recall_at_100(results, label, online);
            let ours = r(&variant);
            let checked = [
                r(&format!("DBoW2-style{CHECKED}")),
                r(&format!("polar context{CHECKED}")),
            ];
            let plain = [r("DBoW2-style"), r("polar context")];
            rows.push(vec![
                name.to_string(),
                "real".into(),
                variant.clone(),
                if online { "online" } else { "kidnapped" }.into(),
                super::report::pct(ours),
                super::report::pct(checked[0]),
                super::report::pct(checked[1]),
                holds(ours, &checked),
                super::report::pct(plain[0]),
                super::report::pct(plain[1]),
                holds(ours, &plain),
            ]);
        }
    }
    rows
}

/// One row per δ of the symmetric IBuILD on scan shapes: online recall at 100 % precision
/// without and with the geometric check, kidnapped with the check.
fn shape_sweep_rows(name: &str, results: &[MethodResult]) -> Vec<Vec<String>> {
    use methods::{CHECKED, SHAPE_DELTA, SHAPE_DELTAS, SHAPE_SYMMETRIC};
    let find = |label: &str| recall_at_100(results, label, true);
    SHAPE_DELTAS
        .iter()
        .map(|&delta| {
            let base = if delta == SHAPE_DELTA {
                SHAPE_SYMMETRIC.to_string()
            } else {
                format!("{SHAPE_SYMMETRIC} δ={delta}")
            };
            let checked = format!("{base}{CHECKED}");
            vec![
                name.to_string(),
                "real".into(),
                delta.to_string(),
                super::report::pct(find(&base)),
                super::report::pct(find(&checked)),
                super::report::pct(recall_at_100(results, &checked, false)),
            ]
        })
        .collect()
}

/// The position of each log of this run in the report (the order of [`LOGS`]).
pub fn log_order(quick: bool) -> Vec<&'static str> {
    plan(quick).into_iter().map(|(name, _, _)| name).collect()
}

/// The unit of fold `fold`: its vocabulary, then every log of the fold in this run.
pub fn run_fold(ctx: &EvalContext, fold: usize) -> Result<FoldResult> {
    ensure!(fold < FOLD_COUNT, "no fold {fold}");
    let (vocabulary, vocabulary_note) = vocabulary(ctx, fold)?;
    let figures = ctx.figure_dir(FIGURES)?;
    let mut logs = Vec::new();
    for (name, path, stride) in plan(ctx.quick) {
        if fold_of(name) != fold {
            continue;
        }
        let file = ctx.data(path);
        if !file.exists() {
            logs.push(LogOutcome::Missing {
                name: name.to_owned(),
                path: path.to_owned(),
            });
            continue;
        }
        let rows = run_log(&file, name, stride, vocabulary.as_ref(), &figures)?;
        logs.push(LogOutcome::Done(Box::new(rows)));
    }
    Ok(FoldResult {
        vocabulary_note,
        logs,
    })
}

/// Every method on one log (every `stride`-th scan; `None`: at most [`MAX_SCANS`]): its rows,
/// PR pictures (written to `figures`) and JSON.
fn run_log(
    file: &Path,
    name: &str,
    stride: Option<usize>,
    vocabulary: Option<&Arc<BinaryVocabulary>>,
    figures: &Path,
) -> Result<LogRows> {
    let started = std::time::Instant::now();
    let full = load(file, 1)?;
    let total = full.scans.len();
    let stride = stride.unwrap_or_else(|| total.div_ceil(MAX_SCANS).max(1));
    let log = full.subsample(stride);
    let (results, truth) = evaluate_log(&log, vocabulary)?;
    let queries = truth::revisit_queries(&truth);
    let scans = if stride > 1 {
        format!("{} (every {stride}th of {total})", log.scans.len())
    } else {
        log.scans.len().to_string()
    };
    let leading = [
        name.to_string(),
        "real".into(),
        scans,
        queries.to_string(),
        truth.true_pairs().to_string(),
    ];
    let rows = LogRows {
        name: name.to_owned(),
        results: results
            .iter()
            .filter(|r| !is_sweep(r))
            .map(|r| leading.iter().cloned().chain(result_cells(r)).collect())
            .collect(),
        sweep: sweep_rows(&[name.to_string(), "real".into()], &results, Input::Planar),
        aim: aim_row(
            name,
            "real",
            &results,
            "IBuILD (planar scan)",
            "DBoW2-style (planar scan)",
        ),
        symmetric_aim: aim_row(
            &format!("{name} ({})", methods::SYMMETRIC_IBUILD),
            "real",
            &results,
            &format!("{} (planar scan)", methods::SYMMETRIC_IBUILD),
            "DBoW2-style (planar scan)",
        ),
        checked_aims: checked_aims(name, &results),
        shape_sweep: shape_sweep_rows(name, &results),
        pictures: format!("**{name}**\n\n")
            + &pr_figures(figures, FIGURES, &format!("2d-{name}"), &results)?,
        json: json!({
            "log": name,
            "data": "real",
            "scans": log.scans.len(),
            "stride": stride,
            "total_scans": total,
            "revisit_queries": queries,
            "true_pairs": truth.true_pairs(),
            "methods": results.iter().map(MethodResult::json).collect::<Vec<Value>>(),
        }),
    };
    eprintln!(
        "place-recognition: 2-D {name} done in {:.0} s ({} scans)",
        started.elapsed().as_secs_f64(),
        log.scans.len()
    );
    Ok(rows)
}
