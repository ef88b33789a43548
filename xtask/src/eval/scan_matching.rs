//! `cargo xtask eval scan-matching`: intensity calibration and Hector-style scan matching
//! (Khan 2017, ch. 3; spec `khan-2017.md` §3).
//!
//! * **Real logs** (occupancy residual; the raw SLAM-benchmark logs have no remissions):
//!   `carmen/raw/{intel, fr079, mit-csail}` matched scan by scan, scored against the poses
//!   of the corrected logs (scans paired by identical readings): relative-motion error of
//!   Kümmerle et al. (2009) over consecutive reference scans and the absolute error after
//!   rigid alignment. Variants: plain Hector (no odometry), odometry as the initial guess,
//!   odometry as a prior, and the odometry itself.
//! * **Calibration** (simulated, `raypath-sim`'s intensity model): LUT and range-only
//!   polynomial fitted to reference-surface samples; three test surfaces (Khan Fig. 3.4)
//!   corrected by the raw, range-only and LUT models; histogram overlap between surfaces
//!   and per-surface coefficient of variation.
//! * **Calibration on real scans**: the same LUT fitted on the road class of the real,
//!   SemanticKITTI-labelled KITTI frames and scored by the coefficient of variation per class
//!   on held-back frames ([`real_calib`]).
//! * **Calibration on real Ouster frames**: the LUT fitted on the ground of the real Ouster
//!   captures, on the raw signal and on the sensor's reflectivity, scored on held-back
//!   columns ([`real_ouster`]).
//! * **Failure case** (simulated, Khan Fig. 3.6): 8.5 m × 5.5 m room with reflectivity
//!   panels, ±60° field of view, stops facing single walls; occupancy, reflectivity and
//!   combined residuals scored against ground truth (and a 180° control).
//! * **Speed**: scans per second of each run (release build, one thread, machine shared).

mod real_calib;
mod real_ouster;
mod sim;

use std::fmt::Write;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use raypath_geometry::Pose2;
use raypath_io::carmen::LaserKind;
use raypath_io::sequence::{LaserChoice, PlanarFrame, PlanarOptions, pair_reference, read_planar};
use raypath_reflectivity::benchmark::{
    AlignedErrors, LogScan, RelativeErrors, aligned_errors, consecutive_relations, relative_errors,
    run_matcher,
};
use raypath_reflectivity::lut::CalibrationSample;
use raypath_reflectivity::{
    IntensityCorrection, IntensityLut, LutConfig, MapConfig, MatcherConfig, PointFilter,
    RangePolynomial, ResidualMode,
};
use raypath_sim::indoor::IntensityModel;
use raypath_sim::rng::stream;
use serde_json::{Value, json};

use super::{EvalContext, EvalReport, comparable};
use crate::table::{Table, fmt_num};

const NAME: &str = "scan-matching";
const SEED: u64 = 2017;

/// The real logs: name, raw log, corrected log.
const LOGS: [(&str, &str, &str); 3] = [
    (
        "intel",
        "carmen/raw/intel.clf.bz2",
        "carmen/corrected/intel-corrected.log.gz",
    ),
    (
        "fr079",
        "carmen/raw/fr079.clf.bz2",
        "carmen/corrected/freiburg-079-corrected.log.gz",
    ),
    (
        "mit-csail",
        "carmen/raw/mit-csail.clf.bz2",
        "carmen/corrected/csail-corrected.log.gz",
    ),
];

/// The "comparable" cell of the Kümmerle anchors beside our real rows.
const ANCHOR_COMPARABLE: &str = "no — same real log, but ours over consecutive corrected-log \
     scans, theirs over the benchmark's relation files; other matchers and hardware; values \
     recalled, not re-checked";

/// Kümmerle et al. (2009) relative-motion errors (translation m mean ± std, rotation °
/// mean ± std) for scan matching and graph-based SLAM, as recalled (the Intel
/// scan-matching row as ≈ 0.22 ± 0.30 m); not checked against the paper here.
const ANCHORS: [(&str, &str, &str); 3] = [
    (
        "intel",
        "0.220 ± 0.296 m, 1.7 ± 4.8°",
        "0.031 ± 0.026 m, 1.3 ± 4.7°",
    ),
    (
        "fr079",
        "0.258 ± 0.427 m, 1.7 ± 2.1°",
        "0.056 ± 0.042 m, 0.6 ± 0.6°",
    ),
    (
        "mit-csail",
        "0.106 ± 0.325 m, 1.4 ± 4.5°",
        "0.004 ± 0.009 m, 0.05 ± 0.08°",
    ),
];

