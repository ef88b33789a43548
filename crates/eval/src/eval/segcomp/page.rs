//! The report stage of `eval segcomp`: the page, its JSON and its headline from the results
//! of the units `real` and `standin` alone.

use anyhow::{Context, Result};
use serde_json::Value;

use super::protocol::{self, HOOVER_COLUMNS, Outcome};
use super::standin::{self, StandinUnit};
use super::{NAME, REAL, RealMeasured, RealUnit, STANDIN};
use crate::eval::stages::UnitResults;
use crate::eval::{EvalContext, EvalReport, comparable};
use crate::table::Table;

const TITLE: &str = "PPE, PEAC-style and MSAC on SegComp Perceptron and a simulated stand-in (Schaefer 2020, Table 11.1)";

/// Cells shown per method in the grid tables.
const SHOWN: usize = 3;

/// Why the stand-in rows are not the thesis' figures.
const NOT_SEGCOMP: &str = "simulated stand-in, not the SegComp images";

/// Where to get the real images.
const HOW_TO_GET: &str = "SegComp is not redistributed with raypath. Download the Perceptron \
collection of the USF range segmentation comparison (Hoover et al. 1996; \
`http://marathon.csee.usf.edu/range/seg-comp/SegComp.html`, archives `PERC-TRAIN-IMAGES.tar` / \
`PERC-TEST-IMAGES.tar` of `compress`-ed files), untar them into \
`$RAYPATH_DATA/segcomp/perceptron/train/` and `$RAYPATH_DATA/segcomp/perceptron/test/` (as \
`datasets/manifest.json` says; files directly in `$RAYPATH_DATA/segcomp/` are found too) so that \
`perc.test.0[.Z]` lies beside `perc.test.0.gt-seg[.Z]` and `perc.test.0.gt-ang[.Z]`, and rerun \
`cargo xtask eval segcomp`.";

/// The SegComp rows of Table 11.1 (method, f, k, RMSE, α, n_o, n_u, n_m, n_s).
const THESIS: [[&str; 9]; 12] = [
    ["USF", "60.9", "–", "–", "2.7", "0.4", "0.0", "5.3", "3.6"],
    ["WSU", "40.4", "–", "–", "3.3", "0.5", "0.6", "6.7", "4.8"],
    ["UB", "65.7", "–", "–", "3.1", "0.6", "0.1", "4.2", "2.8"],
    ["UE", "68.4", "–", "–", "2.6", "0.2", "0.3", "3.8", "2.1"],
    ["UFPR", "75.3", "–", "–", "2.5", "0.3", "0.1", "3.0", "2.5"],
    [
        "Oehler et al.",
        "50.1",
        "–",
        "–",
        "5.2",
        "0.3",
        "0.4",
        "6.2",
        "3.9",
    ],
    [
        "Holz et al.",
        "75.3",
        "–",
        "–",
        "2.6",
        "0.4",
        "0.2",
        "2.7",
        "0.3",
    ],
    [
        "RPL-GMR", "72.4", "–", "–", "2.5", "0.3", "0.3", "3.0", "2.0",
    ],
    [
        "Feng et al.",
        "60.9",
        "–",
        "–",
        "2.4",
        "0.2",
        "0.2",
        "5.1",
        "2.1",
    ],
    [
        "PEAC", "48.6", "91.3", "2.6", "2.6", "0.0", "0.1", "7.1", "2.0",
    ],
    [
        "MSAC", "18.5", "76.7", "3.4", "3.9", "0.1", "0.2", "11.3", "3.4",
    ],
    [
        "PPE", "60.7", "61.2", "2.9", "2.8", "1.4", "1.1", "1.5", "2.3",
    ],
];

/// The result of `unit`, decoded.
fn unit<T: serde::de::DeserializeOwned>(results: &UnitResults, unit: &str) -> Result<T> {
    let (_, value) = results
        .iter()
        .find(|(u, _)| u == unit)
        .with_context(|| format!("no result of the unit {unit}"))?;
    serde_json::from_value(value.clone()).with_context(|| format!("result of {unit}"))
}

