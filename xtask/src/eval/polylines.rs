//! `cargo xtask eval polylines`: the polyline benchmark of Schaefer (2020), chapter 10.
//!
//! * Real: seeded-random scans from every corrected CARMEN log (20 per log; the thesis used
//!   13 logs, 10 are available here), `l_max` = 1 m.
//! * Simulated: 260 random-polygon scans from `raypath-sim` (360 rays, σ_angle 0.2°,
//!   σ_radial 0.03 m; the same generator and seed as `datasets/generated/polygons`, simulated
//!   in memory), `l_max` = ∞ like the reference implementation.
//! * For J ∈ {10, 20, 30, 40, 50}: RMSE, f, a (both denominators), IoU and the time per scan
//!   for VVL, IEF, SAM, PLE, PLE+ (Levenberg–Marquardt, the crate default) and PLE+ with
//!   Nelder–Mead (the thesis solver). Scans run in parallel (rayon), each extraction on one
//!   thread, timed alone.

mod plot;

use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use nalgebra::Point2;
use rayon::prelude::*;
use raypath_geometry::Scan2;
use raypath_io::sequence::{LaserChoice, PlanarOptions, read_planar};
use raypath_polylines::metrics::{area_metrics, ray_metrics};
use raypath_polylines::svg::scan_svg;
use raypath_polylines::{Method, Optimizer, PolylineConfig, extract};
use raypath_sim::polygons::{PolygonsConfig, simulate_scan};
use serde_json::json;

use super::{EvalContext, EvalReport, comparable, median};
use crate::table::{Table, fmt_num};

const JS: [usize; 5] = [10, 20, 30, 40, 50];
const NAME: &str = "polylines";
/// Each extraction runs this often; its time is the fastest run.
const TIMING_RUNS: usize = 3;
/// Label of the Nelder–Mead PLE+ variant.
const NM: &str = "PLE+ (NM)";

/// One extractor as evaluated.
#[derive(Clone, Copy)]
struct Variant {
    label: &'static str,
    method: Method,
    optimizer: Optimizer,
    color: &'static str,
}

const VARIANTS: [Variant; 6] = [
    Variant {
        label: "VVL",
        method: Method::Vvl,
        optimizer: Optimizer::LEVENBERG_MARQUARDT,
        color: "#2ca02c",
    },
    Variant {
        label: "IEF",
        method: Method::Ief,
        optimizer: Optimizer::LEVENBERG_MARQUARDT,
        color: "#ff7f0e",
    },
    Variant {
        label: "SAM",
        method: Method::Sam,
        optimizer: Optimizer::LEVENBERG_MARQUARDT,
        color: "#9467bd",
    },
    Variant {
        label: "PLE",
        method: Method::Ple,
        optimizer: Optimizer::LEVENBERG_MARQUARDT,
        color: "#1f77b4",
    },
    Variant {
        label: "PLE+",
        method: Method::PlePlus,
        optimizer: Optimizer::LEVENBERG_MARQUARDT,
        color: "#d62728",
    },
    Variant {
        label: "PLE+ (NM)",
        method: Method::PlePlus,
        optimizer: Optimizer::NELDER_MEAD,
        color: "#8c564b",
    },
];

/// Thesis Table 10.2 (seconds per scan): (data, J, VVL, IEF, SAM, PLE, PLE+).
const TABLE_10_2: [(&str, usize, [f64; 5]); 4] = [
    ("real", 20, [0.056, 0.27, 28.0, 1.4, 2.3]),
    ("real", 50, [0.050, 1.12, 27.0, 1.3, 6.9]),
    ("simulated", 20, [0.037, 0.38, 103.0, 2.3, 11.0]),
    ("simulated", 50, [0.037, 1.59, 102.0, 2.2, 72.0]),
];

/// The 13 Radish logs of thesis Table 10.1, named as our corrected logs are.
const THESIS_LOGS: [&str; 13] = [
    "acapulco",
    "aces",
    "belgioioso",
    "csail",
    "edmonton",
    "fhw",
    "freiburg-079",
    "freiburg-101",
    "freiburg-campus",
    "infinite-corridor",
    "intel",
    "orebro",
    "seattle",
];