/// Error summary of one run.
struct Scored {
    relative: RelativeErrors,
    aligned: AlignedErrors,
    scans_per_s: f64,
}

fn scored_json(s: &Scored) -> Value {
    json!({
        "relative": s.relative,
        "aligned": s.aligned,
        "scans_per_s": s.scans_per_s,
    })
}

/// The front-laser scans of a log.
fn front_laser(path: &Path) -> Result<Vec<PlanarFrame>> {
    let options = PlanarOptions {
        laser: LaserChoice::Front,
        ..PlanarOptions::default()
    };
    read_planar(path, &options).with_context(|| format!("reading {}", path.display()))
}

/// Pairs the raw scans with the scans of the corrected log `reference` (identical readings,
/// `raypath_io::sequence::pair_reference`): the indices of the paired raw scans and their
/// reference poses, in order.
fn paired(raw: &mut [PlanarFrame], reference: &Path) -> Result<(Vec<usize>, Vec<Pose2>)> {
    let reference = front_laser(reference)?;
    pair_reference(raw, &reference);
    Ok(raw
        .iter()
        .enumerate()
        .filter_map(|(i, f)| f.reference.map(|pose| (i, pose)))
        .unzip())
}

fn real_config() -> MatcherConfig {
    MatcherConfig {
        map: MapConfig {
            size_m: 160.0,
            ..MapConfig::default()
        },
        ..MatcherConfig::default()
    }
}

fn run_real(ctx: &EvalContext, md: &mut String) -> Result<Value> {
    let limit = if ctx.quick { Some(600) } else { None };
    let logs: Vec<_> = if ctx.quick {
        LOGS[..1].to_vec()
    } else {
        LOGS.to_vec()
    };
    let variants: [(&str, bool, Option<[f64; 3]>); 3] = [
        ("Hector, no odometry", false, None),
        ("Hector, odometry guess", true, None),
        ("Hector, odometry prior", true, Some([0.1, 0.1, 0.05])),
    ];
    let mut table = Table::new([
        "log",
        "scans",
        "relations",
        "method",
        "rel. transl. m (mean ± std)",
        "rel. rot. ° (mean ± std)",
        "ATE RMSE m",
        "ATE max m",
        "scans/s",
    ]);
    let mut out = Vec::new();
    for (name, raw_path, ref_path) in logs {
        let (raw_file, ref_file) = (ctx.data(raw_path), ctx.data(ref_path));
        if !raw_file.exists() || !ref_file.exists() {
            let _ = writeln!(
                md,
                "* `{raw_path}` or `{ref_path}` missing: {name} skipped."
            );
            continue;
        }
        let mut raw = front_laser(&raw_file)?;
        if let Some(n) = limit {
            raw.truncate(n);
        }
        let (pairs, truth) = paired(&mut raw, &ref_file)?;
        let relations = consecutive_relations(truth.len());
        let score = |poses: &[Pose2], seconds: f64| -> Scored {
            let est: Vec<Pose2> = pairs
                .iter()
                .filter_map(|&i| poses.get(i).copied())
                .collect();
            Scored {
                relative: relative_errors(&truth, &est, &relations),
                aligned: aligned_errors(&truth, &est),
                scans_per_s: raw.len() as f64 / seconds,
            }
        };
        let mut rows = Vec::new();
        let odometry: Vec<Pose2> = raw.iter().map(|s| s.world_from_laser).collect();
        rows.push(("odometry", score(&odometry, f64::NAN)));
        for (label, guess, prior) in variants {
            let config = MatcherConfig {
                odometry_sigma: prior,
                ..real_config()
            };
            let t = Instant::now();
            let (_, results) = run_matcher(&raw, config, &PointFilter::default(), None, guess)?;
            let seconds = t.elapsed().as_secs_f64();
            let poses: Vec<Pose2> = results.iter().map(|r| r.world_from_sensor).collect();
            rows.push((label, score(&poses, seconds)));
        }
        for (label, s) in &rows {
            table.row([
                name.to_string(),
                raw.len().to_string(),
                s.relative.translation_m.count.to_string(),
                label.to_string(),
                format!(
                    "{} ± {}",
                    fmt_num(s.relative.translation_m.mean, 3),
                    fmt_num(s.relative.translation_m.std, 3)
                ),
                format!(
                    "{} ± {}",
                    fmt_num(s.relative.rotation_rad.mean.to_degrees(), 2),
                    fmt_num(s.relative.rotation_rad.std.to_degrees(), 2)
                ),
                fmt_num(s.aligned.position_m.rms, 3),
                fmt_num(s.aligned.position_m.max, 3),
                fmt_num(s.scans_per_s, 0),
            ]);
            out.push(json!({ "log": name, "scans": raw.len(), "pairs": pairs.len(), "method": label, "errors": scored_json(s) }));
        }
        eprintln!(
            "scan-matching: {name} done ({} scans, {} pairs)",
            raw.len(),
            pairs.len()
        );
    }
    let _ = writeln!(md, "{}", table.to_markdown()?);
    let _ = writeln!(
        md,
        "Without odometry, the first bad relations on Intel fall on in-place turns of about \
         0.5 rad within 6–9 raw scans (≈ 0.08 rad per scan at Intel's ≈ 5 Hz): points 5 m away \
         move by ≈ 0.4 m between scans, beyond the basin of the coarsest (20 cm) level, and the \
         match slips by 0.2–0.7 m. Hector assumes scans at the laser's 40 Hz; with odometry as \
         the initial guess the same matcher stays within a few centimetres.\n"
    );
    Ok(Value::Array(out))
}

