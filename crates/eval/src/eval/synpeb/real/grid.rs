//! Parameter grids of the three extractors on the KITTI tuning sequence (00), scored by the
//! F1 of planar recall and lenient plane precision ([`Pooled::f1`]).

use anyhow::Result;
use serde_json::{Value, json};

use super::data::Frame;
use super::pct;
use super::score::{Method, Pooled, score};
use crate::eval::EvalContext;
use crate::eval::planes::{msac_grid, peac_grid, ppe_grid};
use crate::table::{Table, fmt_num};

/// Cells shown per method (the best by F1).
pub const SHOWN: usize = 5;

/// The grids the full run recomputes on the tuning frames (they contain the chosen cells).
fn grids() -> [Vec<(Method, String)>; 3] {
    [
        ppe_grid(&[0.10, 0.15, 0.20, 0.25], &[2.0, 4.0], &[30, 50, 100], 3),
        peac_grid(&[3, 4], &[0.03, 0.04, 0.05], &[0.15, 0.30], &[50, 100, 200]),
        msac_grid(&[0.05, 0.10, 0.20], &[0.1, 0.2, 0.3], &[10]),
    ]
}

/// Recomputes the grids on `frames` (KITTI 00) and shows, per method, the best cells by F1
/// and the rank of the parameters the tables use (`chosen`, in the order PPE, PEAC, MSAC).
pub fn tuning(ctx: &EvalContext, frames: &[Frame], chosen: &[Method]) -> Result<(String, Value)> {
    let mut table = Table::new([
        "method",
        "cell",
        "F1 [%]",
        "planar recall [%]",
        "precision, planar-ish counted [%]",
        "class purity [%]",
        "planes/frame",
        "RMSE [mm]",
        "used",
    ]);
    let mut notes = Vec::new();
    let mut out = Vec::new();
    for (methods, used) in grids().into_iter().zip(chosen) {
        let bar = ctx.progress(methods.len() as u64, &format!("{} grid", used.name()));
        let mut cells = Vec::new();
        for m in methods {
            cells.extend(evaluate(frames, vec![m])?);
            bar.inc(1);
        }
        bar.finish_and_clear();
        cells.sort_by(|a, b| b.pooled.f1().total_cmp(&a.pooled.f1()));
        let rank = cells.iter().position(|c| c.method == *used);
        for (i, c) in cells.iter().enumerate() {
            if i >= SHOWN && Some(i) != rank {
                continue;
            }
            let p = &c.pooled;
            table.row([
                used.name().to_owned(),
                c.label.clone(),
                pct(p.f1()),
                pct(p.recall),
                pct(p.precision_lenient),
                pct(p.purity),
                fmt_num(p.planes, 1),
                fmt_num(p.rmse_mm, 1),
                if Some(i) == rank { "**yes**" } else { "" }.to_owned(),
            ]);
            out.push(json!({"method": used.name(), "cell": c.label, "f1": p.f1(),
                "used": Some(i) == rank}));
        }
        let top: Vec<f64> = cells.iter().take(SHOWN).map(|c| c.pooled.f1()).collect();
        let spread = format!(
            "the best {} cells span F1 {}–{} %",
            top.len(),
            pct(top.last().copied().unwrap_or(f64::NAN)),
            pct(top.first().copied().unwrap_or(f64::NAN))
        );
        notes.push(match rank {
            Some(r) => format!(
                "{}: rank {} of {} ({spread})",
                used.name(),
                r + 1,
                cells.len()
            ),
            None => format!("{}: not in the grid ({spread})", used.name()),
        });
    }
    let markdown = format!(
        "{}
Rank of the parameters used in their grid: {}.
",
        table.to_markdown()?,
        notes.join("; ")
    );
    Ok((markdown, json!(out)))
}

/// One grid cell: its parameters as text and the pooled scores on the tuning frames.
pub struct Cell {
    /// The method and parameters.
    pub method: Method,
    /// The varied parameters, e.g. `√e 0.20, d 2.0, min 50`.
    pub label: String,
    /// Scores on the tuning frames.
    pub pooled: Pooled,
}

/// Runs `methods` on `frames`.
pub fn evaluate(frames: &[Frame], methods: Vec<(Method, String)>) -> Result<Vec<Cell>> {
    let mut cells = Vec::new();
    for (method, label) in methods {
        let mut scores = Vec::new();
        for frame in frames {
            let (seg, secs) = method.run(&frame.cloud, &frame.name)?;
            scores.push(score(frame, &seg, secs));
        }
        cells.push(Cell {
            method,
            label,
            pooled: Pooled::of(&scores),
        });
    }
    Ok(cells)
}
