//! `cargo xtask eval segcomp`: PPE, the PEAC-style baseline and MSAC under the SegComp
//! protocol of Schaefer (2020, § 11.5, Table 11.1) — each method's parameters grid-searched
//! on the training images for the best mean fraction f of correctly segmented planes, then
//! scored on the test images by the Hoover et al. (1996) evaluator at 80 % overlap (f, k,
//! RMSE, α, n_o, n_u, n_m, n_s).
//!
//! Two data sets, two tables: the **real** SegComp Perceptron images when installed under
//! `$RAYPATH_DATA/segcomp/` (`perceptron/{train,test}/` as in `datasets/manifest.json`, or
//! flat), and always the **simulated** SegComp-like stand-in of `raypath_sim::segcomp`
//! (generated in memory from a fixed seed), every row of which says it is simulated. The
//! thesis' rows stay beside them as the reference.

mod files;
mod protocol;

use anyhow::Result;
use raypath_sim::segcomp::{self as standin, SegcompConfig, Split};

use super::{EvalContext, EvalReport, comparable};
use crate::table::{Table, fmt_num};
use protocol::{Image, Outcome};

const NAME: &str = "segcomp";

/// The stand-in's seed (the workspace's default seed of generated sets).
const SEED: u64 = raypath_sim::datasets::DEFAULT_SEED;

/// Cells shown per method in the grid tables.
const SHOWN: usize = 3;

/// Why the stand-in rows are not the thesis' figures.
const NOT_SEGCOMP: &str = "simulated stand-in, not the SegComp images";

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

/// The stand-in configuration of a run (10 + 30 images, 2 + 3 with `--quick`).
fn standin_config(quick: bool) -> SegcompConfig {
    let (train_images, test_images) = if quick { (2, 3) } else { (10, 30) };
    SegcompConfig {
        train_images,
        test_images,
        ..SegcompConfig::default()
    }
}

/// A generated image as the evaluation sees it: the cloud through the reader's conversion.
fn standin_image(
    config: &SegcompConfig,
    split: Split,
    index: usize,
) -> Result<(Image, standin::ImageStats)> {
    let image = standin::generate_image(config, SEED, split, index)?;
    let cloud = image.cloud(&config.geometry);
    let angles = image
        .angles
        .pairs
        .iter()
        .map(|p| (p.label_a, p.label_b, p.angle_deg))
        .collect();
    Ok((
        Image {
            name: image.name,
            cloud,
            gt: image.labels.labels.into_iter().map(Some).collect(),
            angles: Some(angles),
        },
        image.stats,
    ))
}

