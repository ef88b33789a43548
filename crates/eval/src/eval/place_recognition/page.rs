//! The page of the evaluation from the units' results: the five sections in order, the summary
//! above them, the headline and the JSON.

use std::fmt::Write;

use anyhow::{Context, Result};
use serde_json::{Value, json};

use super::{NAME, Section, UnitResult, real2d, semi_kitti};
use crate::eval::{EvalContext, EvalReport, comparable};
use crate::table::Table;

const TITLE: &str = "Place recognition: IBuILD, lidar intensity images and baselines (Khan ch. 4)";

/// Sections 1–4 as measured (or skipped) and the note on the 3-D vocabulary.
struct Sections {
    real_2d: Section,
    real_3d: Section,
    semi_kitti: Section,
    speed: Section,
    nordland: Section,
    vocabulary_note: String,
    /// How far simulated scans are from real ones (under section 3's heading).
    simulation_gap: String,
}

/// The text of a section left out by `PLACE_RECOGNITION_SECTIONS`.
fn skipped() -> Section {
    Section {
        markdown: "Skipped (`PLACE_RECOGNITION_SECTIONS`).\n\n".into(),
        json: Value::Null,
        summary: Vec::new(),
    }
}

/// Sorts the units' results into the sections; a section without measured units is skipped.
fn sections(quick: bool, units: Vec<UnitResult>) -> Result<Sections> {
    let (mut folds, mut sequences) = (Vec::new(), Vec::new());
    let (mut real_3d, mut speed, mut simulation_gap) = (None, None, None);
    let mut nordland = None;
    let mut notes = Vec::new();
    for unit in units {
        match unit {
            UnitResult::Skipped => {}
            UnitResult::Real2d(fold) => folds.push(fold),
            UnitResult::Real3d {
                section,
                vocabulary_note,
            } => {
                real_3d = Some(section);
                notes.push(vocabulary_note);
            }
            UnitResult::SemiKitti {
                sequence,
                vocabulary_note,
            } => {
                sequences.push(sequence);
                notes.push(vocabulary_note);
            }
            UnitResult::Speed(section) => speed = Some(section),
            UnitResult::Nordland(section) => nordland = Some(section),
            UnitResult::SimulationGap(note) => simulation_gap = Some(note),
        }
    }
    Ok(Sections {
        real_2d: if folds.is_empty() {
            skipped()
        } else {
            real2d::section(quick, &folds)?
        },
        real_3d: real_3d.unwrap_or_else(skipped),
        semi_kitti: if sequences.is_empty() {
            skipped()
        } else {
            semi_kitti::section(quick, &sequences)?
        },
        speed: speed.unwrap_or_else(skipped),
        nordland: nordland.unwrap_or_else(skipped),
        vocabulary_note: notes
            .into_iter()
            .find(|n| !n.is_empty())
            .unwrap_or_default(),
        simulation_gap: simulation_gap.context("no result of the simulation-gap unit")?,
    })
}

/// The page from every unit's result (in the order of the units).
pub(super) fn report(ctx: &EvalContext, units: Vec<UnitResult>) -> Result<EvalReport> {
    let s = sections(ctx.quick, units)?;
    let mut md = String::new();
    write_intro(&mut md, ctx.quick)?;
    let summary: Vec<String> = [&s.real_2d, &s.real_3d, &s.nordland, &s.semi_kitti, &s.speed]
        .iter()
        .flat_map(|s| s.summary.iter().cloned())
        .collect();
    md.push_str("**Summary** (this run):\n\n");
    for line in &summary {
        writeln!(md, "* {line}")?;
    }
    md.push('\n');
    writeln!(md, "## 1. Real 2-D revisits (corrected CARMEN logs)\n")?;
    md.push_str(&s.real_2d.markdown);
    writeln!(
        md,
        "## 2. Real 3-D, no revisits: a sanity check (40 real KITTI frames, 5 real Ouster \
         frames)\n\nThese frames are consecutive: no place is visited twice, so \"best match in \
         the same source\" only says that a descriptor finds a neighbouring frame. It is not a \
         place-recognition result and stays out of the headline until real 3-D frames with \
         revisits exist.\n"
    )?;
    md.push_str(&s.real_3d.markdown);
    if !s.vocabulary_note.is_empty() {
        writeln!(md, "* {}\n", s.vocabulary_note)?;
    }
    writeln!(md, "## 3. Semi-synthetic KITTI with real trajectories\n")?;
    writeln!(md, "{}", s.simulation_gap)?;
    md.push_str(&s.semi_kitti.markdown);
    writeln!(md, "## 4. Speed\n")?;
    md.push_str(&s.speed.markdown);
    writeln!(md, "## 5. Khan Table 4.2 (camera data sets)\n")?;
    let thesis = thesis_table(&mut md)?;
    writeln!(md, "## 6. Real camera seasons (Nordland)\n")?;
    md.push_str(&s.nordland.markdown);
    Ok(EvalReport {
        name: NAME,
        title: TITLE.into(),
        markdown: md,
        headline: headline(&s),
        json: json!({
            "real_2d": s.real_2d.json,
            "real_3d": s.real_3d.json,
            "semi_kitti": s.semi_kitti.json,
            "vocabulary_3d": s.vocabulary_note,
            "speed": s.speed.json,
            "thesis_table_4_2": thesis,
            "nordland": s.nordland.json,
            "summary": summary,
        }),
    })
}

