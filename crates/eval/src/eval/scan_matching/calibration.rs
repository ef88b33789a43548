//! Intensity calibration on simulated samples (Khan Fig. 3.4): the LUT and the range-only
//! polynomial fitted to reference-surface samples of the simulator's intensity model, scored
//! on three test surfaces by histogram overlap and coefficient of variation. One unit, which
//! also measures the note on how far simulated scans are from real ones.

use std::fmt::Write;
use std::time::Instant;

use anyhow::Result;
use raypath_reflectivity::lut::CalibrationSample;
use raypath_reflectivity::{IntensityCorrection, IntensityLut, LutConfig, RangePolynomial};
use raypath_sim::indoor::IntensityModel;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use super::stats::{coefficient_of_variation, overlap, quantile};
use super::{Num, SEED, nums, reference_count, sim, values};
use crate::eval::EvalContext;
use crate::eval::stages::float;
use crate::table::{Table, fmt_num};

/// The unit's result.
#[derive(Debug, Serialize, Deserialize)]
pub(super) struct CalibrationUnit {
    /// How far simulated scans are from real ones (`eval sim`'s gap note).
    pub gap_note: String,
    /// Reference-surface samples.
    pub reference_samples: usize,
    /// Observations per test surface.
    pub surface_samples: usize,
    /// LUT rows (ranges) and columns (angles).
    pub lut_ranges: usize,
    pub lut_angles: usize,
    /// Share of the LUT's entries inside the samples' hull, %.
    #[serde(with = "float")]
    pub inside_percent: f64,
    /// The LUT's fit time (s).
    #[serde(with = "float")]
    pub lut_fit_s: f64,
    /// Raw, range, LUT.
    pub models: Vec<ModelScores>,
}

/// One correction model on the three test surfaces.
#[derive(Debug, Serialize, Deserialize)]
pub(super) struct ModelScores {
    pub model: String,
    /// Overlap of surfaces 1–2, 1–3, 2–3.
    pub overlap: Vec<Num>,
    /// Per surface.
    pub cv: Vec<Num>,
    /// Per surface: the mean corrected value.
    pub mean: Vec<Num>,
}

/// Fits the models and scores them (the unit `calibration`).
pub(super) fn measure(ctx: &EvalContext) -> Result<CalibrationUnit> {
    let gap_note = crate::eval::sim::gap_note(ctx)?;
    let model = IntensityModel::default();
    let n_ref = reference_count(ctx.quick);
    let n_surface = if ctx.quick { 3000 } else { 12000 };
    let reference = sim::reference_samples(&model, n_ref, SEED);
    let surfaces = sim::surface_samples(&model, n_surface, SEED);
    let t = Instant::now();
    let lut = IntensityLut::fit(&reference, &LutConfig::default())?;
    let lut_fit_s = t.elapsed().as_secs_f64();
    let poly = RangePolynomial::fit(&reference, 4, 10f64.to_radians())?;
    let inside = lut.inside_hull.iter().filter(|&&b| b).count();
    let inside_percent = 100.0 * inside as f64 / lut.values.len() as f64;
    let (lut_ranges, lut_angles) = (lut.ranges, lut.angles);
    let models = [
        IntensityCorrection::Raw,
        IntensityCorrection::Range(poly),
        IntensityCorrection::Lut(lut),
    ];
    Ok(CalibrationUnit {
        gap_note,
        reference_samples: n_ref,
        surface_samples: n_surface,
        lut_ranges,
        lut_angles,
        inside_percent,
        lut_fit_s,
        models: models.iter().map(|m| scores(m, &surfaces)).collect(),
    })
}

/// One model's scores on the test surfaces.
fn scores(model: &IntensityCorrection, surfaces: &[Vec<CalibrationSample>]) -> ModelScores {
    let values: Vec<Vec<f64>> = surfaces
        .iter()
        .map(|s| {
            s.iter()
                .filter_map(|c| model.relative(c.intensity, c.range_m, c.incidence_rad))
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
    ModelScores {
        model: model.name().to_owned(),
        overlap: nums(&[ov(0, 1), ov(0, 2), ov(1, 2)]),
        cv: nums(&cv),
        mean: nums(&means),
    }
}

/// The section's JSON as the page writes it.
pub(super) fn json(unit: &CalibrationUnit) -> Value {
    let models: Vec<Value> = unit
        .models
        .iter()
        .map(|m| {
            json!({ "model": m.model, "overlap": values(&m.overlap), "cv": values(&m.cv),
                    "mean": values(&m.mean) })
        })
        .collect();
    json!({ "models": models, "lut_fit_s": unit.lut_fit_s })
}

/// The section's text and table (after the gap note).
pub(super) fn markdown(unit: &CalibrationUnit) -> Result<String> {
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
    for m in &unit.models {
        let (o, cv, means) = (values(&m.overlap), values(&m.cv), values(&m.mean));
        let mut row = vec![m.model.clone()];
        row.extend(o.iter().chain(&cv).map(|v| fmt_num(*v, 3)));
        // The raw intensities are counts, the corrected ones ratios.
        let decimals = if m.model == "raw" { 0 } else { 3 };
        let shown: Vec<String> = means.iter().map(|v| format!("{v:.decimals$}")).collect();
        row.push(shown.join(" / "));
        table.row(row);
    }
    let mut md = String::new();
    let _ = writeln!(
        md,
        "Reference surface (ρ = {}) sampled {} times over r ∈ [0.2, 19] m, α ≤ 80° near and \
         ≤ 60° far; three test surfaces of ρ = {:?} ({} observations each; surface 1: \
         r 1–12 m, α 0–60°; surfaces 2 and 3: r 2.5–3.5 m, α 0–70° and 0–30°). Angles carry 1° \
         of normal-estimation noise. LUT: {} × {} entries (Δr = 1 cm, Δα = 0.5°), {:.1} % inside \
         the samples' hull, fitted in {:.2} s; range model: degree-4 polynomial on α ≤ 10°. \
         Overlap = Σ min(p, q) of 60-bin histograms over the pooled 0.5–99.5 % range (1 = \
         identical, 0 = separated); true ratios ρ/ρ_ref are 0.625 / 0.4375 / 0.3125.\n",
        sim::REFERENCE_REFLECTIVITY,
        unit.reference_samples,
        sim::SURFACES.iter().map(|s| s.0).collect::<Vec<_>>(),
        unit.surface_samples,
        unit.lut_ranges,
        unit.lut_angles,
        unit.inside_percent,
        unit.lut_fit_s
    );
    let _ = writeln!(md, "{}", table.to_markdown()?);
    Ok(md)
}