/// The generated indoor world `lab` (raypath-sim: 360° laser at 0.5° with remissions from the
/// same intensity model, noisy wheel odometry): all three residuals against its ground truth.
fn run_generated(ctx: &EvalContext, md: &mut String, lut: &IntensityCorrection) -> Result<Value> {
    let dir = crate::generate::ensure("indoor", ctx.quick)?;
    let find = |stem: &str| {
        ["", ".gz", ".bz2"]
            .iter()
            .map(|ext| dir.join(format!("{stem}{ext}")))
            .find(|p| p.exists())
    };
    let (Some(raw_file), Some(ref_file)) = (find("lab.clf"), find("lab-corrected.log")) else {
        let _ = writeln!(
            md,
            "* the generated `indoor/lab` logs are missing: skipped.\n"
        );
        return Ok(Value::Null);
    };
    let mut raw = front_laser(&raw_file)?;
    if ctx.quick {
        raw.truncate(300);
    }
    let (pairs, truth) = paired(&mut raw, &ref_file)?;
    let relations = consecutive_relations(truth.len());
    let mut table = Table::new([
        "residual",
        "odometry",
        "rel. transl. mm (mean ± std)",
        "rel. rot. ° (mean ± std)",
        "ATE RMSE m",
        "ATE max m",
        "scans/s",
    ]);
    let mut out = Vec::new();
    let odometry: Vec<Pose2> = pairs
        .iter()
        .filter_map(|&i| raw.get(i).map(|s| s.world_from_laser))
        .collect();
    let mut rows = vec![(
        "—".to_string(),
        "odometry only".to_string(),
        relative_errors(&truth, &odometry, &relations),
        aligned_errors(&truth, &odometry),
        f64::NAN,
    )];
    for guess in [false, true] {
        for mode in [
            ResidualMode::Occupancy,
            ResidualMode::Reflectivity,
            ResidualMode::Combined,
        ] {
            let config = MatcherConfig {
                mode,
                ..real_config()
            };
            let t = Instant::now();
            let (_, results) =
                run_matcher(&raw, config, &PointFilter::default(), Some(lut), guess)?;
            let sps = raw.len() as f64 / t.elapsed().as_secs_f64();
            let est: Vec<Pose2> = pairs
                .iter()
                .filter_map(|&i| results.get(i).map(|r| r.world_from_sensor))
                .collect();
            rows.push((
                mode.name().to_string(),
                if guess { "initial guess" } else { "none" }.to_string(),
                relative_errors(&truth, &est, &relations),
                aligned_errors(&truth, &est),
                sps,
            ));
        }
    }
    for (mode, odo, rel, ali, sps) in &rows {
        table.row([
            mode.clone(),
            odo.clone(),
            format!(
                "{} ± {}",
                fmt_num(1000.0 * rel.translation_m.mean, 1),
                fmt_num(1000.0 * rel.translation_m.std, 1)
            ),
            format!(
                "{} ± {}",
                fmt_num(rel.rotation_rad.mean.to_degrees(), 3),
                fmt_num(rel.rotation_rad.std.to_degrees(), 3)
            ),
            fmt_num(ali.position_m.rms, 3),
            fmt_num(ali.position_m.max, 3),
            fmt_num(*sps, 0),
        ]);
        out.push(json!({ "mode": mode, "odometry": odo, "relative": rel, "aligned": ali, "scans_per_s": sps }));
    }
    let _ = writeln!(
        md,
        "`datasets/generated/indoor/lab` (raypath-sim: offices and crossing corridors with glass, \
         furniture and posters; {} ROBOTLASER1 scans of 720 beams over 360° with remissions from \
         the same intensity model as above; noisy wheel odometry), scored against its corrected \
         log ({} pairs, relations between consecutive scans). ϱ̄ from the LUT above.\n",
        raw.len(),
        pairs.len()
    );
    let _ = writeln!(md, "{}", table.to_markdown()?);
    Ok(Value::Array(out))
}