/// What the page compares and what a quick run leaves out.
fn write_intro(md: &mut String, quick: bool) -> Result<()> {
    writeln!(
        md,
        "Khan (2017) ch. 4: IBuILD (incremental binary bag of words, §4.4) and lidar place \
         recognition with intensity images (§4.5), beside DBoW2-style, Scan Context, planar \
         polar context, HOG, GIST and SHOT. Every table says whether its data are **real** or \
         **simulated**. Seeds fixed.{}\n",
        if quick {
            " **Quick run**: Intel and freiburg-079 (every 16th scan) only, the 40 real KITTI \
             frames, one short semi-synthetic stretch of sequence 00, speed at 1 000 frames."
        } else {
            ""
        }
    )?;
    Ok(())
}

/// The headline: the real revisits first (Nordland, then the 2-D logs), then speed; the 3-D
/// sanity check (consecutive frames, no revisit) and the semi-synthetic lines stay on the page.
fn headline(s: &Sections) -> Option<String> {
    let lines: Vec<&String> = [&s.nordland, &s.real_2d, &s.speed]
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
}

/// Khan 2017, Table 4.2: recall at 100 % precision (%), Malaga6L and City Centre.
const TABLE_4_2: [(&str, &str, &str); 3] = [
    ("IBuILD", "78.13", "38.92"),
    ("Gálvez-López (DBoW2)", "74.75", "30.61"),
    ("FAB-MAP 2.0", "68.52", "38.77"),
];