/// The page from the units' results.
pub fn report(ctx: &EvalContext, results: &UnitResults) -> Result<EvalReport> {
    let real: RealUnit = unit(results, REAL)?;
    let standin: StandinUnit = unit(results, STANDIN)?;
    let real = real.measured.as_ref();
    let outcome = &standin.outcome;
    let mut json = serde_json::Map::new();
    if let Some(r) = real {
        json.insert("real".into(), protocol::json(&r.outcome));
    }
    json.insert("standin".into(), protocol::json(outcome));
    json.insert("standin_images".into(), standin::images_json(&standin));
    let markdown = format!(
        "The protocol of § 11.5: per method, a grid search on the training images for the best \
         mean fraction f of correctly segmented planes (the thesis grid-searches e and d of PPE \
         this way and the parameters of MSAC and PEAC analogously), then that cell on the test \
         images, scored by the Hoover et al. (1996) evaluator at 80 % overlap: f and k in %, \
         the per-ray radial RMSE of the planes with RMSE ≤ 10 m, the mean angle deviation α \
         of adjacent correctly detected planes, and the numbers of over-, under-segmented, \
         missed and spurious planes n_o, n_u, n_m, n_s per image. Means over the test images \
         (α over the images where it is defined), median extraction time with {threads} rayon \
         threads on a shared machine. Grids: {grids}. The PEAC-style baseline is \
         `raypath_planes::peac` (Feng et al. 2014 re-implemented), not the PEAC code the thesis \
         ran.\n\n{real_md}\n\
         ### Simulated SegComp-like stand-in\n\n{standin_md}\
         ### Table 11.1 (thesis, SegComp rows)\n\n{thesis}\n\
         The stand-in rows measure the extractors on Perceptron-like images with the artifacts \
         the thesis describes, at amplitudes we chose; they say how the methods rank on such \
         images, not what they score on SegComp (PPE f = {ppe_f:.1} % here against 60.7 % in \
         the thesis).\n",
        threads = rayon::current_num_threads(),
        grids = protocol::grid_text(ctx.quick),
        real_md = real_section(ctx, real)?,
        standin_md = standin_section(ctx, &standin, real)?,
        thesis = thesis_table(real.is_some()).to_markdown()?,
        ppe_f = protocol::test_f(outcome, 0),
    );
    Ok(EvalReport {
        name: NAME,
        title: TITLE.into(),
        markdown,
        json: Value::Object(json),
        headline: Some(headline(real.map(|r| &r.outcome), outcome)),
    })
}

/// The real set's results table, or how to install the images.
fn real_section(ctx: &EvalContext, real: Option<&RealMeasured>) -> Result<String> {
    let root = ctx.data("segcomp");
    let Some(real) = real else {
        return Ok(format!(
            "### Real SegComp Perceptron\n\n**Not installed**: no `perc.test.N` range images \
             under `{}` (nor under `{}`). {HOW_TO_GET}\n",
            root.display(),
            root.join("perceptron/test").display()
        ));
    };
    let mut results = Table::new(protocol::result_header());
    protocol::results_rows(
        &mut results,
        "real SegComp Perceptron, test",
        &real.outcome,
        &comparable::yes("the SegComp Perceptron test images, the thesis' protocol"),
    );
    Ok(format!(
        "### Real SegComp Perceptron\n\nImages under `{}`.\n\n{}\n",
        root.display(),
        results.to_markdown()?
    ))
}

/// The stand-in's section after its heading: what it is, its results, its grid search and
/// then the real set's grid tables.
fn standin_section(
    ctx: &EvalContext,
    standin: &StandinUnit,
    real: Option<&RealMeasured>,
) -> Result<String> {
    let outcome = &standin.outcome;
    let describe = standin::describe(&standin::config(ctx.quick), &standin.train, &standin.test);
    let mut sim_results = Table::new(protocol::result_header());
    protocol::results_rows(
        &mut sim_results,
        "simulated stand-in, test",
        outcome,
        &comparable::no(NOT_SEGCOMP),
    );
    let sim_grid = protocol::grid_table("simulated stand-in, train", outcome, SHOWN);
    let matrix = protocol::ppe_matrix(outcome)
        .map(|t| t.to_markdown())
        .transpose()?
        .map_or(String::new(), |m| {
            format!("PPE, mean f [%] on the simulated training images (bold: used):\n\n{m}\n")
        });
    let sim_edges = protocol::edge_note(outcome, ctx.quick);
    let grids_md = match real {
        Some(r) => real_grid_md(&r.outcome, r.train_images, ctx.quick)?,
        None => String::new(),
    };
    Ok(format!(
        "{describe}\n\n{sim}\n\
         #### Grid search on the simulated training images\n\n{matrix}\nBest {SHOWN} cells per \
         method:\n\n{sim_grid}\n{sim_edges}\n\n{grids_md}",
        sim = sim_results.to_markdown()?,
        sim_grid = sim_grid.to_markdown()?,
    ))
}

