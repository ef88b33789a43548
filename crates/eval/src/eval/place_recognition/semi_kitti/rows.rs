//! One sequence's share of section 3, made by its unit: the cells of its rows in every
//! table, its PR pictures and its JSON.

use std::path::Path;

use anyhow::Result;
use raypath_place_recognition::GroundTruth;
use serde_json::{Value, json};

use super::{Facts, Plan, Selection, SequenceRows};
use crate::eval::place_recognition::report::{is_sweep, pct, pr_figures, result_cells, sweep_rows};
use crate::eval::place_recognition::runner::{Input, MethodResult};
use crate::eval::place_recognition::{FIGURES, aim_row, methods, truth};
use crate::table::fmt_num;

/// The rows of one sequence (the PR pictures written to `figures`).
pub(super) fn rows(
    plan: &Plan,
    s: &Selection,
    truth: &GroundTruth,
    facts: &Facts,
    results: &[MethodResult],
    figures: &Path,
) -> Result<SequenceRows> {
    let sequence = plan.sequence;
    let leading = [sequence.to_string(), "simulated".into()];
    Ok(SequenceRows {
        info: info_row(plan, s, truth, facts),
        results: results
            .iter()
            .filter(|r| !is_sweep(r))
            .map(|r| leading.iter().cloned().chain(result_cells(r)).collect())
            .collect(),
        sweep: sweep_rows(&leading, results, Input::Intensity),
        claims: ["HOG", "GIST", "IBuILD"]
            .into_iter()
            .filter_map(|label| claim_row(sequence, label, results))
            .collect(),
        aim: aim_row(
            sequence,
            "simulated",
            results,
            "IBuILD (intensity image)",
            "Scan Context (point cloud)",
        ),
        symmetric_aim: aim_row(
            &format!("{sequence} ({})", methods::SYMMETRIC_IBUILD),
            "simulated",
            results,
            &format!("{} (intensity image)", methods::SYMMETRIC_IBUILD),
            "Scan Context (point cloud)",
        ),
        pictures: format!("**Sequence {sequence}**\n\n")
            + &pr_figures(figures, FIGURES, &format!("semi-kitti-{sequence}"), results)?,
        json: sequence_json(plan, s, truth, facts, results),
    })
}

/// Length of the selected path (m).
fn length_m(s: &Selection) -> f64 {
    s.poses
        .windows(2)
        .map(|w| (w[1].translation() - w[0].translation()).norm())
        .sum()
}

/// Revisit queries whose true match was seen in the opposite direction.
fn opposite_queries(s: &Selection, truth: &GroundTruth) -> usize {
    let yaws: Vec<f64> = s.poses.iter().map(|p| p.to_planar().theta()).collect();
    truth::opposite_queries(truth, &yaws)
}

/// The input frame of the second pass's first frame.
fn second_pass_frame(s: &Selection, facts: &Facts) -> Option<usize> {
    facts.second.map(|k| s.drive.frames[s.selected[k]])
}

/// The sequence's row of the table of sequences.
fn info_row(plan: &Plan, s: &Selection, truth: &GroundTruth, facts: &Facts) -> Vec<String> {
    let frames_text = match &plan.ranges {
        Some(rs) => rs
            .iter()
            .map(|r| format!("{}–{}", r.start, r.end - 1))
            .collect::<Vec<_>>()
            .join(", "),
        None => format!("0–{}", s.drive.frames.last().copied().unwrap_or(0)),
    };
    vec![
        plan.sequence.to_string(),
        "simulated scans, real trajectory".into(),
        frames_text,
        plan.stride.to_string(),
        s.selected.len().to_string(),
        fmt_num(length_m(s), 0),
        truth::revisit_queries(truth).to_string(),
        opposite_queries(s, truth).to_string(),
        second_pass_frame(s, facts).map_or("none".into(), |f| f.to_string()),
        if facts.second.is_some() {
            format!("{} parked cars removed, foliage 0.6", facts.cars_removed)
        } else {
            "none".into()
        },
        fmt_num(facts.seconds, 0),
    ]
}

fn sequence_json(
    plan: &Plan,
    s: &Selection,
    truth: &GroundTruth,
    facts: &Facts,
    results: &[MethodResult],
) -> Value {
    json!({
        "sequence": plan.sequence,
        "data": "simulated scans along the real trajectory",
        "stride": plan.stride,
        "frames": s.selected.len(),
        "length_m": length_m(s),
        "revisit_queries": truth::revisit_queries(truth),
        "opposite_direction_queries": opposite_queries(s, truth),
        "true_pairs": truth.true_pairs(),
        "second_pass_frame": second_pass_frame(s, facts),
        "cars_removed": facts.cars_removed,
        "methods": results.iter().map(MethodResult::json).collect::<Vec<Value>>(),
    })
}

/// The thesis' claim for one descriptor on one sequence: does the intensity image beat the
/// range image and the camera stand-in at both key points (kidnapped)? Without the
/// "comparable" cell (the page adds it).
fn claim_row(sequence: &str, label: &str, results: &[MethodResult]) -> Option<Vec<String>> {
    let get = |input: Input| {
        results
            .iter()
            .find(|r| r.label == label && r.input == input)
            .and_then(MethodResult::kidnapped_summary)
    };
    let (i, r, c) = (
        get(Input::Intensity)?,
        get(Input::Range)?,
        get(Input::Camera)?,
    );
    let yes = |b: bool| if b { "yes" } else { "**no**" }.to_string();
    Some(vec![
        sequence.to_string(),
        "simulated".into(),
        label.to_string(),
        format!(
            "{} / {} / {}",
            pct(Some(i.recall_at_100_precision)),
            pct(Some(r.recall_at_100_precision)),
            pct(Some(c.recall_at_100_precision))
        ),
        format!(
            "{} / {} / {}",
            pct(Some(i.precision_at_100_recall)),
            pct(Some(r.precision_at_100_recall)),
            pct(Some(c.precision_at_100_recall))
        ),
        yes(i.recall_at_100_precision >= r.recall_at_100_precision),
        yes(i.precision_at_100_recall >= r.precision_at_100_recall),
        yes(i.recall_at_100_precision >= c.recall_at_100_precision),
        yes(i.precision_at_100_recall >= c.precision_at_100_recall),
    ])
}
