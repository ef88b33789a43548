//! The simulated SegComp-like stand-in of `raypath_sim::segcomp`: its images generated in
//! memory from a fixed seed, the protocol run on them (the unit `standin`), and the paragraph
//! that says what they are.

use anyhow::Result;
use raypath_sim::segcomp::{self as standin, ImageStats, SegcompConfig, Split};
use serde::{Deserialize, Serialize};

use super::SEED;
use super::protocol::{self, Image, Outcome};
use crate::eval::EvalContext;
use crate::eval::stages::float;
use crate::table::fmt_num;

/// The stand-in configuration of a run (10 + 30 images, 2 + 3 with `--quick`).
pub fn config(quick: bool) -> SegcompConfig {
    let (train_images, test_images) = if quick { (2, 3) } else { (10, 30) };
    SegcompConfig {
        train_images,
        test_images,
        ..SegcompConfig::default()
    }
}

/// The stand-in's result.
#[derive(Serialize, Deserialize)]
pub struct StandinUnit {
    /// The protocol's outcome.
    pub outcome: Outcome,
    /// The figures of the training images and of the test images.
    pub train: Vec<Stats>,
    pub test: Vec<Stats>,
    /// Generation and evaluation time (s).
    #[serde(with = "float")]
    pub seconds: f64,
}

/// [`ImageStats`] in a unit's result (non-finite figures survive it).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Stats {
    planes: usize,
    objects: usize,
    small_faces: usize,
    mixed_pixels: usize,
    no_data_pixels: usize,
    #[serde(with = "float")]
    noise_rms_mm: f64,
    #[serde(with = "float")]
    mean_incidence_deg: f64,
    #[serde(with = "float")]
    range_min_m: f64,
    #[serde(with = "float")]
    range_max_m: f64,
}

impl From<&ImageStats> for Stats {
    fn from(s: &ImageStats) -> Self {
        Self {
            planes: s.planes,
            objects: s.objects,
            small_faces: s.small_faces,
            mixed_pixels: s.mixed_pixels,
            no_data_pixels: s.no_data_pixels,
            noise_rms_mm: s.noise_rms_mm,
            mean_incidence_deg: s.mean_incidence_deg,
            range_min_m: s.range_m[0],
            range_max_m: s.range_m[1],
        }
    }
}

impl From<&Stats> for ImageStats {
    fn from(s: &Stats) -> Self {
        Self {
            planes: s.planes,
            objects: s.objects,
            small_faces: s.small_faces,
            mixed_pixels: s.mixed_pixels,
            no_data_pixels: s.no_data_pixels,
            noise_rms_mm: s.noise_rms_mm,
            mean_incidence_deg: s.mean_incidence_deg,
            range_m: [s.range_min_m, s.range_max_m],
        }
    }
}

/// A generated image as the evaluation sees it: the cloud through the reader's conversion.
fn image(config: &SegcompConfig, split: Split, index: usize) -> Result<(Image, ImageStats)> {
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

/// Generates the stand-in and runs the protocol on it (the unit `standin`).
pub fn measure(ctx: &EvalContext) -> Result<StandinUnit> {
    let config = config(ctx.quick);
    let started = std::time::Instant::now();
    let mut stats = Vec::new();
    let mut train = Vec::with_capacity(config.train_images);
    for i in 0..config.train_images {
        let (image, s) = image(&config, Split::Train, i)?;
        train.push(image);
        stats.push(s);
    }
    let outcome = protocol::run(ctx, "stand-in", &train, config.test_images, |i| {
        let (image, s) = image(&config, Split::Test, i)?;
        stats.push(s);
        Ok(image)
    })?;
    drop(train);
    let seconds = started.elapsed().as_secs_f64();
    let (train, test) = stats.split_at(config.train_images.min(stats.len()));
    Ok(StandinUnit {
        outcome,
        train: train.iter().map(Stats::from).collect(),
        test: test.iter().map(Stats::from).collect(),
        seconds,
    })
}

/// The stand-in's figures as the page's JSON has them (`standin_images`).
pub fn images_json(unit: &StandinUnit) -> serde_json::Value {
    let summary = |stats: &[Stats]| {
        let stats: Vec<ImageStats> = stats.iter().map(ImageStats::from).collect();
        standin::summary(&stats.iter().collect::<Vec<_>>())
    };
    serde_json::json!({
        "seed": SEED,
        "train": summary(&unit.train),
        "test": summary(&unit.test),
        "seconds_generation_and_evaluation": unit.seconds,
    })
}

/// What the stand-in is, with its figures.
pub fn describe(config: &SegcompConfig, train: &[Stats], test: &[Stats]) -> String {
    let all: Vec<&Stats> = train.iter().chain(test).collect();
    let avg = |f: fn(&Stats) -> f64| {
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
            .map(|s| s.range_min_m)
            .fold(f64::INFINITY, f64::min),
        rmax = all
            .iter()
            .map(|s| s.range_max_m)
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