/// The thesis' SegComp rows with the verdict on comparing them (`real`: whether the real
/// rows are on the page).
fn thesis_table(real: bool) -> Table {
    let verdict = if real {
        format!(
            "{} for the real rows; {} for the stand-in rows",
            comparable::yes("same images and protocol"),
            comparable::no(NOT_SEGCOMP)
        )
    } else {
        comparable::no(NOT_SEGCOMP)
    };
    let mut header = vec!["method (thesis, SegComp Perceptron test)"];
    header.extend(HOOVER_COLUMNS);
    header.push(comparable::HEADER);
    let mut thesis = Table::new(header);
    for row in THESIS {
        let mut cells: Vec<String> = row.iter().map(|c| (*c).to_owned()).collect();
        cells.push(verdict.clone());
        thesis.row(cells);
    }
    thesis
}

/// The grid tables of the real data (or why there are none).
fn real_grid_md(outcome: &Outcome, n_train: usize, quick: bool) -> Result<String> {
    if n_train == 0 {
        return Ok(
            "No `perc.train.N` images were found, so the real rows use the untuned parameters \
             (`PpeParams::segcomp()` and the baselines' defaults at the SegComp scale).\n\n"
                .to_owned(),
        );
    }
    let matrix = protocol::ppe_matrix(outcome)
        .map(|t| t.to_markdown())
        .transpose()?
        .unwrap_or_default();
    Ok(format!(
        "#### Grid search on the real training images ({n_train})\n\nPPE, mean f [%] (bold: \
         used):\n\n{matrix}\nBest {SHOWN} cells per method:\n\n{}\n{}\n\n",
        protocol::grid_table("real SegComp Perceptron, train", outcome, SHOWN).to_markdown()?,
        protocol::edge_note(outcome, quick)
    ))
}