/// Histogram overlap Σ min(p, q) of two samples over common bins.
fn overlap(a: &[f64], b: &[f64], lo: f64, hi: f64, bins: usize) -> f64 {
    let hist = |v: &[f64]| {
        let mut h = vec![0.0; bins];
        for &x in v {
            let k = (((x - lo) / (hi - lo)) * bins as f64)
                .floor()
                .clamp(0.0, (bins - 1) as f64) as usize;
            if let Some(c) = h.get_mut(k) {
                *c += 1.0 / v.len() as f64;
            }
        }
        h
    };
    hist(a).iter().zip(hist(b)).map(|(p, q)| p.min(q)).sum()
}

fn coefficient_of_variation(v: &[f64]) -> f64 {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
    var.sqrt() / mean
}

fn quantile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    let k = ((v.len() - 1) as f64 * q).round() as usize;
    v.get(k).copied().unwrap_or(f64::NAN)
}

/// The intensity LUT fitted to `n` reference-surface samples of the simulator's intensity
/// model (the calibration of this evaluation), for other evaluations on the generated worlds.
pub(super) fn simulated_lut(n: usize) -> Result<IntensityCorrection> {
    let reference = sim::reference_samples(&IntensityModel::default(), n, SEED);
    Ok(IntensityCorrection::Lut(IntensityLut::fit(
        &reference,
        &LutConfig::default(),
    )?))
}

