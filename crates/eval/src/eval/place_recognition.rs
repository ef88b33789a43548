//! `cargo xtask eval place-recognition`: IBuILD loop closure and lidar place recognition
//! (Khan 2017, ch. 4) beside the DBoW2-style, Scan Context, planar polar-context, HOG, GIST
//! and SHOT baselines of `raypath-place-recognition`.
//!
//! * **Real 2-D** ([`real2d`]): the corrected CARMEN logs with loops (real scans; the
//!   SLAM-corrected poses are the ground truth). IBuILD and DBoW2-style on rasterised scans
//!   (the DBoW2-style vocabulary trained offline on the logs of the other fold), planar polar
//!   context, each also with the geometric check (`GeometricCheck`). Online loop closure and
//!   kidnapped mode; PR curves as PNG.
//! * **Real 3-D** ([`kitti_real`]): the 40 real KITTI frames and 5 real Ouster frames (KITTI sequences 00, 01, 04, 07, ten
//!   each) in one database, kidnapped: is each frame's best match a neighbour of the same
//!   sequence? Real intensity-image statistics beside simulated frames at the same poses.
//! * **Semi-synthetic KITTI** ([`semi_kitti`]): simulated HDL-64E scans with intensity along
//!   the real poses of `kitti-poles/00, 02, 05, 06`; the second pass seen at "night" by a
//!   camera stand-in and with scenery changes. Intensity vs range vs camera images, Scan
//!   Context, DBoW2-style.
//! * **Speed** ([`speed`]): time per query at 1 000 and 10 000 frames (real raw Intel log),
//!   beside Khan Table 4.3, on one thread.
//! * Khan Table 4.2 quoted (camera data sets not available: not comparable).
//!
//! `--quick` (CI): Intel and freiburg-079 (every 16th scan), the 40 real KITTI frames, one short
//! semi-synthetic stretch of sequence 00, speed at 1 000 frames, the first 600 Nordland frames. `PLACE_RECOGNITION_SECTIONS=1,4`
//! runs only the listed sections; `PLACE_RECOGNITION_STRIDE` sets the frame stride of the full
//! semi-synthetic drives (default 10).
//!
//! In stages: one unit per fold of section 1 (`real-2d/fold-0`, `real-2d/fold-1`: a fold's
//! logs share the DBoW2-style vocabulary trained on the other fold, so the fold is the unit and
//! trains it once), one for section 2 (`real-3d`: one database of all real frames), one for the
//! note on simulated scans under section 3's heading (`simulation-gap`, measured whichever
//! sections run), one per sequence of section 3 (`semi-kitti/00` …) and one for section 4
//! (`speed`), one for section 6 (`nordland`: run it alone with
//! `PLACE_RECOGNITION_SECTIONS=6 RAYPATH_EVAL_OUT=/tmp/out cargo xtask eval place-recognition`,
//! which writes its page under `/tmp/out` and leaves `docs/results` alone); the page ([`page`])
//! from their results alone, section 5 (quoted) in the report
//! stage. The folds and sequences hand over the cells of their table rows, pictures and JSON;
//! the single units of sections 2 and 4 hand over their section's text and JSON. A unit of a section left out by `PLACE_RECOGNITION_SECTIONS` measures nothing and
//! says so; its section reads "Skipped". The 3-D vocabulary ([`methods::kitti_vocabulary`],
//! seeded) is shared by sections 2 and 3: every unit that needs it trains it again (the same
//! bytes each time) rather than joining the sections into one unit — it is cheap beside a
//! section (quick: intensity images of 21 simulated scans along sequence 03, 2 s in a release
//! build, against 15 s for the quick semi-synthetic sequence; full: 81 scans), and the
//! sequences of section 3 stay units of their own.

mod camera;
mod data2d;
mod kitti_real;
mod methods;
mod nordland;
mod nordland_speed;
mod page;
mod plot;
mod real2d;
mod report;
mod runner;
mod semi_kitti;
mod speed;
mod truth;

use std::sync::Arc;

use anyhow::{Result, bail};
use raypath_place_recognition::BinaryVocabulary;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use self::runner::MethodResult;
use super::EvalContext;
use super::stages::{self, Staged, UnitResults};

const NAME: &str = "place-recognition";
/// Folder of the pictures under `docs/results/`.
const FIGURES: &str = "place-recognition";
/// Selects the sections to run (`1,4`); unset: all.
const SECTIONS_VAR: &str = "PLACE_RECOGNITION_SECTIONS";

/// The evaluation in stages (`--shard i/n` and `eval merge`).
pub const STAGED: Staged = Staged {
    name: NAME,
    units,
    run_unit,
    report,
};

/// The markdown and JSON of one section.
#[derive(Serialize, Deserialize)]
pub struct Section {
    markdown: String,
    json: Value,
    /// One-line findings for the summary at the top.
    summary: Vec<String>,
}

/// What one unit measured.
#[derive(Serialize, Deserialize)]
enum UnitResult {
    /// The unit's section is left out by `PLACE_RECOGNITION_SECTIONS`.
    Skipped,
    /// A fold of section 1.
    Real2d(real2d::FoldResult),
    /// Section 2 and the note on the 3-D vocabulary.
    Real3d {
        section: Section,
        vocabulary_note: String,
    },
    /// A sequence of section 3 and the note on the 3-D vocabulary.
    SemiKitti {
        sequence: semi_kitti::SequenceResult,
        vocabulary_note: String,
    },
    /// Section 4.
    Speed(Section),
    /// Section 6 (Nordland).
    Nordland(Section),
    /// The note on how far simulated scans are from real ones (under section 3's heading,
    /// measured whichever sections run).
    SimulationGap(String),
}