/// Section 5: Table 4.2 quoted, not comparable; returns its JSON.
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
         other ground truth) cannot be set beside these: not comparable. The real camera rows \
         of section 6 (Nordland, other data) carry these figures beside IBuILD and DBoW2-style, \
         also not like for like.\n\n{}",
        t.to_markdown()?
    )?;
    Ok(json!(
        TABLE_4_2
            .iter()
            .map(|(a, m, c)| json!({ "approach": a, "malaga6l": m, "city_centre": c, "comparable": false }))
            .collect::<Vec<_>>()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::place_recognition::real2d::{FoldResult, LogOutcome, LogRows};
    use crate::eval::place_recognition::semi_kitti::{SequenceResult, SequenceRows};

    /// An aim row whose "holds" cells say `online` and `kidnapped`.
    fn aim(name: &str, online: &str, kidnapped: &str) -> Vec<String> {
        [
            name, "real", "50.0", "40.0", online, "30.0", "20.0", kidnapped,
        ]
        .map(str::to_owned)
        .to_vec()
    }

    fn log(name: &str, online: &str) -> LogOutcome {
        let cells = |n: usize| (0..n).map(|k| format!("{name}-{k}")).collect::<Vec<_>>();
        LogOutcome::Done(Box::new(LogRows {
            name: name.to_owned(),
            results: vec![cells(15)],
            sweep: vec![cells(8)],
            aim: aim(name, online, "yes"),
            symmetric_aim: aim(&format!("{name} (sym)"), "yes", "yes"),
            checked_aims: Vec::new(),
            shape_sweep: Vec::new(),
            pictures: format!("![{name}](x.png)\n\n"),
            json: json!({ "log": name }),
        }))
    }

    fn section(summary: &str) -> Section {
        Section {
            markdown: format!("Text of {summary}\n\n"),
            json: json!({ "of": summary }),
            summary: vec![summary.to_owned()],
        }
    }

    fn sequence(name: &str) -> SequenceResult {
        let cells = |n: usize| (0..n).map(|k| format!("s{name}-{k}")).collect::<Vec<_>>();
        SequenceResult {
            sequence: name.to_owned(),
            rows: (name == "00").then(|| {
                Box::new(SequenceRows {
                    info: cells(11),
                    results: vec![cells(12)],
                    sweep: vec![cells(8)],
                    claims: vec![
                        [
                            "00",
                            "simulated",
                            "HOG",
                            "a",
                            "b",
                            "yes",
                            "**no**",
                            "yes",
                            "yes",
                        ]
                        .map(str::to_owned)
                        .to_vec(),
                    ],
                    aim: aim("00", "yes", "**no**"),
                    symmetric_aim: aim("00 (sym)", "yes", "yes"),
                    pictures: String::new(),
                    json: json!({ "sequence": name }),
                })
            }),
        }
    }

    /// The units of a full run in which section 4 is left out, `freiburg-079` and
    /// `kitti-poles/02` are missing: logs in the order of `LOGS` across the folds, the notes,
    /// the skipped section, section 6 after the thesis table, the summary, headline and JSON
    /// keys.
    #[test]
    fn report_from_known_units() {
        let units = [
            UnitResult::Real2d(FoldResult {
                vocabulary_note: "Vocabulary zero.".into(),
                logs: vec![log("intel", "yes"), log("csail", "**no**")],
            }),
            UnitResult::Real2d(FoldResult {
                vocabulary_note: "Vocabulary one.".into(),
                logs: vec![
                    LogOutcome::Missing {
                        name: "freiburg-079".into(),
                        path: "carmen/fr079.log".into(),
                    },
                    log("aces", "yes"),
                ],
            }),
            UnitResult::Real3d {
                section: section("Real 3-D: 9/10."),
                vocabulary_note: "Vocabulary 3-D.".into(),
            },
            UnitResult::SimulationGap("GAP NOTE\n".into()),
            UnitResult::SemiKitti {
                sequence: sequence("00"),
                vocabulary_note: "Vocabulary 3-D.".into(),
            },
            UnitResult::SemiKitti {
                sequence: sequence("02"),
                vocabulary_note: "Vocabulary 3-D.".into(),
            },
            UnitResult::Skipped,
            UnitResult::Nordland(section("Nordland: 7/10.")),
        ];
        let results: Vec<(String, Value)> = units
            .iter()
            .map(|u| ("unit".to_owned(), serde_json::to_value(u).unwrap()))
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let ctx = EvalContext {
            quick: false,
            ..EvalContext::scratch(dir.path())
        };
        let page = super::super::report(&ctx, &results).unwrap();
        let md = &page.markdown;
        let rows: Vec<&str> = md
            .lines()
            .filter(|l| l.starts_with("| intel-0") || l.starts_with("| csail-0"))
            .chain(md.lines().filter(|l| l.starts_with("| aces-0")))
            .collect();
        assert_eq!(rows.len(), 6, "{md}");
        let at = |text: &str| md.find(text).unwrap_or_else(|| panic!("{text:?} in {md}"));
        assert!(at("| intel-0 ") < at("| csail-0 ") && at("| csail-0 ") < at("| aces-0 "));
        assert!(at("* Vocabulary zero.\n* Vocabulary one.\n* `carmen/fr079.log` missing") > 0);
        assert!(
            at("* Real 2-D (CARMEN): IBuILD recall at 100 % precision ≥ DBoW2-style on 2 of 3") > 0
        );
        assert!(at("| 00 (sym) ") > at("| 00 "));
        assert!(at("Text of Real 3-D: 9/10.\n\n* Vocabulary 3-D.\n") < at("## 3."));
        assert!(at("## 3. Semi-synthetic KITTI with real trajectories\n\nGAP NOTE\n") > 0);
        assert!(at("* `kitti-poles/02` not found: sequence skipped.") < at("## 4."));
        assert!(at("## 4. Speed\n\nSkipped (`PLACE_RECOGNITION_SECTIONS`).") < at("## 5."));
        assert!(at("| no — semi-synthetic") > 0);
        assert!(
            at("## 6. Real camera seasons (Nordland)\n\nText of Nordland: 7/10.") > at("## 5.")
        );
        assert_eq!(
            page.headline.as_deref(),
            Some(
                "Nordland: 7/10; Real 2-D (CARMEN): IBuILD recall at 100 % precision ≥ \
                 DBoW2-style on 2 of 3 logs online and 3 of 3 kidnapped."
            )
        );
        let mut keys: Vec<&String> = page.json.as_object().unwrap().keys().collect();
        keys.sort();
        assert_eq!(
            keys,
            [
                "nordland",
                "real_2d",
                "real_3d",
                "semi_kitti",
                "speed",
                "summary",
                "thesis_table_4_2",
                "vocabulary_3d"
            ]
        );
        assert_eq!(page.json["real_2d"]["logs"].as_array().unwrap().len(), 3);
        assert_eq!(page.json["real_2d"]["logs"][1]["log"], "csail");
        assert_eq!(page.json["semi_kitti"]["missing"], json!(["02"]));
        assert!(page.json["speed"].is_null());
        assert_eq!(page.json["vocabulary_3d"], "Vocabulary 3-D.");
        assert_eq!(page.json["summary"].as_array().unwrap().len(), 5);
    }

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