fn run_calibration(ctx: &EvalContext, md: &mut String) -> Result<(Value, IntensityCorrection)> {
    let model = IntensityModel::default();
    let (n_ref, n_surface) = if ctx.quick {
        (4000, 3000)
    } else {
        (20000, 12000)
    };
    let reference = sim::reference_samples(&model, n_ref, SEED);
    let surfaces = sim::surface_samples(&model, n_surface, SEED);
    let t = Instant::now();
    let lut = IntensityLut::fit(&reference, &LutConfig::default())?;
    let fit_s = t.elapsed().as_secs_f64();
    let poly = RangePolynomial::fit(&reference, 4, 10f64.to_radians())?;
    let models = [
        IntensityCorrection::Raw,
        IntensityCorrection::Range(poly),
        IntensityCorrection::Lut(lut.clone()),
    ];
    let mut table = Table::new([
        "model",
        "overlap 1–2",
        "overlap 1–3",
        "overlap 2–3",
        "CV surface 1",
        "CV surface 2",
        "CV surface 3",
        "mean ϱ̄ (1 / 2 / 3)",
    ]);
    let mut out = Vec::new();
    for m in &models {
        let values: Vec<Vec<f64>> = surfaces
            .iter()
            .map(|s| {
                s.iter()
                    .filter_map(|c: &CalibrationSample| {
                        m.relative(c.intensity, c.range_m, c.incidence_rad)
                    })
                    .collect()
            })
            .collect();
        let mut pooled: Vec<f64> = values.iter().flatten().copied().collect();
        let (lo, hi) = (quantile(&mut pooled, 0.005), quantile(&mut pooled, 0.995));
        let ov = |i: usize, j: usize| overlap(&values[i], &values[j], lo, hi, 60);
        let cv: Vec<f64> = values.iter().map(|v| coefficient_of_variation(v)).collect();
        let means: Vec<f64> = values
            .iter()
            .map(|v| v.iter().sum::<f64>() / v.len() as f64)
            .collect();
        let (o12, o13, o23) = (ov(0, 1), ov(0, 2), ov(1, 2));
        table.row([
            m.name().to_string(),
            fmt_num(o12, 3),
            fmt_num(o13, 3),
            fmt_num(o23, 3),
            fmt_num(cv[0], 3),
            fmt_num(cv[1], 3),
            fmt_num(cv[2], 3),
            if matches!(m, IntensityCorrection::Raw) {
                format!("{:.0} / {:.0} / {:.0}", means[0], means[1], means[2])
            } else {
                format!("{:.3} / {:.3} / {:.3}", means[0], means[1], means[2])
            },
        ]);
        out.push(json!({ "model": m.name(), "overlap": [o12, o13, o23], "cv": cv, "mean": means }));
    }
    let inside = lut.inside_hull.iter().filter(|&&b| b).count();
    let _ = writeln!(
        md,
        "Reference surface (ρ = {}) sampled {n_ref} times over r ∈ [0.2, 19] m, α ≤ 80° near and \
         ≤ 60° far; three test surfaces of ρ = {:?} ({n_surface} observations each; surface 1: \
         r 1–12 m, α 0–60°; surfaces 2 and 3: r 2.5–3.5 m, α 0–70° and 0–30°). Angles carry 1° \
         of normal-estimation noise. LUT: {} × {} entries (Δr = 1 cm, Δα = 0.5°), {:.1} % inside \
         the samples' hull, fitted in {:.2} s; range model: degree-4 polynomial on α ≤ 10°. \
         Overlap = Σ min(p, q) of 60-bin histograms over the pooled 0.5–99.5 % range (1 = \
         identical, 0 = separated); true ratios ρ/ρ_ref are 0.625 / 0.4375 / 0.3125.\n",
        sim::REFERENCE_REFLECTIVITY,
        sim::SURFACES.iter().map(|s| s.0).collect::<Vec<_>>(),
        lut.ranges,
        lut.angles,
        100.0 * inside as f64 / lut.values.len() as f64,
        fit_s
    );
    let _ = writeln!(md, "{}", table.to_markdown()?);
    Ok((
        json!({ "models": out, "lut_fit_s": fit_s }),
        IntensityCorrection::Lut(lut),
    ))
}

