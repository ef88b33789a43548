//! `cargo xtask eval place-recognition`: IBuILD loop closure and lidar place recognition
//! (Khan 2017, ch. 4) beside the DBoW2-style, Scan Context, planar polar-context, HOG, GIST
//! and SHOT baselines of `raypath-place-recognition`.
//!
//! * **Real 2-D** ([`real2d`]): the corrected CARMEN logs with loops (real scans; the
//!   SLAM-corrected poses are the ground truth). IBuILD and DBoW2-style on rasterised scans
//!   (the DBoW2-style vocabulary trained offline on the logs of the other fold), planar polar
//!   context. Online loop closure and kidnapped mode; PR curves as PNG.
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
//! semi-synthetic stretch of sequence 00, speed at 1 000 frames. `PLACE_RECOGNITION_SECTIONS=1,4`
//! runs only the listed sections; `PLACE_RECOGNITION_STRIDE` sets the frame stride of the full
//! semi-synthetic drives (default 10).

mod camera;
mod data2d;
mod kitti_real;
mod methods;
mod plot;
mod real2d;
mod report;
mod runner;
mod semi_kitti;
mod speed;
mod truth;

use std::fmt::Write;

use anyhow::Result;
use serde_json::{Value, json};

use self::runner::MethodResult;
use super::{EvalContext, EvalReport, comparable};
use crate::table::Table;

const NAME: &str = "place-recognition";
/// Folder of the pictures under `docs/results/`.
const FIGURES: &str = "place-recognition";

