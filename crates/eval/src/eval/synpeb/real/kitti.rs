//! The KITTI tables: per sequence and held out, and the classes the planes cover.

use std::collections::BTreeSet;

use anyhow::Result;
use raypath_io::kitti::{KittiSequence, semantic_class_name};
use serde_json::{Map, Value, json};

use super::data::{self, Frame};
use super::score::{FrameScore, Method, Pooled};
use super::{NOT_LIKE_FOR_LIKE, SEQUENCES, key, methods, pct, run_methods};
use crate::eval::EvalContext;
use crate::table::{Table, fmt_num};

/// Reads the KITTI frames of one sequence (10, or 2 with `--quick`); `None` when absent.
pub fn frames(ctx: &EvalContext, seq: &str) -> Result<Option<Vec<Frame>>> {
    let dir = ctx.data(&format!("kitti/sequences/{seq}"));
    if !dir.join("velodyne").is_dir() {
        return Ok(None);
    }
    let sequence = KittiSequence::open(&dir)?;
    let count = if ctx.quick { 2 } else { 10 };
    let frames = sequence
        .scan_files
        .iter()
        .take(count)
        .map(|f| data::kitti_frame(&sequence, f.frame))
        .collect::<Result<Vec<_>>>()?;
    Ok(Some(frames))
}

fn row(t: &mut Table, data: &str, method: &Method, p: &Pooled) {
    t.row([
        data.to_owned(),
        method.name().to_owned(),
        p.frames.to_string(),
        fmt_num(p.planes, 1),
        pct(p.recall),
        pct(p.precision),
        pct(p.precision_lenient),
        pct(p.f1()),
        pct(p.purity),
        pct(p.on_plane),
        fmt_num(p.rmse_mm, 1),
        fmt_num(p.median_secs, 2),
        NOT_LIKE_FOR_LIKE.into(),
    ]);
}

/// The table of the plane pixels' classes (classes with at least 1 % under some method).
fn class_table(pooled: &[(Method, Pooled)]) -> Table {
    let mut header = vec!["class of the plane pixels".to_owned()];
    header.extend(pooled.iter().map(|(m, _)| format!("{} [%]", m.name())));
    let mut table = Table::new(header);
    let classes: BTreeSet<u16> = pooled
        .iter()
        .flat_map(|(_, p)| p.by_class.iter())
        .filter(|(_, share)| **share >= 0.01)
        .map(|(c, _)| *c)
        .collect();
    for c in classes {
        let name = semantic_class_name(c).unwrap_or("?");
        let mut cells = vec![format!("{name} ({c})")];
        cells.extend(
            pooled
                .iter()
                .map(|(_, p)| pct(p.by_class.get(&c).copied().unwrap_or(0.0))),
        );
        table.row(cells);
    }
    table
}

/// The KITTI section: markdown, JSON and the frames of the tuning sequence (for the grid).
pub fn run(ctx: &EvalContext) -> Result<(String, Value, Vec<Frame>)> {
    let mut table = Table::new([
        "data (real)",
        "method",
        "frames",
        "planes/frame",
        "planar recall [%]",
        "plane precision [%]",
        "precision, planar-ish counted [%]",
        "F1 [%]",
        "class purity [%]",
        "returns on planes [%]",
        "RMSE [mm]",
        "time/frame [s]",
        "like for like with Table 11.1",
    ]);
    let sequences: &[&str] = if ctx.quick {
        &SEQUENCES[..1]
    } else {
        &SEQUENCES
    };
    let mut results = Map::new();
    let mut held_out: Vec<Vec<FrameScore>> = vec![Vec::new(); methods().len()];
    let mut tuning_scores: Vec<Vec<FrameScore>> = vec![Vec::new(); methods().len()];
    let (mut kept, mut source) = (0usize, 0usize);
    let (mut missing, mut tuning_frames) = (Vec::new(), Vec::new());
    for &seq in sequences {
        let Some(frames) = frames(ctx, seq)? else {
            missing.push(seq);
            continue;
        };
        kept += frames.iter().map(|f| f.cloud.num_valid()).sum::<usize>();
        source += frames.iter().map(|f| f.source_points).sum::<usize>();
        let runs = run_methods(ctx, &frames, &format!("KITTI {seq}"))?;
        let tuning = seq == SEQUENCES[0];
        let tag = if tuning {
            format!("KITTI {seq} (tuning sequence)")
        } else {
            format!("KITTI {seq}")
        };
        for (k, (method, scores)) in runs.into_iter().enumerate() {
            let pooled = Pooled::of(&scores);
            row(&mut table, &tag, &method, &pooled);
            results.insert(format!("{}_kitti_{seq}", key(&method)), pooled.json());
            if tuning {
                tuning_scores[k] = scores;
            } else {
                held_out[k].extend(scores);
            }
        }
        if tuning {
            tuning_frames = frames;
        }
    }
    let (breakdown, which) = if held_out[0].is_empty() {
        (tuning_scores, "the tuning sequence 00")
    } else {
        for (method, scores) in methods().iter().zip(&held_out) {
            let pooled = Pooled::of(scores);
            row(&mut table, "KITTI 01 + 04 + 07 (held out)", method, &pooled);
            results.insert(format!("{}_kitti_held_out", key(method)), pooled.json());
        }
        (held_out, "the held-out sequences 01, 04, 07")
    };
    let pooled: Vec<(Method, Pooled)> = methods()
        .into_iter()
        .zip(breakdown.iter().map(|s| Pooled::of(s)))
        .collect();
    let classes = class_table(&pooled);
    let note = if missing.is_empty() {
        String::new()
    } else {
        format!(
            "KITTI sequences absent under RAYPATH_DATA (`kitti/sequences/…`): {}.\n\n",
            missing.join(", ")
        )
    };
    let markdown = format!(
        "{}\n{note}The range images hold {kept} of the {source} returns of the files ({:.1} %; \
         the rest share a pixel with a nearer return of the same laser).\n\n\
         Where the plane pixels lie, by SemanticKITTI class, on {which} (classes with at least \
         1 % under some method):\n\n{}",
        table.to_markdown()?,
        100.0 * kept as f64 / source.max(1) as f64,
        classes.to_markdown()?,
    );
    results.insert(
        "projection".into(),
        json!({"returns_in_images": kept, "returns_in_files": source}),
    );
    Ok((markdown, Value::Object(results), tuning_frames))
}