fn run_failure_case(
    ctx: &EvalContext,
    md: &mut String,
    lut: &IntensityCorrection,
) -> Result<Value> {
    let model = IntensityModel::default();
    let scene = sim::room(SEED)?;
    let laps = if ctx.quick { 1 } else { 3 };
    let rate_hz = 20.0;
    let truth = sim::path(laps, rate_hz);
    let make_scans = |half_fov_deg: f64, beams: usize| -> Vec<LogScan> {
        let mut draw = sim::Draw::new(SEED + 7);
        let mut rng = stream(SEED, 3, beams as u64);
        truth
            .iter()
            .enumerate()
            .map(|(k, pose)| LogScan {
                scan: sim::scan(
                    &scene,
                    pose,
                    beams,
                    half_fov_deg.to_radians(),
                    &model,
                    &mut draw,
                    &mut rng,
                ),
                world_from_laser: *pose,
                ipc_timestamp_secs: k as f64 / rate_hz,
                logger_timestamp_secs: k as f64 / rate_hz,
                line: k as u64 + 1,
                kind: LaserKind::RobotLaser1,
            })
            .collect()
    };
    let narrow = make_scans(60.0, 121);
    let wide = make_scans(90.0, 181);
    let runs: [(&str, &[LogScan], ResidualMode, Option<&str>); 4] = [
        (
            "occupancy, ±60°",
            &narrow,
            ResidualMode::Occupancy,
            Some("room-occupancy-60"),
        ),
        (
            "reflectivity, ±60°",
            &narrow,
            ResidualMode::Reflectivity,
            None,
        ),
        (
            "combined, ±60°",
            &narrow,
            ResidualMode::Combined,
            Some("room-combined-60"),
        ),
        (
            "occupancy, ±90° (control)",
            &wide,
            ResidualMode::Occupancy,
            None,
        ),
    ];
    let relations = consecutive_relations(truth.len());
    let mut table = Table::new([
        "residual, field of view",
        "rel. transl. mm (mean ± std)",
        "rel. rot. ° (mean ± std)",
        "ATE RMSE m",
        "ATE max m",
        "final error m",
        "scans/s",
    ]);
    let mut out = Vec::new();
    for (label, scans, mode, figure) in runs {
        let config = MatcherConfig {
            mode,
            map: MapConfig {
                size_m: 30.0,
                ..MapConfig::default()
            },
            ..MatcherConfig::default()
        };
        let t = Instant::now();
        let (matcher, results) =
            run_matcher(scans, config, &PointFilter::default(), Some(lut), false)?;
        let seconds = t.elapsed().as_secs_f64();
        if let (Some(file), Some(level)) = (figure, matcher.map().levels().first()) {
            let dir = ctx.figure_dir(NAME)?;
            write_occupancy_png(level, &dir.join(format!("{file}-occupancy.png")))?;
            if mode != ResidualMode::Occupancy {
                raypath_reflectivity::export::write_reflectivity_png(
                    level,
                    &dir.join(format!("{file}-reflectivity.png")),
                )?;
            }
        }
        // The map frame starts at the first scan: express the estimate in the world frame.
        let start = truth.first().copied().unwrap_or_else(Pose2::identity);
        let est: Vec<Pose2> = results
            .iter()
            .map(|r| start * r.world_from_sensor)
            .collect();
        let rel = relative_errors(&truth, &est, &relations);
        let ali = aligned_errors(&truth, &est);
        let final_err = match (truth.last(), est.last()) {
            (Some(g), Some(e)) => (g.translation() - e.translation()).norm(),
            _ => f64::NAN,
        };
        let sps = scans.len() as f64 / seconds;
        table.row([
            label.to_string(),
            format!(
                "{} ± {}",
                fmt_num(1000.0 * rel.translation_m.mean, 1),
                fmt_num(1000.0 * rel.translation_m.std, 1)
            ),
            format!(
                "{} ± {}",
                fmt_num(rel.rotation_rad.mean.to_degrees(), 3),
                fmt_num(rel.rotation_rad.std.to_degrees(), 3)
            ),
            fmt_num(ali.position_m.rms, 3),
            fmt_num(ali.position_m.max, 3),
            fmt_num(final_err, 3),
            fmt_num(sps, 0),
        ]);
        out.push(json!({ "run": label, "relative": rel, "aligned": ali, "final_error_m": final_err, "scans_per_s": sps }));
    }
    let _ = writeln!(
        md,
        "Room [0, 8.5] × [0, 5.5] m, walls of panels 0.3–1.2 m long with ρ ∈ [0.1, 0.9]; {} scans \
         at {rate_hz} Hz ({laps} lap(s)): from the centre to stops 0.7 m in front of each wall's \
         middle, where the robot turns to face the wall (with ±60° only that wall is in view, so \
         the position along it is unobservable from geometry) and pauses 1 s. 0.4 m/s, 0.6 rad/s, \
         σ_r = 1 cm, no odometry (as Hector). ϱ̄ from the LUT above with PCA normals of the scan.\n",
        truth.len()
    );
    let _ = writeln!(md, "{}", table.to_markdown()?);
    let _ = writeln!(
        md,
        "Maps (finest level, 5 cm) after the run: occupancy-only (left: the map smears where \
         the position along a wall slid) and combined (right), and the combined run's mean \
         reflectivity per cell (bottom; brighter = higher ϱ̄).\n\n\
         ![occupancy-only map](scan-matching/room-occupancy-60-occupancy.png) \
         ![combined map](scan-matching/room-combined-60-occupancy.png)\n\n\
         ![reflectivity map](scan-matching/room-combined-60-reflectivity.png)\n"
    );
    Ok(Value::Array(out))
}