/// The markdown and JSON of one section.
pub struct Section {
    markdown: String,
    json: Value,
    /// One-line findings for the summary at the top.
    summary: Vec<String>,
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

/// Khan 2017, Table 4.2: recall at 100 % precision (%), Malaga6L and City Centre.
const TABLE_4_2: [(&str, &str, &str); 3] = [
    ("IBuILD", "78.13", "38.92"),
    ("Gálvez-López (DBoW2)", "74.75", "30.61"),
    ("FAB-MAP 2.0", "68.52", "38.77"),
];

fn thesis_table(md: &mut String) -> Result<Value> {
    let mut t = Table::new([
        "approach",
        "data",
        "Malaga6L R@100P % (thesis)",
        "City Centre R@100P % (thesis)",
        "ours",
        comparable::HEADER,
    ]);
    for (approach, malaga, city) in TABLE_4_2 {
        t.row([
            approach.to_owned(),
            "real (camera)".to_owned(),
            malaga.to_owned(),
            city.to_owned(),
            "not run".to_owned(),
            comparable::no(
                "real camera images of Malaga 2009 parking 6L and Oxford City Centre, not \
                 available here; none of our rows uses them (ours: lidar scans, other ground \
                 truth)",
            ),
        ]);
    }
    writeln!(
        md,
        "Khan 2017, Table 4.2 (maximum recall at 100 % precision, the Gálvez-López evaluation \
         script and hand-made loop intervals). The camera data sets (Malaga 2009 parking 6L, \
         Oxford City Centre) are **not available here**, so our numbers above (other data, \
         other ground truth) cannot be set beside these: not comparable.\n\n{}",
        t.to_markdown()?
    )?;
    Ok(json!(
        TABLE_4_2
            .iter()
            .map(|(a, m, c)| json!({ "approach": a, "malaga6l": m, "city_centre": c, "comparable": false }))
            .collect::<Vec<_>>()
    ))
}

/// Runs the evaluation.
pub fn run(ctx: &EvalContext) -> Result<EvalReport> {
    let mut md = String::new();
    writeln!(
        md,
        "Khan (2017) ch. 4: IBuILD (incremental binary bag of words, §4.4) and lidar place \
         recognition with intensity images (§4.5), beside DBoW2-style, Scan Context, planar \
         polar context, HOG, GIST and SHOT. Every table says whether its data are **real** or \
         **simulated**. Seeds fixed.{}\n",
        if ctx.quick {
            " **Quick run**: Intel and freiburg-079 (every 16th scan) only, the 40 real KITTI \
             frames, one short semi-synthetic stretch of sequence 00, speed at 1 000 frames."
        } else {
            ""
        }
    )?;
    let only: Option<Vec<String>> = std::env::var("PLACE_RECOGNITION_SECTIONS")
        .ok()
        .map(|v| v.split(',').map(|s| s.trim().to_owned()).collect());
    let wanted = |k: &str| only.as_ref().is_none_or(|o| o.iter().any(|x| x == k));
    let skipped = || Section {
        markdown: "Skipped (`PLACE_RECOGNITION_SECTIONS`).\n\n".into(),
        json: Value::Null,
        summary: Vec::new(),
    };
    writeln!(md, "## 1. Real 2-D revisits (corrected CARMEN logs)\n")?;
    let s1 = if wanted("1") {
        real2d::run(ctx)?
    } else {
        skipped()
    };
    md.push_str(&s1.markdown);
    let (vocabulary, vocabulary_note) = if wanted("2") || wanted("3") {
        let started = std::time::Instant::now();
        let v = methods::kitti_vocabulary(ctx)?;
        eprintln!(
            "place-recognition: 3-D vocabulary in {:.0} s",
            started.elapsed().as_secs_f64()
        );
        v
    } else {
        (None, String::new())
    };
    writeln!(
        md,
        "## 2. Real 3-D: 40 real KITTI frames and 5 real Ouster frames\n"
    )?;
    let s2 = if wanted("2") {
        kitti_real::run(ctx, vocabulary.as_ref())?
    } else {
        skipped()
    };
    md.push_str(&s2.markdown);
    if !vocabulary_note.is_empty() {
        writeln!(md, "* {vocabulary_note}\n")?;
    }
    writeln!(md, "## 3. Semi-synthetic KITTI with real trajectories\n")?;
    writeln!(md, "{}", super::sim::gap_note(ctx)?)?;
    let s3 = if wanted("3") {
        semi_kitti::run(ctx, vocabulary.as_ref())?
    } else {
        skipped()
    };
    md.push_str(&s3.markdown);
    writeln!(md, "## 4. Speed\n")?;
    let s4 = if wanted("4") {
        speed::run(ctx)?
    } else {
        skipped()
    };
    md.push_str(&s4.markdown);
    writeln!(md, "## 5. Khan Table 4.2 (camera data sets)\n")?;
    let s5 = thesis_table(&mut md)?;
    let summary: Vec<String> = [&s1, &s2, &s3, &s4]
        .iter()
        .flat_map(|s| s.summary.iter().cloned())
        .collect();
    let mut head = String::from("**Summary** (this run):\n\n");
    for line in &summary {
        head.push_str(&format!("* {line}\n"));
    }
    head.push('\n');
    if let Some(at) = md.find("## 1.") {
        md.insert_str(at, &head);
    }
    Ok(EvalReport {
        name: NAME,
        title: "Place recognition: IBuILD, lidar intensity images and baselines (Khan ch. 4)"
            .into(),
        markdown: md,
        json: json!({
            "real_2d": s1.json,
            "real_3d": s2.json,
            "semi_kitti": s3.json,
            "vocabulary_3d": vocabulary_note,
            "speed": s4.json,
            "thesis_table_4_2": s5,
            "summary": summary,
        }),
        headline: {
            // Real sections first (3-D, then 2-D), then speed; the semi-synthetic lines stay
            // on the page.
            let lines: Vec<&String> = [&s2, &s1, &s4]
                .iter()
                .flat_map(|s| s.summary.iter())
                .collect();
            (!lines.is_empty()).then(|| {
                lines
                    .iter()
                    .map(|l| l.trim_end_matches('.'))
                    .collect::<Vec<_>>()
                    .join("; ")
                    + "."
            })
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_4_2_renders_and_says_why_not_comparable() {
        let mut md = String::new();
        let json = thesis_table(&mut md).expect("table renders");
        assert_eq!(json.as_array().map(Vec::len), Some(TABLE_4_2.len()));
        let rows: Vec<&str> = md.lines().filter(|l| l.starts_with("| IBuILD")).collect();
        assert_eq!(rows.len(), 1);
        assert!(
            rows[0].contains("| no — real camera images of Malaga"),
            "{}",
            rows[0]
        );
    }
}