/// Runs the evaluation.
pub fn run(ctx: &EvalContext) -> Result<EvalReport> {
    let root = ctx.data("segcomp");
    let mut results = Table::new(protocol::RESULT_HEADER);
    let mut grids_md = String::new();
    let mut json = serde_json::Map::new();

    // Real SegComp, when installed.
    let mut test_files = files::find(&root, Split::Test);
    let mut train_files = files::find(&root, Split::Train);
    let real = if test_files.is_empty() {
        eprintln!(
            "segcomp: no perc.test.N under {} — running the simulated stand-in only",
            root.display()
        );
        None
    } else {
        if ctx.quick {
            train_files.truncate(2);
            test_files.truncate(3);
        }
        let train = train_files
            .iter()
            .map(files::load)
            .collect::<Result<Vec<_>>>()?;
        let outcome = protocol::run(ctx, "real", &train, test_files.len(), |i| {
            files::load(&test_files[i])
        })?;
        Some((outcome, train.len()))
    };
    if let Some((outcome, n_train)) = &real {
        protocol::results_rows(
            &mut results,
            "real SegComp Perceptron, test",
            outcome,
            &comparable::yes("the SegComp Perceptron test images, the thesis' protocol"),
        );
        json.insert("real".into(), protocol::json(outcome));
        grids_md.push_str(&real_grid_md(outcome, *n_train, ctx.quick)?);
    }

    // The simulated stand-in.
    let config = standin_config(ctx.quick);
    let started = std::time::Instant::now();
    let mut stats = Vec::new();
    let mut train = Vec::with_capacity(config.train_images);
    for i in 0..config.train_images {
        let (image, s) = standin_image(&config, Split::Train, i)?;
        train.push(image);
        stats.push(s);
    }
    let outcome = protocol::run(ctx, "stand-in", &train, config.test_images, |i| {
        let (image, s) = standin_image(&config, Split::Test, i)?;
        stats.push(s);
        Ok(image)
    })?;
    drop(train);
    let standin_secs = started.elapsed().as_secs_f64();
    let mut sim_results = Table::new(protocol::RESULT_HEADER);
    protocol::results_rows(
        &mut sim_results,
        "simulated stand-in, test",
        &outcome,
        &comparable::no(NOT_SEGCOMP),
    );
    let (train_stats, test_stats) = stats.split_at(config.train_images.min(stats.len()));
    let describe = describe_standin(&config, train_stats, test_stats);
    json.insert("standin".into(), protocol::json(&outcome));
    json.insert(
        "standin_images".into(),
        serde_json::json!({
            "seed": SEED,
            "train": standin::summary(&train_stats.iter().collect::<Vec<_>>()),
            "test": standin::summary(&test_stats.iter().collect::<Vec<_>>()),
            "seconds_generation_and_evaluation": standin_secs,
        }),
    );
    let sim_grid = protocol::grid_table("simulated stand-in, train", &outcome, SHOWN);
    let matrix = protocol::ppe_matrix(&outcome)
        .map(|t| t.to_markdown())
        .transpose()?
        .map_or(String::new(), |m| {
            format!("PPE, mean f [%] on the simulated training images (bold: used):\n\n{m}\n")
        });
    let sim_edges = protocol::edge_note(&outcome, ctx.quick);

    // The thesis.
    let verdict = match &real {
        Some(_) => format!(
            "{} for the real rows; {} for the stand-in rows",
            comparable::yes("same images and protocol"),
            comparable::no(NOT_SEGCOMP)
        ),
        None => comparable::no(NOT_SEGCOMP),
    };
    let mut thesis = Table::new([
        "method (thesis, SegComp Perceptron test)",
        "f [%]",
        "k [%]",
        "RMSE [mm]",
        "α [°]",
        "n_o",
        "n_u",
        "n_m",
        "n_s",
        comparable::HEADER,
    ]);
    for row in THESIS {
        let mut cells: Vec<String> = row.iter().map(|c| (*c).to_owned()).collect();
        cells.push(verdict.clone());
        thesis.row(cells);
    }

    let real_md = match &real {
        Some(_) => format!(
            "### Real SegComp Perceptron\n\nImages under `{}`.\n\n{}\n",
            root.display(),
            results.to_markdown()?
        ),
        None => format!(
            "### Real SegComp Perceptron\n\n**Not installed**: no `perc.test.N` range images \
             under `{}` (nor under `{}`). {HOW_TO_GET}\n",
            root.display(),
            root.join("perceptron/test").display()
        ),
    };
    let ppe_f = protocol::test_f(&outcome, 0);
    let headline = Some(headline(&real, &outcome));
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
         ### Simulated SegComp-like stand-in\n\n{describe}\n\n{sim}\n\
         #### Grid search on the simulated training images\n\n{matrix}\nBest {SHOWN} cells per \
         method:\n\n{sim_grid}\n{sim_edges}\n\n{grids_md}\
         ### Table 11.1 (thesis, SegComp rows)\n\n{thesis}\n\
         The stand-in rows measure the extractors on Perceptron-like images with the artifacts \
         the thesis describes, at amplitudes we chose; they say how the methods rank on such \
         images, not what they score on SegComp (PPE f = {ppe_f:.1} % here against 60.7 % in \
         the thesis).\n",
        threads = rayon::current_num_threads(),
        grids = protocol::grid_text(ctx.quick),
        sim = sim_results.to_markdown()?,
        matrix = matrix,
        sim_grid = sim_grid.to_markdown()?,
        thesis = thesis.to_markdown()?,
    );
    Ok(EvalReport {
        name: NAME,
        title: "PPE, PEAC-style and MSAC on SegComp Perceptron and a simulated stand-in (Schaefer 2020, Table 11.1)".into(),
        markdown,
        json: serde_json::Value::Object(json),
        headline,
    })
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