/// What our real scans are beside the thesis' (for the "comparable" cells): which of the
/// thesis' 13 logs they come from and which are absent.
fn real_data_text(logs: &[&str], scans: usize) -> String {
    let (ours, absent, extra) = comparable::log_overlap(logs, &THESIS_LOGS);
    let mut text =
        format!("{scans} real scans from {ours} of the thesis' 13 Radish logs (thesis: 260 scans)");
    if !absent.is_empty() {
        text.push_str(&format!(", absent: {}", absent.join(", ")));
    }
    if !extra.is_empty() {
        text.push_str(&format!(", not in the thesis: {}", extra.join(", ")));
    }
    text.push_str(", other random draws");
    text
}

/// What our simulated scans are beside the thesis' (for the "comparable" cells).
const SIM_DATA_TEXT: &str = "simulated in both: the thesis' protocol (random polygons, 360 rays, \
     σ 0.2° / 0.03 m), other random draws, l_max = ∞ (thesis text: 1 m)";

/// The "comparable" cell of a Table 10.2 row (`data_text`: what our scans are).
fn time_comparable(data_text: &str) -> String {
    comparable::no(&format!(
        "other language and hardware (thesis: MATLAB on one 2.5 GHz Intel Xeon thread; ours: \
         Rust, one thread on the machine above); {data_text}"
    ))
}

/// A scan to evaluate, with its ground-truth polygon for simulated scans.
struct Sample {
    source: String,
    scan: Scan2,
    ground_truth: Option<Vec<Point2<f64>>>,
}

/// Metrics of one extraction.
#[derive(Clone, Copy, Default)]
struct Outcome {
    rmse_m: f64,
    f: f64,
    a_gt: f64,
    a_printed: f64,
    iou: f64,
    secs: f64,
    vertices: usize,
}

/// A log used: name, scans sampled, beams per scan.
type LogInfo = (String, usize, usize);

/// `results[variant][j][scan]`.
type Results = Vec<Vec<Vec<Outcome>>>;

fn evaluate(ctx: &EvalContext, samples: &[Sample], max_edge_m: f64, what: &str) -> Result<Results> {
    let bar = ctx.progress(samples.len() as u64, what);
    let per_scan: Vec<Vec<Vec<Outcome>>> = samples
        .par_iter()
        .map(|sample| {
            let out = VARIANTS
                .iter()
                .map(|v| {
                    JS.iter()
                        .map(|&j| {
                            let config = PolylineConfig {
                                max_edge_m,
                                optimizer: v.optimizer,
                                ..PolylineConfig::new(v.method, j)
                            };
                            // The fastest of TIMING_RUNS runs: preemption by other jobs
                            // on a shared machine only ever adds time.
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
                        })
                        .collect::<Result<Vec<_>, raypath_polylines::PolylineError>>()
                })
                .collect::<Result<Vec<_>, _>>()
                .with_context(|| format!("extracting from {}", sample.source));
            bar.inc(1);
            out
        })
        .collect::<Result<_>>()?;
    bar.finish_and_clear();
    Ok((0..VARIANTS.len())
        .map(|v| {
            (0..JS.len())
                .map(|j| per_scan.iter().map(|s| s[v][j]).collect())
                .collect()
        })
        .collect())
}

/// Mean and standard error of the finite values.
fn mean_se(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = if v.len() > 1 {
        v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0)
    } else {
        0.0
    };
    (mean, (var / n).sqrt())
}

