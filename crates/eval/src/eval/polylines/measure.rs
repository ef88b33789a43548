//! What one unit measures: every extractor at every J on a set of scans (one corrected log's
//! seeded-random scans, or a block of simulated random-polygon scans).

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use nalgebra::Point2;
use rayon::prelude::*;
use raypath_geometry::Scan2;
use raypath_io::sequence::{LaserChoice, PlanarOptions, read_planar};
use raypath_polylines::metrics::{area_metrics, ray_metrics};
use raypath_polylines::{PolylineConfig, PolylineError, extract};
use raypath_sim::polygons::{PolygonsConfig, simulate_scan};
use serde::{Deserialize, Serialize};

use super::{JS, TIMING_RUNS, VARIANTS, Variant};
use crate::eval::stages::float;

/// A scan to evaluate, with its ground-truth polygon for simulated scans.
pub struct Sample {
    /// Where it comes from (`intel scan 12`, `polygon 3 (n = 12)`).
    pub source: String,
    /// The scan.
    pub scan: Scan2,
    /// The polygon's vertices (simulated scans).
    pub ground_truth: Option<Vec<Point2<f64>>>,
}

/// Metrics of one extraction.
#[derive(Clone, Copy, Default, Serialize, Deserialize)]
pub struct Outcome {
    /// RMSE of the ray radii, metres.
    #[serde(with = "float")]
    pub rmse_m: f64,
    /// Fraction of the reflected rays explained.
    #[serde(with = "float")]
    pub f: f64,
    /// Area error, ground-truth area as denominator (NaN on real scans).
    #[serde(with = "float")]
    pub a_gt: f64,
    /// Area error, estimated area as denominator (NaN on real scans).
    #[serde(with = "float")]
    pub a_printed: f64,
    /// Intersection over union with the polygon (NaN on real scans).
    #[serde(with = "float")]
    pub iou: f64,
    /// Time of one extraction (the fastest run), seconds.
    #[serde(with = "float")]
    pub secs: f64,
    /// Vertices of the polylines.
    pub vertices: usize,
}

/// `results[variant][j][scan]`.
pub type Results = Vec<Vec<Vec<Outcome>>>;

/// Every variant at every J on `samples` (scans in parallel, each extraction on one
/// thread, timed alone).
pub fn evaluate(samples: &[Sample], max_edge_m: f64) -> Result<Results> {
    let per_scan: Vec<Vec<Vec<Outcome>>> = samples
        .par_iter()
        .map(|sample| {
            VARIANTS
                .iter()
                .map(|v| {
                    JS.iter()
                        .map(|&j| extract_one(sample, v, j, max_edge_m))
                        .collect::<Result<Vec<_>, PolylineError>>()
                })
                .collect::<Result<Vec<_>, _>>()
                .with_context(|| format!("extracting from {}", sample.source))
        })
        .collect::<Result<_>>()?;
    Ok((0..VARIANTS.len())
        .map(|v| {
            (0..JS.len())
                .map(|j| per_scan.iter().map(|s| s[v][j]).collect())
                .collect()
        })
        .collect())
}

/// One extraction of `sample` by variant `v` with `j` vertices, and its metrics.
fn extract_one(
    sample: &Sample,
    v: &Variant,
    j: usize,
    max_edge_m: f64,
) -> Result<Outcome, PolylineError> {
    let config = PolylineConfig {
        max_edge_m,
        optimizer: v.optimizer,
        ..PolylineConfig::new(v.method, j)
    };
    // The fastest of TIMING_RUNS runs: preemption by other jobs on a shared machine only
    // ever adds time.
    let mut secs = f64::INFINITY;
    let mut map = Default::default();
    for _ in 0..TIMING_RUNS {
        let started = Instant::now();
        map = extract(&sample.scan, &config)?;
        secs = secs.min(started.elapsed().as_secs_f64());
    }
    let m = ray_metrics(&sample.scan, &map)?;
    let mut o = Outcome {
        rmse_m: m.rmse_m,
        f: m.f,
        a_gt: f64::NAN,
        a_printed: f64::NAN,
        iou: f64::NAN,
        secs,
        vertices: map.vertex_count(),
    };
    if let Some(gt) = &sample.ground_truth {
        let a = area_metrics(&map, gt)?;
        o.a_gt = a.a_gt;
        o.a_printed = a.a_printed;
        o.iou = a.iou;
    }
    Ok(o)
}

/// Deterministic pseudo-random sample of `count` indices out of `n` (SplitMix64-driven
/// partial Fisher–Yates), sorted.
fn seeded_sample(n: usize, count: usize, seed: u64) -> Vec<usize> {
    let mut state = seed;
    let mut next = || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let mut idx: Vec<usize> = (0..n).collect();
    let count = count.min(n);
    for i in 0..count {
        let j = i + (next() % (n - i) as u64) as usize;
        idx.swap(i, j);
    }
    let mut chosen = idx[..count].to_vec();
    chosen.sort_unstable();
    chosen
}

fn fnv(name: &str) -> u64 {
    name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// `per_log` seeded-random scans (seed: FNV-1a of `name`) of the corrected log at `path`,
/// and the beams per scan of the log.
pub fn real_samples(path: &Path, name: &str, per_log: usize) -> Result<(Vec<Sample>, usize)> {
    let options = PlanarOptions {
        laser: LaserChoice::Front,
        ..PlanarOptions::default()
    };
    let scans: Vec<Scan2> = read_planar(path, &options)
        .with_context(|| format!("reading {}", path.display()))?
        .into_iter()
        .map(|f| f.scan)
        .collect();
    let beams = scans.first().map_or(0, Scan2::len);
    let samples = seeded_sample(scans.len(), per_log, fnv(name))
        .into_iter()
        .map(|i| Sample {
            source: format!("{name} scan {i}"),
            scan: scans[i].clone(),
            ground_truth: None,
        })
        .collect();
    Ok((samples, beams))
}

/// Simulated random-polygon scan `i` (the `polygons` generator, default seed).
pub fn simulated_sample(i: usize) -> Result<Sample> {
    let s = simulate_scan(
        &PolygonsConfig::default(),
        raypath_sim::datasets::DEFAULT_SEED,
        i,
    )?;
    Ok(Sample {
        source: format!("polygon {i} (n = {})", s.polygon.n),
        ground_truth: Some(
            s.polygon
                .vertices
                .iter()
                .map(|v| Point2::new(v[0], v[1]))
                .collect(),
        ),
        scan: s.scan,
    })
}

/// Simulated scans `range`, generated in parallel.
pub fn simulated_samples(range: std::ops::Range<usize>) -> Result<Vec<Sample>> {
    range.into_par_iter().map(simulated_sample).collect()
}
