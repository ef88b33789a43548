//! Result tables and figures shared by the sections.

use std::path::Path;

use anyhow::Result;

use super::plot::{Curve, legend, write_pr_png};
use super::runner::{Input, MethodResult};
use crate::table::{Table, fmt_num};

/// Percent with one decimal, "—" when missing.
pub fn pct(v: Option<f64>) -> String {
    v.map_or_else(|| "—".to_string(), |v| fmt_num(100.0 * v, 1))
}

/// The header of a per-method results table (after the leading sequence columns).
pub const RESULT_HEADERS: [&str; 10] = [
    "method",
    "input",
    "online R@100P %",
    "online P@100R %",
    "online max F1",
    "kidnapped R@100P %",
    "kidnapped P@100R %",
    "kidnapped max F1",
    "ms/query",
    "note",
];

/// The result cells of one method (see [`RESULT_HEADERS`]).
pub fn result_cells(r: &MethodResult) -> Vec<String> {
    let on = r.online_summary();
    let kid = r.kidnapped_summary();
    vec![
        r.label.clone(),
        r.input.name().to_string(),
        pct(on.map(|s| s.recall_at_100_precision)),
        pct(on.map(|s| s.precision_at_100_recall)),
        on.map_or("—".into(), |s| fmt_num(s.max_f1, 3)),
        pct(kid.map(|s| s.recall_at_100_precision)),
        pct(kid.map(|s| s.precision_at_100_recall)),
        kid.map_or("—".into(), |s| fmt_num(s.max_f1, 3)),
        fmt_num(r.ms_per_query, 2),
        r.error.clone().unwrap_or_default(),
    ]
}

/// A results table whose rows start with `leading` columns.
pub fn results_table(leading: &[&str]) -> Table {
    Table::new(leading.iter().copied().chain(RESULT_HEADERS))
}

/// Writes the online and kidnapped PR curves of `results` as `<stem>-online.png` and
/// `<stem>-kidnapped.png` in `dir`; returns the markdown (pictures and legend).
pub fn pr_figures(
    dir: &Path,
    folder: &str,
    stem: &str,
    results: &[MethodResult],
) -> Result<String> {
    let mut md = String::new();
    for (mode, online) in [("online", true), ("kidnapped", false)] {
        let pick = |r: &MethodResult| {
            if online {
                r.online.clone()
            } else {
                r.kidnapped.clone()
            }
        };
        let curves: Vec<Curve> = results
            .iter()
            .filter(|r| !is_sweep(r))
            .filter_map(|r| {
                pick(r).map(|c| Curve {
                    label: format!("{} ({})", r.label, r.input.name()),
                    points: c.points.iter().map(|p| (p.recall, p.precision)).collect(),
                })
            })
            .collect();
        if curves.is_empty() {
            continue;
        }
        let file = format!("{stem}-{mode}.png");
        write_pr_png(&dir.join(&file), &curves)?;
        md.push_str(&format!(
            "![{stem} {mode}]({folder}/{file}) {mode}: {}\n\n",
            legend(&curves)
        ));
    }
    Ok(md)
}

/// True for the extra runs of the δ sweep (kept out of the main tables).
pub fn is_sweep(r: &MethodResult) -> bool {
    r.label.contains(" δ=")
}

/// The header of the δ-sweep table (after the leading sequence columns).
pub const SWEEP_HEADERS: [&str; 6] = [
    "δ [bits]",
    "thesis-style point: precision %",
    "thesis-style point: recall %",
    "online R@100P % (score sweep)",
    "kidnapped R@100P %",
    "kidnapped max F1",
];

/// Rows of the δ sweep of IBuILD on one sequence (δ ascending): the thesis' operating point of
/// each δ (every loop the temporal-consistency test accepts, no score threshold: the online
/// curve's lowest threshold) and the summaries.
pub fn sweep_rows(leading: &[String], results: &[MethodResult], input: Input) -> Vec<Vec<String>> {
    let mut runs: Vec<(u32, &MethodResult)> = results
        .iter()
        .filter(|r| r.input == input && (r.label == "IBuILD" || r.label.starts_with("IBuILD δ=")))
        .map(|r| {
            let delta = r
                .label
                .strip_prefix("IBuILD δ=")
                .and_then(|d| d.parse().ok())
                .unwrap_or(super::methods::DEFAULT_DELTA);
            (delta, r)
        })
        .collect();
    runs.sort_by_key(|(d, _)| *d);
    runs.into_iter()
        .map(|(delta, r)| {
            let last = r.online.as_ref().and_then(|c| c.points.last());
            let on = r.online_summary();
            let kid = r.kidnapped_summary();
            leading
                .iter()
                .cloned()
                .chain([
                    delta.to_string(),
                    pct(last.map(|p| p.precision)),
                    pct(last.map(|p| p.recall)),
                    pct(on.map(|s| s.recall_at_100_precision)),
                    pct(kid.map(|s| s.recall_at_100_precision)),
                    kid.map_or("—".into(), |s| fmt_num(s.max_f1, 3)),
                ])
                .collect()
        })
        .collect()
}