fn stat(results: &Results, v: usize, j: usize, f: impl Fn(&Outcome) -> f64) -> (f64, f64) {
    mean_se(results[v][j].iter().map(f))
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

fn real_samples(ctx: &EvalContext, per_log: usize) -> Result<(Vec<Sample>, Vec<LogInfo>)> {
    let dir = ctx.data("carmen/corrected");
    let mut logs: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map(|entries| {
            entries
                .flatten()
                .map(|e| e.path())
                .filter(|p| p.to_string_lossy().ends_with("-corrected.log.gz"))
                .collect()
        })
        .unwrap_or_default();
    logs.sort();
    let loaded: Vec<(String, Vec<Scan2>)> = logs
        .par_iter()
        .map(|path| {
            let name = log_name(path);
            let options = PlanarOptions {
                laser: LaserChoice::Front,
                ..PlanarOptions::default()
            };
            let scans: Vec<Scan2> = read_planar(path, &options)
                .with_context(|| format!("reading {}", path.display()))?
                .into_iter()
                .map(|f| f.scan)
                .collect();
            Ok((name, scans))
        })
        .collect::<Result<_>>()?;
    let mut samples = Vec::new();
    let mut logs_used = Vec::new();
    for (name, scans) in loaded {
        let chosen = seeded_sample(scans.len(), per_log, fnv(&name));
        let beams = scans.first().map_or(0, Scan2::len);
        logs_used.push((name.clone(), chosen.len(), beams));
        for i in chosen {
            samples.push(Sample {
                source: format!("{name} scan {i}"),
                scan: scans[i].clone(),
                ground_truth: None,
            });
        }
    }
    Ok((samples, logs_used))
}

fn log_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().replace("-corrected.log.gz", ""))
        .unwrap_or_default()
}

fn simulated_samples(count: usize) -> Result<Vec<Sample>> {
    let config = PolygonsConfig::default();
    (0..count)
        .into_par_iter()
        .map(|i| {
            let s = simulate_scan(&config, raypath_sim::datasets::DEFAULT_SEED, i)?;
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
        })
        .collect()
}

fn metric_table(
    results: &Results,
    f: impl Fn(&Outcome) -> f64,
    scale: f64,
    decimals: usize,
) -> Result<String> {
    let mut headers = vec!["J".to_owned()];
    headers.extend(VARIANTS.iter().map(|v| v.label.to_owned()));
    let mut table = Table::new(headers);
    for (ji, j) in JS.iter().enumerate() {
        let mut row = vec![j.to_string()];
        for vi in 0..VARIANTS.len() {
            let (m, se) = stat(results, vi, ji, &f);
            row.push(format!(
                "{} ± {}",
                fmt_num(m * scale, decimals),
                fmt_num(se * scale, decimals)
            ));
        }
        table.row(row);
    }
    table.to_markdown()
}

fn chart(
    results: &Results,
    title: &str,
    y_label: &str,
    f: impl Fn(&Outcome) -> f64,
    scale: f64,
    reference: Option<(f64, &str)>,
    exclude: &[&str],
) -> String {
    let series: Vec<plot::Series> = VARIANTS
        .iter()
        .enumerate()
        .filter(|(_, v)| !exclude.contains(&v.label))
        .map(|(vi, v)| plot::Series {
            label: v.label.to_owned(),
            color: v.color,
            points: JS
                .iter()
                .enumerate()
                .map(|(ji, &j)| {
                    let (m, se) = stat(results, vi, ji, &f);
                    (j as f64, m * scale, se * scale)
                })
                .collect(),
        })
        .collect();
    plot::line_chart(title, "number of vertices J", y_label, &series, reference)
}

fn write_figure(dir: &Path, name: &str, svg: &str) -> Result<()> {
    let path = dir.join(name);
    std::fs::write(&path, svg).with_context(|| format!("writing {}", path.display()))
}

fn variant_json(results: &Results) -> serde_json::Value {
    let per_variant: Vec<_> = VARIANTS
        .iter()
        .enumerate()
        .map(|(vi, v)| {
            let per_j: Vec<_> = JS
                .iter()
                .enumerate()
                .map(|(ji, &j)| {
                    let s = |f: &dyn Fn(&Outcome) -> f64| {
                        let (m, se) = stat(results, vi, ji, f);
                        json!({"mean": m, "se": se})
                    };
                    let mut secs: Vec<f64> = results[vi][ji].iter().map(|o| o.secs).collect();
                    json!({
                        "j": j,
                        "rmse_m": s(&|o| o.rmse_m),
                        "f": s(&|o| o.f),
                        "a_gt": s(&|o| o.a_gt),
                        "a_printed": s(&|o| o.a_printed),
                        "iou": s(&|o| o.iou),
                        "secs": s(&|o| o.secs),
                        "secs_median": median(&mut secs),
                        "vertices": s(&|o| o.vertices as f64),
                    })
                })
                .collect();
            json!({"method": v.label, "optimizer": v.optimizer.name(), "per_j": per_j})
        })
        .collect();
    json!(per_variant)
}