/// What the stand-in is, with its figures.
fn describe_standin(
    config: &SegcompConfig,
    train: &[standin::ImageStats],
    test: &[standin::ImageStats],
) -> String {
    let all: Vec<&standin::ImageStats> = train.iter().chain(test).collect();
    let avg = |f: fn(&standin::ImageStats) -> f64| {
        if all.is_empty() {
            f64::NAN
        } else {
            all.iter().map(|s| f(s)).sum::<f64>() / all.len() as f64
        }
    };
    let test_planes: Vec<f64> = test.iter().map(|s| s.planes as f64).collect();
    let (lo, hi) = test_planes
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let mean_test = if test_planes.is_empty() {
        f64::NAN
    } else {
        test_planes.iter().sum::<f64>() / test_planes.len() as f64
    };
    let pixels = (config.rows * config.cols) as f64;
    format!(
        "**Every row of this section is simulated.** `raypath_sim::segcomp` renders {train} \
         training and {test} test images (seed {SEED}, generated in memory: same seed, same \
         counts and labels) of {rows} × {cols} raw 12-bit ranges with the Perceptron \
         projection of the SegComp reader (`PerceptronGeometry`, `sc2cart`; the cloud comes \
         from the reader's own conversion): a table and a backdrop wall with {o0}–{o1} blocks, \
         wedges and 3- to 8-sided prisms standing on the table, some boxes carrying a \
         smaller block; {planes} ground-truth planes per test image ({lo:.0}–{hi:.0}; the real \
         test images have 14.6), {objects} objects per image, ranges {rmin:.2}–{rmax:.2} m. \
         Sensor artifacts modelled after § 11.5: range noise σ = {sigma} mm / cos θ (capped at \
         {cap}×; {noise} mm RMS drawn, mean incidence {inc:.0}°), mixed pixels from a \
         {fp}-pixel beam footprint along every edge ({mixed:.1} % of the pixels), a \
         systematic calibration error bending every surface by {kink} mm along the centre \
         column (the kinked tabletop), 0.2 mm range counts. Faces under {minpx} pixels are \
         not labelled; the angles of adjacent planes are exact.",
        train = config.train_images,
        test = config.test_images,
        rows = config.rows,
        cols = config.cols,
        o0 = config.objects[0],
        o1 = config.objects[1],
        planes = fmt_num(mean_test, 1),
        objects = fmt_num(avg(|s| s.objects as f64), 1),
        rmin = all
            .iter()
            .map(|s| s.range_m[0])
            .fold(f64::INFINITY, f64::min),
        rmax = all
            .iter()
            .map(|s| s.range_m[1])
            .fold(f64::NEG_INFINITY, f64::max),
        sigma = config.range_noise_mm,
        cap = config.max_noise_factor,
        noise = fmt_num(avg(|s| s.noise_rms_mm), 2),
        inc = avg(|s| s.mean_incidence_deg),
        fp = config.footprint_px,
        mixed = 100.0 * avg(|s| s.mixed_pixels as f64) / pixels,
        kink = config.calibration_kink_mm,
        minpx = config.min_region_pixels,
    )
}

/// The page's headline: real rows first, then the stand-in, named simulated.
fn headline(real: &Option<(Outcome, usize)>, standin: &Outcome) -> String {
    let fs = |o: &Outcome| {
        (
            protocol::test_f(o, 0),
            protocol::test_f(o, 1),
            protocol::test_f(o, 2),
        )
    };
    let real_part = match real {
        Some((o, _)) => {
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