/// Writes the occupancy of a level as a PNG (free white, occupied black, unknown grey),
/// cropped to the observed cells.
fn write_occupancy_png(level: &raypath_reflectivity::GridLevel, path: &Path) -> Result<()> {
    let (mut i0, mut j0, mut i1, mut j1) = (usize::MAX, usize::MAX, 0, 0);
    for j in 0..level.height() {
        for i in 0..level.width() {
            if level.log_odds(i, j) != 0.0 {
                (i0, j0, i1, j1) = (i0.min(i), j0.min(j), i1.max(i + 1), j1.max(j + 1));
            }
        }
    }
    if i1 == 0 {
        return Ok(());
    }
    let mut img = image::GrayImage::new((i1 - i0) as u32, (j1 - j0) as u32);
    for (row, j) in (j0..j1).rev().enumerate() {
        for (col, i) in (i0..i1).enumerate() {
            let l = level.log_odds(i, j);
            let v = if l == 0.0 {
                160
            } else {
                (255.0 * (1.0 - raypath_reflectivity::probability(l))) as u8
            };
            img.put_pixel(col as u32, row as u32, image::Luma([v]));
        }
    }
    img.save(path)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// Runs the evaluation.
pub fn run(ctx: &EvalContext) -> Result<EvalReport> {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "Khan (2017) ch. 3: Hector-style multi-resolution scan matching (3 levels, \
         finest 5 cm, update factors 0.4 / 0.9, 3 + 3 + 5 Gauss–Newton iterations, map updates \
         after 0.4 m or 0.9 rad) with occupancy, reflectivity or combined residuals; intensity \
         calibration by LUT. Release build, one thread; the machine was shared with other jobs, \
         so absolute speeds are lower bounds — compare rows of one run.{}\n",
        if ctx.quick {
            " **Quick run**: the first 600 scans of Intel, one lap of the room, fewer calibration samples."
        } else {
            ""
        }
    );
    let _ = writeln!(md, "## Real logs (occupancy residual)\n");
    let _ = writeln!(
        md,
        "Relations join consecutive scans of the corrected log (the benchmark's own relation \
         files are not in the data set, so the numbers are comparable in kind, not identical in \
         protocol); the raw scans are paired with them by identical readings. Anchors: Kümmerle \
         et al. (2009) as recalled — the issue recalls ≈ 0.22 ± 0.30 m for scan matching on \
         Intel; the other values are from memory of the paper's table and were **not \
         re-checked** (the paper is not available offline).\n"
    );
    let mut anchors = Table::new([
        "log",
        "scan matching (Kümmerle 2009)",
        "graph SLAM (Kümmerle 2009)",
        comparable::HEADER,
    ]);
    for (log, sm, graph) in ANCHORS {
        anchors.row([
            log.to_owned(),
            sm.to_owned(),
            graph.to_owned(),
            ANCHOR_COMPARABLE.to_owned(),
        ]);
    }
    let _ = writeln!(md, "{}", anchors.to_markdown()?);
    let real = run_real(ctx, &mut md)?;
    let speeds: Vec<(String, f64)> = real
        .as_array()
        .map(|rows| {
            rows.iter()
                .filter_map(|r| {
                    let sps = r["errors"]["scans_per_s"].as_f64()?;
                    let label = format!("{} / {}", r["log"].as_str()?, r["method"].as_str()?);
                    sps.is_finite().then_some((label, sps))
                })
                .collect()
        })
        .unwrap_or_default();
    if let Some((slowest, sps)) = speeds.iter().min_by(|a, b| a.1.total_cmp(&b.1)) {
        let _ = writeln!(
            md,
            "**Speed** (aim ≥ 200 scans/s for 180-beam scans at 5 cm): slowest run {slowest} \
             at {sps:.0} scans/s (Intel has 180 beams; fr079 360, mit-csail 361), including map \
             updates, under load from other jobs. `cargo bench -p raypath-reflectivity` measures \
             the matcher alone on synthetic 180-beam scans.\n"
        );
    }
    let _ = writeln!(md, "## Intensity calibration (simulated, Khan Fig. 3.4)\n");
    let _ = writeln!(md, "{}", super::sim::gap_note(ctx)?);
    let (calibration, lut) = run_calibration(ctx, &mut md)?;
    let _ = writeln!(
        md,
        "## Intensity calibration on real KITTI scans (real, Khan Fig. 3.4 in real form)\n"
    );
    let real_calibration = real_calib::run(ctx, &mut md)?;
    let ouster_calibration = real_ouster::run(ctx, &mut md)?;
    let _ = writeln!(md, "## Failure case (simulated, Khan Fig. 3.6)\n");
    let failure = run_failure_case(ctx, &mut md, &lut)?;
    let _ = writeln!(
        md,
        "## Generated indoor world with remissions (all three residuals)\n"
    );
    let generated = run_generated(ctx, &mut md, &lut)?;
    Ok(EvalReport {
        name: NAME,
        title: "Intensity calibration and Hector-style scan matching (Khan ch. 3)".into(),
        markdown: md,
        json: json!({ "real": real, "calibration": calibration, "real_calibration": real_calibration, "ouster_calibration": ouster_calibration, "failure_case": failure, "generated_lab": generated }),
        headline: headline(&real, &real_calibration, &ouster_calibration),
    })
}