/// The page's headline: real rows first, then the stand-in, named simulated.
fn headline(real: Option<&Outcome>, standin: &Outcome) -> String {
    let fs = |o: &Outcome| {
        (
            protocol::test_f(o, 0),
            protocol::test_f(o, 1),
            protocol::test_f(o, 2),
        )
    };
    let real_part = match real {
        Some(o) => {
            let (p, e, m) = fs(o);
            format!(
                "Real SegComp Perceptron test images: PPE f {p:.1} %, PEAC-style {e:.1} %, \
                 MSAC {m:.1} % (thesis: 60.7, 48.6, 18.5 %). "
            )
        }
        None => "Real SegComp not installed. ".to_owned(),
    };
    let (p, e, m) = fs(standin);
    format!(
        "{real_part}Simulated SegComp-like stand-in (not the SegComp images; parameters \
         grid-searched on its training images): PPE f {p:.1} %, PEAC-style {e:.1} %, MSAC \
         {m:.1} %."
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::planes::HooverScore;
    use protocol::Cell;
    use raypath_sim::segcomp::ImageStats;

    fn score(f: f64) -> HooverScore {
        HooverScore {
            f,
            k: f + 1.0,
            rmse_mm: 2.0,
            alpha_deg: f64::NAN,
            gt: 10.0,
            planes: 9.0,
            secs: 0.5,
            ..HooverScore::default()
        }
    }

    /// An outcome over two test images where PPE, PEAC-style and MSAC score `f`, `f − 10`,
    /// `f − 20` (with a searched grid when `grid`).
    fn outcome(f: f64, grid: bool) -> Outcome {
        let chosen = protocol::untuned();
        let cells: [Vec<Cell>; 3] = if grid {
            protocol::grids(true).map(|methods| {
                methods
                    .into_iter()
                    .enumerate()
                    .map(|(i, method)| Cell {
                        method,
                        scores: vec![score(f - i as f64)],
                    })
                    .collect()
            })
        } else {
            Default::default()
        };
        let chosen = if grid {
            [0, 1, 2].map(|k| cells[k][0].method)
        } else {
            chosen
        };
        Outcome {
            cells,
            chosen,
            test: [0.0, 10.0, 20.0].map(|d| vec![score(f - d), score(f - d)]),
            test_names: vec!["t.0".into(), "t.1".into()],
        }
    }

    fn standin_unit() -> Value {
        let stats = |planes: usize| {
            standin::Stats::from(&ImageStats {
                planes,
                objects: 4,
                noise_rms_mm: 1.5,
                mean_incidence_deg: f64::NAN,
                range_m: [1.0, 3.0],
                ..ImageStats::default()
            })
        };
        serde_json::to_value(StandinUnit {
            outcome: outcome(80.0, true),
            train: vec![stats(12), stats(14)],
            test: vec![stats(10), stats(20), stats(15)],
            seconds: 3.0,
        })
        .unwrap()
    }

    /// The page from known unit results: without the real images (how to get them), then
    /// with them but without their training images (the untuned parameters).
    #[test]
    fn report_from_known_units() {
        let ctx = EvalContext::scratch(&std::env::temp_dir().join("raypath-segcomp-report-test"));
        let absent = serde_json::to_value(RealUnit { measured: None }).unwrap();
        let results = vec![
            (REAL.to_owned(), absent),
            (STANDIN.to_owned(), standin_unit()),
        ];
        let page = report(&ctx, &results).unwrap();
        let md = &page.markdown;
        assert!(md.contains("**Not installed**: no `perc.test.N`"), "{md}");
        assert!(
            md.contains("15.0 ground-truth planes per test image (10–20;"),
            "{md}"
        );
        assert!(md.contains("mean incidence NaN°"), "{md}");
        assert!(md.contains("#### Grid search on the simulated training images"));
        assert!(md.contains("PPE f = 80.0 % here"), "{md}");
        let row = md
            .lines()
            .find(|l| l.starts_with("| simulated stand-in, test | MSAC"))
            .unwrap();
        assert!(row.contains("| 60.0 "), "{row}");
        let keys: Vec<&String> = page.json.as_object().unwrap().keys().collect();
        assert_eq!(keys, ["standin", "standin_images"]);
        assert_eq!(page.json["standin"]["test_images"][1], "t.1");
        assert_eq!(page.json["standin_images"]["test"]["planes"]["max"], 20.0);
        assert!(page.json["standin_images"]["test"]["mean_incidence_deg"]["mean"].is_null());
        assert_eq!(
            page.headline.unwrap(),
            "Real SegComp not installed. Simulated SegComp-like stand-in (not the SegComp \
             images; parameters grid-searched on its training images): PPE f 80.0 %, \
             PEAC-style 70.0 %, MSAC 60.0 %."
        );

        let real = RealUnit {
            measured: Some(RealMeasured {
                outcome: outcome(50.0, false),
                train_images: 0,
            }),
        };
        let results = vec![
            (REAL.to_owned(), serde_json::to_value(real).unwrap()),
            (STANDIN.to_owned(), standin_unit()),
        ];
        let page = report(&ctx, &results).unwrap();
        let md = &page.markdown;
        assert!(md.contains("Images under `"), "{md}");
        assert!(md.contains("No `perc.train.N` images were found"), "{md}");
        assert!(md.contains("for the real rows;"), "{md}");
        assert!(
            page.json["real"]["methods"][0]["grid"]
                .as_array()
                .unwrap()
                .is_empty()
        );
        assert!(
            page.headline.unwrap().starts_with(
                "Real SegComp Perceptron test images: PPE f 50.0 %, PEAC-style 40.0 %"
            )
        );
        let error = report(&ctx, &results[1..]).err().unwrap();
        assert!(format!("{error:#}").contains("no result of the unit real"));
    }
}