fn variant_index(label: &str) -> usize {
    VARIANTS.iter().position(|v| v.label == label).unwrap_or(0)
}

/// Ranking of the five thesis methods by mean RMSE at each J ("PLE+ < PLE < …").
fn ranking(results: &Results) -> Vec<String> {
    JS.iter()
        .enumerate()
        .map(|(ji, j)| {
            let mut order: Vec<(f64, &str)> = VARIANTS
                .iter()
                .enumerate()
                .filter(|(_, v)| v.label != "PLE+ (NM)")
                .map(|(vi, v)| (stat(results, vi, ji, |o| o.rmse_m).0, v.label))
                .collect();
            order.sort_by(|a, b| a.0.total_cmp(&b.0));
            format!(
                "J = {j}: {}",
                order
                    .iter()
                    .map(|(m, l)| format!("{l} ({:.1} mm)", m * 1e3))
                    .collect::<Vec<_>>()
                    .join(" < ")
            )
        })
        .collect()
}

/// Runs the evaluation.
pub fn run(ctx: &EvalContext) -> Result<EvalReport> {
    let (per_log, sim_count) = if ctx.quick { (3, 40) } else { (20, 260) };
    let (real, logs) = real_samples(ctx, per_log)?;
    let sim = simulated_samples(sim_count)?;
    eprintln!(
        "polylines: {} real scans from {} logs, {} simulated scans",
        real.len(),
        logs.len(),
        sim.len()
    );
    let real_results = if real.is_empty() {
        None
    } else {
        Some(evaluate(ctx, &real, 1.0, "real")?)
    };
    let sim_results = evaluate(ctx, &sim, f64::INFINITY, "simulated")?;
    let fig_dir = ctx.figure_dir(NAME)?;

    let mut md = String::new();
    let _ = writeln!(
        md,
        "Schaefer (2020) ch. 10 (experiments, Table 10.1): RMSE of the ray radii, fraction f of reflected \
         rays explained, area error a and IoU (simulation), time per scan; mean ± standard \
         error over scans. PLE+ uses Levenberg–Marquardt (crate default); PLE+ (NM) is the \
         thesis' Nelder–Mead (fminsearch options TolX = TolFun = 1e-2, 200·dim iterations). \
         Times: one extraction on one thread, fastest of {TIMING_RUNS} runs (scans in parallel on {} threads), release build.\n",
        rayon::current_num_threads()
    );
    let _ = writeln!(md, "## Data\n");
    if logs.is_empty() {
        let _ = writeln!(
            md,
            "- Real: no corrected CARMEN logs under `{}` — real part skipped.",
            ctx.data("carmen/corrected").display()
        );
    } else {
        let listing: Vec<String> = logs
            .iter()
            .map(|(n, c, b)| format!("{n} ({c} × {b} beams)"))
            .collect();
        let rays: f64 = real.iter().map(|s| s.scan.len() as f64).sum::<f64>() / real.len() as f64;
        let _ = writeln!(
            md,
            "- Real: {} scans, {per_log} seeded-random scans (SplitMix64, seed = FNV-1a of the log name) \
             from each of {} corrected logs: {}; {rays:.0} rays per scan on average (thesis: 260 scans \
             from 13 logs, 264 rays). l_max = 1 m, d_rm = 0.5 m.",
            real.len(),
            logs.len(),
            listing.join(", ")
        );
    }
    let _ = writeln!(
        md,
        "- Simulated: {} random polygons (raypath-sim `polygons`, seed {}, 360 rays over [−180°, 180°), \
         σ_angle 0.2°, σ_radial 0.03 m); l_max = ∞ (reference implementation; the thesis text says 1 m), \
         d_rm = 0.5 m.\n",
        sim.len(),
        raypath_sim::datasets::DEFAULT_SEED
    );

    let mut json_real = serde_json::Value::Null;
    if let Some(results) = &real_results {
        let _ = writeln!(md, "## Real scans (Fig. 10.4 a, c)\n");
        let _ = writeln!(
            md,
            "RMSE in mm:\n\n{}",
            metric_table(results, |o| o.rmse_m, 1e3, 1)?
        );
        let _ = writeln!(md, "f:\n\n{}", metric_table(results, |o| o.f, 1.0, 3)?);
        write_figure(
            &fig_dir,
            "real-rmse.svg",
            &chart(
                results,
                "Real scans: RMSE",
                "RMSE [mm]",
                |o| o.rmse_m,
                1e3,
                None,
                &[],
            ),
        )?;
        write_figure(
            &fig_dir,
            "real-rmse-zoom.svg",
            &chart(
                results,
                "Real scans: RMSE without IEF",
                "RMSE [mm]",
                |o| o.rmse_m,
                1e3,
                None,
                &["IEF"],
            ),
        )?;
        write_figure(
            &fig_dir,
            "real-f.svg",
            &chart(results, "Real scans: f", "f", |o| o.f, 1.0, None, &[NM]),
        )?;
        let _ = writeln!(
            md,
            "![RMSE, real](polylines/real-rmse.svg) ![RMSE, real, zoom](polylines/real-rmse-zoom.svg) \
             ![f, real](polylines/real-f.svg)\n\n\
             IEF keeps one polyline through all returned endpoints (no-returns removed, as in \
             the thesis), so its segments bridge depth jumps (door frames, gaps between \
             objects); the few rays between the bridged endpoints hit such a segment metres \
             in front of their endpoint and dominate the mean RMSE. SAM's fitted segments are \
             separate (as the thesis' reference implementation leaves them), so a depth jump \
             stays open and its rays count against f instead. Median RMSE at J = 20: {}.\n",
            median_rmse(results, 1)
        );
        json_real = variant_json(results);
    }

    let sr = &sim_results;
    let _ = writeln!(md, "## Simulated scans (Fig. 10.4 b, d, e)\n");
    let _ = writeln!(
        md,
        "RMSE in mm (σ_radial = 30 mm):\n\n{}",
        metric_table(sr, |o| o.rmse_m, 1e3, 1)?
    );
    let _ = writeln!(md, "f:\n\n{}", metric_table(sr, |o| o.f, 1.0, 3)?);
    let _ = writeln!(
        md,
        "a with the ground-truth area as denominator (reference implementation):\n\n{}",
        metric_table(sr, |o| o.a_gt, 1.0, 3)?
    );
    let _ = writeln!(
        md,
        "a with the estimated area as denominator (as printed in the thesis):\n\n{}",
        metric_table(sr, |o| o.a_printed, 1.0, 3)?
    );
    let _ = writeln!(md, "IoU:\n\n{}", metric_table(sr, |o| o.iou, 1.0, 3)?);
    write_figure(
        &fig_dir,
        "sim-rmse.svg",
        &chart(
            sr,
            "Simulated: RMSE",
            "RMSE [mm]",
            |o| o.rmse_m,
            1e3,
            Some((30.0, "σ_radial")),
            &[],
        ),
    )?;
    write_figure(
        &fig_dir,
        "sim-rmse-zoom.svg",
        &chart(
            sr,
            "Simulated: RMSE without IEF",
            "RMSE [mm]",
            |o| o.rmse_m,
            1e3,
            Some((30.0, "σ_radial")),
            &["IEF"],
        ),
    )?;
    write_figure(
        &fig_dir,
        "sim-f.svg",
        &chart(sr, "Simulated: f", "f", |o| o.f, 1.0, None, &[NM]),
    )?;
    write_figure(
        &fig_dir,
        "sim-a.svg",
        &chart(
            sr,
            "Simulated: area error a (GT denominator)",
            "a",
            |o| o.a_gt,
            1.0,
            None,
            &[],
        ),
    )?;
    let _ = writeln!(
        md,
        "![RMSE, simulated](polylines/sim-rmse.svg) \
         ![RMSE, simulated, zoom](polylines/sim-rmse-zoom.svg) ![f, simulated](polylines/sim-f.svg) \
         ![a, simulated](polylines/sim-a.svg)\n"
    );

    // Table 10.2.
    let log_names: Vec<&str> = logs.iter().map(|(n, _, _)| n.as_str()).collect();
    let real_text = real_data_text(&log_names, real.len());
    let _ = writeln!(md, "## Time per scan (Table 10.2)\n");
    let mut t = Table::new([
        "data",
        "J",
        "VVL",
        "IEF",
        "SAM",
        "PLE",
        "PLE+",
        "PLE+ (NM)",
        "thesis VVL / IEF / SAM / PLE / PLE+ [s]",
        comparable::HEADER,
    ]);
    for (data, j, thesis) in TABLE_10_2 {
        let Some(results) = (if data == "real" {
            real_results.as_ref()
        } else {
            Some(sr)
        }) else {
            continue;
        };
        let ji = JS.iter().position(|&x| x == j).unwrap_or(0);
        let mut row = vec![data.to_owned(), j.to_string()];
        for vi in 0..VARIANTS.len() {
            let (m, _) = stat(results, vi, ji, |o| o.secs);
            row.push(format!("{} ms", fmt_num(m * 1e3, 3)));
        }
        row.push(
            thesis
                .iter()
                .map(|s| format!("{s}"))
                .collect::<Vec<_>>()
                .join(" / "),
        );
        row.push(time_comparable(if data == "real" {
            &real_text
        } else {
            SIM_DATA_TEXT
        }));
        t.row(row);
    }
    let _ = writeln!(md, "{}", t.to_markdown()?);
    let _ = writeln!(
        md,
        "The thesis times are MATLAB on one Intel Xeon 2.50 GHz thread; ours are Rust on the \
         machine above.\n"
    );

    // Speed aims and the solver comparison.
    let (ple, plus, nm) = (
        variant_index("PLE"),
        variant_index("PLE+"),
        variant_index("PLE+ (NM)"),
    );
    let speed_source = real_results.as_ref().unwrap_or(sr);
    let j20 = 1;
    let times = |vi: usize| {
        let mut v: Vec<f64> = speed_source[vi][j20].iter().map(|o| o.secs).collect();
        let med = median(&mut v);
        let p95 = v
            .get(((v.len() as f64) * 0.95) as usize)
            .copied()
            .unwrap_or(f64::NAN);
        let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
        (mean, med, p95)
    };
    let (ple_t, plus_t, nm_t) = (times(ple), times(plus), times(nm));
    let _ = writeln!(
        md,
        "## Speed aims (J = 20, {} scans, one thread per scan)\n",
        if real_results.is_some() {
            "real"
        } else {
            "simulated"
        }
    );
    let mut t = Table::new(["method", "mean", "median", "95th percentile", "aim", "met"]);
    for (label, (mean, med, p95), aim) in [
        ("PLE", ple_t, 1e-3),
        ("PLE+ (LM)", plus_t, 20e-3),
        ("PLE+ (NM)", nm_t, 20e-3),
    ] {
        t.row([
            label.to_owned(),
            format!("{:.3} ms", mean * 1e3),
            format!("{:.3} ms", med * 1e3),
            format!("{:.3} ms", p95 * 1e3),
            format!("≤ {} ms", aim * 1e3),
            if mean <= aim { "yes" } else { "no" }.to_owned(),
        ]);
    }
    let _ = writeln!(md, "{}", t.to_markdown()?);

    let _ = writeln!(md, "## PLE+ solver: Levenberg–Marquardt vs Nelder–Mead\n");
    let mut t = Table::new([
        "data",
        "J",
        "RMSE PLE [mm]",
        "RMSE LM [mm]",
        "RMSE NM [mm]",
        "time LM",
        "time NM",
    ]);
    for (data, results) in [("real", real_results.as_ref()), ("simulated", Some(sr))] {
        let Some(results) = results else { continue };
        for (ji, j) in JS.iter().enumerate() {
            let r = |vi| stat(results, vi, ji, |o| o.rmse_m).0 * 1e3;
            let s = |vi| stat(results, vi, ji, |o| o.secs).0 * 1e3;
            t.row([
                data.to_owned(),
                j.to_string(),
                fmt_num(r(ple), 2),
                fmt_num(r(plus), 2),
                fmt_num(r(nm), 2),
                format!("{} ms", fmt_num(s(plus), 2)),
                format!("{} ms", fmt_num(s(nm), 2)),
            ]);
        }
    }
    let _ = writeln!(md, "{}", t.to_markdown()?);

    // Example pictures.
    let example_config = PolylineConfig::new(Method::PlePlus, 20);
    if let Some(sample) = real.first() {
        let map = extract(&sample.scan, &example_config)?;
        write_figure(
            &fig_dir,
            "example-real.svg",
            &scan_svg(&sample.scan, &map, 600.0),
        )?;
        let _ = writeln!(
            md,
            "Example: PLE+ with J = 20 on {} (grey: endpoints, blue: polylines, red: vertices).\n\n\
             ![example, real](polylines/example-real.svg)\n",
            sample.source
        );
    }
    if let Some(sample) = sim
        .iter()
        .find(|s| s.source.contains("n = 12"))
        .or(sim.first())
    {
        let map = extract(
            &sample.scan,
            &PolylineConfig {
                max_edge_m: f64::INFINITY,
                ..example_config
            },
        )?;
        write_figure(
            &fig_dir,
            "example-sim.svg",
            &scan_svg(&sample.scan, &map, 600.0),
        )?;
        let _ = writeln!(
            md,
            "Example: PLE+ with J = 20 on simulated {}.\n\n![example, simulated](polylines/example-sim.svg)\n",
            sample.source
        );
    }

    // Ranking against the thesis.
    let _ = writeln!(md, "## Ranking of the methods vs the thesis\n");
    let _ = writeln!(md, "By mean RMSE (lower is better):\n");
    if let Some(results) = &real_results {
        for line in ranking(results) {
            let _ = writeln!(md, "- real, {line}");
        }
    }
    for line in ranking(sr) {
        let _ = writeln!(md, "- simulated, {line}");
    }
    let _ = writeln!(md);
    let mut notes = Vec::new();
    for (data, results) in [("real", real_results.as_ref()), ("simulated", Some(sr))] {
        let Some(results) = results else { continue };
        let plus_le_ple = (0..JS.len()).all(|ji| {
            stat(results, plus, ji, |o| o.rmse_m).0 <= stat(results, ple, ji, |o| o.rmse_m).0
        });
        let (ief, sam, vvl) = (
            variant_index("IEF"),
            variant_index("SAM"),
            variant_index("VVL"),
        );
        let ief_beats_sam = (0..JS.len()).all(|ji| {
            stat(results, ief, ji, |o| o.rmse_m).0 < stat(results, sam, ji, |o| o.rmse_m).0
                && stat(results, ief, ji, |o| o.f).0 >= stat(results, sam, ji, |o| o.f).0
        });
        let ple_best = (0..JS.len()).all(|ji| {
            let best_baseline = [vvl, ief, sam]
                .iter()
                .map(|&vi| stat(results, vi, ji, |o| o.rmse_m).0)
                .fold(f64::INFINITY, f64::min);
            stat(results, ple, ji, |o| o.rmse_m).0 < best_baseline
        });
        let f = |vi: usize| stat(results, vi, 1, |o| o.f).0;
        notes.push(format!(
            "- {data}: PLE+ RMSE ≤ PLE at every J: **{}** (thesis: always lower); PLE below every \
             baseline at every J: **{}** (thesis: PLE and PLE+ outperform all others); IEF beats SAM \
             in RMSE and f at every J: **{}** (thesis: yes). f at J = 20: VVL {:.3}, IEF {:.3}, SAM {:.3}, \
             PLE {:.3}, PLE+ {:.3} (thesis: IEF explains all rays, SAM misses many, VVL small on real \
             data and 1 in simulation, PLE/PLE+ 1 in simulation).",
            yes_no(plus_le_ple),
            yes_no(ple_best),
            yes_no(ief_beats_sam),
            f(vvl),
            f(ief),
            f(sam),
            f(ple),
            f(plus)
        ));
    }
    let _ = writeln!(md, "{}\n", notes.join("\n"));
    let _ = writeln!(
        md,
        "Comparable with the thesis' Fig. 10.4 statements: real rows: {}; simulated rows: {}. \
         The thesis gives its accuracies as plots, so orderings are compared, not digits.\n",
        if real_results.is_some() {
            comparable::no(&real_text)
        } else {
            "no real scans in this run".to_owned()
        },
        comparable::yes(SIM_DATA_TEXT),
    );
    if let Some(results) = &real_results {
        let vvl = variant_index("VVL");
        let lower: Vec<String> = JS
            .iter()
            .enumerate()
            .filter(|(ji, _)| {
                stat(results, vvl, *ji, |o| o.rmse_m).0 < stat(results, ple, *ji, |o| o.rmse_m).0
            })
            .map(|(ji, j)| {
                format!(
                    "J = {j} (f {:.3} vs {:.3})",
                    stat(results, vvl, ji, |o| o.f).0,
                    stat(results, ple, ji, |o| o.f).0
                )
            })
            .collect();
        if !lower.is_empty() {
            let _ = writeln!(
                md,
                "Where VVL has a lower RMSE than PLE on real scans it explains fewer rays: {}. \
                 VVL drops short polylines first (zero area cost) and spends its vertices on \
                 the long walls it keeps; PLE charges d_rm = 0.5 m for every ray it stops \
                 explaining and keeps more of the scan. RMSE alone rewards explaining less; the \
                 thesis' claim that PLE beats all baselines holds here for the pair (RMSE, f) \
                 but not for RMSE alone against VVL.\n",
                lower.join(", ")
            );
        }
    }
    let timing_source = real_results.as_ref().unwrap_or(sr);
    let mut order: Vec<(f64, &str)> = VARIANTS
        .iter()
        .enumerate()
        .filter(|(_, v)| v.label != "PLE+ (NM)")
        .map(|(vi, v)| (stat(timing_source, vi, 1, |o| o.secs).0, v.label))
        .collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0));
    let _ = writeln!(
        md,
        "Times: the thesis ranks VVL fastest, then IEF, PLE, PLE+, and SAM slowest (Table 10.2, \
         MATLAB). Measured order at J = 20 ({} scans): {}. SAM is no longer the slowest: the \
         thesis' SAM time reflects its MATLAB implementation, not the algorithm (it refits every \
         piece with a numerical optimiser; ours fits each piece in closed form). Each time is \
         the fastest of three runs, which removes most preemption by other jobs on this shared \
         2-core machine.",
        if real_results.is_some() {
            "real"
        } else {
            "simulated"
        },
        order
            .iter()
            .map(|(t, l)| format!("{l} {:.3} ms", t * 1e3))
            .collect::<Vec<_>>()
            .join(" < ")
    );

    let json = json!({
        "js": JS,
        "real": { "logs": logs.iter().map(|(n, c, b)| json!({"log": n, "scans": c, "beams": b})).collect::<Vec<_>>(), "results": json_real },
        "simulated": { "scans": sim.len(), "results": variant_json(sr) },
        "speed_j20": {
            "ple_mean_s": ple_t.0, "ple_plus_lm_mean_s": plus_t.0, "ple_plus_nm_mean_s": nm_t.0,
        },
    });
    Ok(EvalReport {
        name: NAME,
        title:
            "Polyline extraction: PLE, PLE+ and baselines (Schaefer ch. 10, Fig. 10.4, Table 10.2)"
                .into(),
        markdown: md,
        json,
        headline: None,
    })
}

/// Median RMSE per method at J index `ji`, as "VVL 12.3 mm, …".
fn median_rmse(results: &Results, ji: usize) -> String {
    VARIANTS
        .iter()
        .enumerate()
        .map(|(vi, v)| {
            let mut values: Vec<f64> = results[vi][ji]
                .iter()
                .map(|o| o.rmse_m)
                .filter(|x| x.is_finite())
                .collect();
            format!("{} {:.1} mm", v.label, median(&mut values) * 1e3)
        })
        .collect::<Vec<_>>()
        .join(", ")
}

fn yes_no(b: bool) -> &'static str {
    if b { "yes" } else { "no" }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn real_data_text_names_the_thesis_logs_we_lack() {
        let text = real_data_text(&["intel", "aces", "freiburg-campus", "fr-clinic"], 80);
        assert!(
            text.starts_with("80 real scans from 3 of the thesis' 13 Radish logs"),
            "{text}"
        );
        assert!(text.contains("absent: acapulco, belgioioso"), "{text}");
        assert!(text.contains("not in the thesis: fr-clinic"), "{text}");
        let cell = time_comparable(&text);
        assert!(
            cell.starts_with("no — other language and hardware"),
            "{cell}"
        );
    }
}