/// The page's headline: Hector-style matching on the real logs, then the intensity
/// calibration on the real KITTI and Ouster frames.
fn headline(real: &Value, kitti: &Value, ouster: &Value) -> Option<String> {
    let logs: Vec<String> = real
        .as_array()
        .into_iter()
        .flatten()
        .filter(|r| r["method"] == "Hector, odometry prior")
        .filter_map(|r| {
            let t = r["errors"]["relative"]["translation_m"]["mean"].as_f64()?;
            let a = r["errors"]["relative"]["rotation_rad"]["mean"].as_f64()?;
            Some(format!(
                "{} {:.3} m / {:.2}°",
                r["log"].as_str()?,
                t,
                a.to_degrees()
            ))
        })
        .collect();
    let mut parts = Vec::new();
    if !logs.is_empty() {
        parts.push(format!(
            "Real logs, Hector-style matching with odometry prior, mean relative error: {}",
            logs.join(", ")
        ));
    }
    let cv = |rows: &Value, model: &str| -> Vec<f64> {
        rows.as_array()
            .into_iter()
            .flatten()
            .find(|r| r["model"] == model)
            .and_then(|r| r["cv"].as_array())
            .map(|v| v.iter().filter_map(Value::as_f64).collect())
            .unwrap_or_default()
    };
    let rows = &kitti["models_covered_only"];
    let (raw, lut) = (cv(rows, "raw"), cv(rows, "lut"));
    if !raw.is_empty() && raw.len() == lut.len() {
        parts.push(format!(
            "real KITTI intensity calibration (LUT fitted on the road): lower CV than the raw \
             reflectance for {} of {} classes",
            raw.iter().zip(&lut).filter(|(r, l)| l < r).count(),
            raw.len()
        ));
    }
    let ground: Vec<String> = ouster["rows"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|r| r["channel"] == "signal")
        .filter_map(|r| Some((r["model"].as_str()?, r["cv"].as_f64()?)))
        .map(|(model, cv)| format!("{model} {cv:.2}"))
        .collect();
    if !ground.is_empty() {
        parts.push(format!(
            "real Ouster raw signal, CV on held-back ground: {}",
            ground.join(", ")
        ));
    }
    (!parts.is_empty()).then(|| format!("{}.", parts.join("; ")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// The headline from known rows: the real logs' odometry-prior errors, the KITTI classes
    /// where the LUT lowers the CV, the Ouster ground CVs; nothing when nothing ran.
    #[test]
    fn headline_from_known_rows() {
        let real = json!([
            {"log": "intel", "method": "Hector, odometry prior",
             "errors": {"relative": {"translation_m": {"mean": 0.03},
                                     "rotation_rad": {"mean": 0.5f64.to_radians()}}}},
            {"log": "intel", "method": "Hector alone",
             "errors": {"relative": {"translation_m": {"mean": 9.0},
                                     "rotation_rad": {"mean": 1.0}}}},
        ]);
        let kitti = json!({"models_covered_only": [
            {"model": "raw", "cv": [0.5, 0.4]},
            {"model": "lut", "cv": [0.4, 0.6]},
        ]});
        let ouster = json!({"rows": [
            {"channel": "signal", "model": "raw", "cv": 0.79},
            {"channel": "reflectivity", "model": "raw", "cv": 1.38},
        ]});
        let h = headline(&real, &kitti, &ouster).unwrap();
        assert_eq!(
            h,
            "Real logs, Hector-style matching with odometry prior, mean relative error: intel \
             0.030 m / 0.50°; real KITTI intensity calibration (LUT fitted on the road): lower \
             CV than the raw reflectance for 1 of 2 classes; real Ouster raw signal, CV on \
             held-back ground: raw 0.79."
        );
        assert!(headline(&json!([]), &json!({}), &json!({})).is_none());
    }
}