/// The units in report order: the folds of section 1, section 2, the note on simulated scans,
/// the sequences of section 3, section 4.
fn units(ctx: &EvalContext) -> Result<Vec<String>> {
    let mut units: Vec<String> = (0..real2d::FOLD_COUNT)
        .map(|fold| format!("real-2d/fold-{fold}"))
        .collect();
    units.extend(["real-3d".into(), SIMULATION_GAP.into()]);
    units.extend(
        semi_kitti::sequences(ctx.quick)
            .into_iter()
            .map(|s| format!("semi-kitti/{s}")),
    );
    units.push("speed".into());
    units.push("nordland".into());
    Ok(units)
}

/// The unit of the note on simulated scans.
const SIMULATION_GAP: &str = "simulation-gap";

/// The section (1–4) a unit belongs to; `None` for the note on simulated scans (on the page
/// whichever sections run).
fn section_of(unit: &str) -> Result<Option<&'static str>> {
    Ok(Some(match unit.split('/').next() {
        Some("real-2d") => "1",
        Some("real-3d") => "2",
        Some("semi-kitti") => "3",
        Some("speed") => "4",
        Some("nordland") => "6",
        Some(SIMULATION_GAP) => return Ok(None),
        _ => bail!("no unit {unit:?} in {NAME}"),
    }))
}

/// Whether `PLACE_RECOGNITION_SECTIONS` (unset: all) selects section `k`.
fn wanted(k: &str) -> bool {
    std::env::var(SECTIONS_VAR)
        .ok()
        .is_none_or(|v| v.split(',').any(|s| s.trim() == k))
}

/// Measures one unit (nothing when its section is not selected).
fn run_unit(ctx: &EvalContext, unit: &str) -> Result<Value> {
    let result = if !section_of(unit)?.is_none_or(wanted) {
        UnitResult::Skipped
    } else if unit == SIMULATION_GAP {
        UnitResult::SimulationGap(super::sim::gap_note(ctx)?)
    } else if let Some(fold) = unit.strip_prefix("real-2d/fold-") {
        UnitResult::Real2d(real2d::run_fold(ctx, fold.parse()?)?)
    } else if unit == "real-3d" {
        let (vocabulary, vocabulary_note) = vocabulary_3d(ctx)?;
        UnitResult::Real3d {
            section: kitti_real::run(ctx, vocabulary.as_ref())?,
            vocabulary_note,
        }
    } else if let Some(sequence) = unit.strip_prefix("semi-kitti/") {
        let (vocabulary, vocabulary_note) = vocabulary_3d(ctx)?;
        UnitResult::SemiKitti {
            sequence: semi_kitti::run_sequence(ctx, sequence, vocabulary.as_ref())?,
            vocabulary_note,
        }
    } else if unit == "nordland" {
        UnitResult::Nordland(nordland::run(ctx)?)
    } else {
        UnitResult::Speed(speed::run(ctx)?)
    };
    Ok(serde_json::to_value(result)?)
}

/// The DBoW2-style vocabulary of the 3-D sections and its note (timed on stderr).
fn vocabulary_3d(ctx: &EvalContext) -> Result<(Option<Arc<BinaryVocabulary>>, String)> {
    let started = std::time::Instant::now();
    let v = methods::kitti_vocabulary(ctx)?;
    eprintln!(
        "place-recognition: 3-D vocabulary in {:.0} s",
        started.elapsed().as_secs_f64()
    );
    Ok(v)
}

/// The page from every unit's result.
fn report(ctx: &EvalContext, results: &UnitResults) -> Result<super::EvalReport> {
    page::report(ctx, stages::decode::<UnitResult>(results)?)
}

/// "k of n" rows of an aim table whose cell `column` says yes.
fn count_yes(rows: &[Vec<String>], column: usize) -> String {
    let yes = rows
        .iter()
        .filter(|r| r.get(column).is_some_and(|c| c == "yes"))
        .count();
    let ties = rows
        .iter()
        .filter(|r| r.get(column).is_some_and(|c| c == "tie at 0"))
        .count();
    if ties > 0 {
        format!("{yes} of {} (ties at 0 %: {ties})", rows.len())
    } else {
        format!("{yes} of {}", rows.len())
    }
}

/// A row of an aim table: does `ours` reach `baseline`'s recall at 100 % precision, online and
/// kidnapped? Methods by [`MethodResult::key`].
fn aim_row(
    sequence: &str,
    data: &str,
    results: &[MethodResult],
    ours: &str,
    baseline: &str,
) -> Vec<String> {
    let find = |key: &str| results.iter().find(|r| r.key() == key);
    let mut row = vec![sequence.to_string(), data.to_string()];
    for online in [true, false] {
        let value = |r: Option<&MethodResult>| {
            r.and_then(|r| {
                if online {
                    r.online_summary()
                } else {
                    r.kidnapped_summary()
                }
            })
            .map(|s| s.recall_at_100_precision)
        };
        let (a, b) = (value(find(ours)), value(find(baseline)));
        row.push(report::pct(a));
        row.push(report::pct(b));
        row.push(match (a, b) {
            (Some(a), Some(b)) if a == 0.0 && b == 0.0 => "tie at 0".into(),
            (Some(a), Some(b)) if a >= b => "yes".into(),
            (Some(_), Some(_)) => "**no**".into(),
            _ => "—".into(),
        });
    }
    row
}
