//! Intensity calibration on real KITTI scans (Khan 2017 §3.3, Fig. 3.4 in real form): the LUT
//! `I_ref(r, α)` fitted on the road class of SemanticKITTI as the reference surface, with
//! angles of incidence from local PCA normals, and scored by the coefficient of variation of
//! the corrected intensity per class on held-back frames. One unit: the LUT is fitted on the
//! road samples of every sequence pooled.

use std::fmt::Write;

use anyhow::Result;
use nalgebra::Point3;
use raypath_io::kitti::{KittiSequence, PointLabel};
use raypath_reflectivity::lut::CalibrationSample;
use raypath_reflectivity::normals::incidence_angle;
use raypath_reflectivity::{IntensityCorrection, IntensityLut, LutConfig, RangePolynomial};
use raypath_registration::{RegistrationConfig, surface_normals};
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use super::stats::{coefficient_of_variation, overlap, quantile};
use crate::eval::EvalContext;
use crate::eval::stages::float;
use crate::table::{Table, fmt_num};

/// The scored classes (SemanticKITTI ids): road is the reference surface.
const CLASSES: [(u16, &str); 4] = [
    (40, "road"),
    (48, "sidewalk"),
    (50, "building"),
    (70, "vegetation"),
];
/// Frames 0–4 of each sequence fit the models; frames 5–9 are held back for scoring.
const FIT_FRAMES: u64 = 5;
/// Neighbours and radius of the PCA normals.
const NORMAL_NEIGHBOURS: usize = 16;
const NORMAL_RADIUS_M: f64 = 0.6;
/// Largest number of road samples used (a deterministic stride picks them).
const MAX_FIT_SAMPLES: usize = 60_000;
/// The road samples are averaged in (r, α) bins of this size before the LUT is fitted, and
/// bins with fewer samples are dropped: one real road point's intensity varies with the laser
/// that measured it and the asphalt's texture (raw CV ≈ 0.5), and a table through single
/// samples divides by near-zero values.
const BIN_RANGE_M: f64 = 1.0;
const BIN_ANGLE_DEG: f64 = 2.0;
const BIN_MIN_SAMPLES: usize = 10;

/// The mean sample of each (r, α) bin holding at least [`BIN_MIN_SAMPLES`] samples.
pub(super) fn binned_means(samples: &[CalibrationSample]) -> Vec<CalibrationSample> {
    let mut bins: std::collections::BTreeMap<(i64, i64), (CalibrationSample, usize)> =
        Default::default();
    for s in samples {
        let key = (
            (s.range_m / BIN_RANGE_M).floor() as i64,
            (s.incidence_rad.to_degrees() / BIN_ANGLE_DEG).floor() as i64,
        );
        let (sum, n) = bins.entry(key).or_insert((
            CalibrationSample {
                range_m: 0.0,
                incidence_rad: 0.0,
                intensity: 0.0,
            },
            0,
        ));
        sum.range_m += s.range_m;
        sum.incidence_rad += s.incidence_rad;
        sum.intensity += s.intensity;
        *n += 1;
    }
    bins.into_values()
        .filter(|(_, n)| *n >= BIN_MIN_SAMPLES)
        .map(|(sum, n)| CalibrationSample {
            range_m: sum.range_m / n as f64,
            incidence_rad: sum.incidence_rad / n as f64,
            intensity: sum.intensity / n as f64,
        })
        .collect()
}

/// Samples `(r, α, I)` of one class, split into fit and held-back frames.
#[derive(Default)]
struct ClassSamples {
    fit: Vec<CalibrationSample>,
    held: Vec<CalibrationSample>,
}

/// The samples of the scored classes of one frame, every `stride`-th labelled point.
fn frame_samples(
    cloud: &raypath_geometry::PointCloud,
    labels: &[PointLabel],
    stride: usize,
) -> Vec<(usize, CalibrationSample)> {
    let points: Vec<Point3<f64>> = (0..cloud.len()).map(|i| cloud.point_f64(i)).collect();
    let config = RegistrationConfig {
        normal_neighbours: NORMAL_NEIGHBOURS,
        normal_radius_m: NORMAL_RADIUS_M,
        ..RegistrationConfig::default()
    };
    let normals = surface_normals(&points, &Point3::origin(), &config);
    let Some(intensity) = &cloud.intensity else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let mut seen = 0usize;
    for (i, label) in labels.iter().enumerate() {
        let Some(class) = CLASSES.iter().position(|c| c.0 == label.class) else {
            continue;
        };
        seen += 1;
        if seen % stride != 0 {
            continue;
        }
        let (Some(p), Some(Some(n))) = (points.get(i), normals.get(i)) else {
            continue;
        };
        out.push((
            class,
            CalibrationSample {
                range_m: p.coords.norm(),
                incidence_rad: incidence_angle([p.x, p.y, p.z], [n.x, n.y, n.z]),
                intensity: f64::from(intensity[i]),
            },
        ));
    }
    out
}

/// The unit's result.
#[derive(Debug, Serialize, Deserialize)]
pub(super) struct KittiUnit {
    /// The section's JSON as the page writes it (`{"skipped": …}` without labelled frames).
    pub json: Value,
    /// What the text says beyond the JSON; `None` when skipped.
    pub fit: Option<FitFacts>,
}

/// The sampling and the fitted LUT's size.
#[derive(Debug, Serialize, Deserialize)]
pub(super) struct FitFacts {
    /// Every `stride`-th labelled point was used.
    pub stride: usize,
    /// LUT rows (ranges) and columns (angles).
    pub lut_ranges: usize,
    pub lut_angles: usize,
    /// Share of the LUT's entries inside the samples' hull, %.
    #[serde(with = "float")]
    pub inside_percent: f64,
}

/// The samples of every scored class of the labelled `sequences` (those without labels are
/// left out) and the sequences used.
fn collect(
    ctx: &EvalContext,
    sequences: &[&'static str],
    stride: usize,
) -> Result<(Vec<ClassSamples>, Vec<&'static str>)> {
    let mut classes: Vec<ClassSamples> = CLASSES.iter().map(|_| Default::default()).collect();
    let mut used = Vec::new();
    for seq in sequences {
        let dir = ctx.data(&format!("kitti/sequences/{seq}"));
        if !dir.join("labels").is_dir() {
            eprintln!(
                "scan-matching: {} has no labels, skipping it",
                dir.display()
            );
            continue;
        }
        let sequence = KittiSequence::open(&dir)?;
        for scan in sequence.scans() {
            let scan = scan?;
            let Some(labels) = sequence.labels(scan.frame)? else {
                continue;
            };
            for (class, sample) in frame_samples(&scan.points, &labels, stride) {
                let bucket = &mut classes[class];
                if scan.frame < FIT_FRAMES {
                    bucket.fit.push(sample);
                } else {
                    bucket.held.push(sample);
                }
            }
        }
        used.push(*seq);
    }
    Ok((classes, used))
}

/// Fits the models on the road and scores them per class (the unit `kitti-calibration`).
pub(super) fn measure(ctx: &EvalContext) -> Result<KittiUnit> {
    let sequences: &[&str] = if ctx.quick {
        &["00"]
    } else {
        &["00", "01", "04", "07"]
    };
    let stride = if ctx.quick { 8 } else { 2 };
    let (classes, used) = collect(ctx, sequences, stride)?;
    if used.is_empty() {
        return Ok(KittiUnit {
            json: json!({ "skipped": "no labelled KITTI frames" }),
            fit: None,
        });
    }
    let road = &classes[0].fit;
    let step = road.len().div_ceil(MAX_FIT_SAMPLES).max(1);
    let raw_reference: Vec<CalibrationSample> = road.iter().step_by(step).copied().collect();
    let reference = binned_means(&raw_reference);
    anyhow::ensure!(
        reference.len() >= 3,
        "only {} (r, α) bins of the real road hold {BIN_MIN_SAMPLES} samples",
        reference.len()
    );
    let lut = IntensityLut::fit(&reference, &LutConfig::default())?;
    // The road is never seen near normal incidence from a car's roof, so the range model is
    // fitted to all road samples (the simulated section uses α ≤ 10°).
    let poly = RangePolynomial::fit(&raw_reference, 4, std::f64::consts::FRAC_PI_2)?;
    let models = [
        IntensityCorrection::Raw,
        IntensityCorrection::Range(poly),
        IntensityCorrection::Lut(lut.clone()),
    ];
    let rows = [false, true].map(|covered_only| score(&models, &classes, &lut, covered_only));
    let coverage: Vec<f64> = classes
        .iter()
        .map(|c| {
            let n = c
                .held
                .iter()
                .filter(|s| lut.covers(s.range_m, s.incidence_rad))
                .count();
            n as f64 / c.held.len().max(1) as f64
        })
        .collect();
    let inside = lut.inside_hull.iter().filter(|&&b| b).count();
    let [all, covered] = rows;
    Ok(KittiUnit {
        json: json!({
            "coverage": coverage,
            "models_covered_only": covered,
            "sequences": used,
            "reference_samples": raw_reference.len(),
            "reference_bins": reference.len(),
            "samples": CLASSES.iter().zip(&classes).map(|(c, s)| json!({
                "class": c.0, "name": c.1, "fit": s.fit.len(), "held_back": s.held.len()
            })).collect::<Vec<_>>(),
            "models": all,
        }),
        fit: Some(FitFacts {
            stride,
            lut_ranges: lut.ranges,
            lut_angles: lut.angles,
            inside_percent: 100.0 * inside as f64 / lut.values.len().max(1) as f64,
        }),
    })
}

/// The section's text and tables.
pub(super) fn markdown(ctx: &EvalContext, unit: &KittiUnit) -> Result<String> {
    let mut md = String::new();
    let Some(fit) = &unit.fit else {
        let _ = writeln!(
            md,
            "*Skipped: no labelled real KITTI frames under `{}`.*\n",
            ctx.data("kitti/sequences").display()
        );
        return Ok(md);
    };
    let json = &unit.json;
    let used: Vec<&str> = json["sequences"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(Value::as_str)
        .collect();
    let counts: Vec<String> = json["samples"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|s| {
            let name = s["name"].as_str().unwrap_or_default();
            format!("{name} {} / {}", s["fit"], s["held_back"])
        })
        .collect();
    let stride = fit.stride;
    let _ = writeln!(
        md,
        "**Real data.** SemanticKITTI-labelled HDL-64E frames of sequences {} (every {stride}th \
         labelled point of the scored classes; samples fit / held back: {}). Reference surface: \
         the road (class 40) of frames 0–4, {} samples averaged in {BIN_RANGE_M} m × {BIN_ANGLE_DEG}° \
         (r, α) bins of at least {BIN_MIN_SAMPLES} samples ({} bins; single real road points \
         vary too much to interpolate between); scored on frames 5–9. Angle of incidence \
         from PCA normals over the {NORMAL_NEIGHBOURS} nearest points within {NORMAL_RADIUS_M} m. \
         LUT {} × {} entries, {:.1} % inside the samples' hull (outside: nearest sample); range \
         model: degree-4 polynomial on all road samples (the road is never seen near normal \
         incidence). KITTI's reflectance is the sensor's value in [0, 1] with per-laser gains \
         the LUT does not model. Not like for like with Khan Fig. 3.4 (his own 2-D sensor and \
         surfaces); a lower CV per class and a lower overlap between classes is better.\n",
        used.join(", "),
        counts.join(", "),
        json["reference_samples"],
        json["reference_bins"],
        fit.lut_ranges,
        fit.lut_angles,
        fit.inside_percent,
    );
    let rows = |key: &str| json[key].as_array().cloned().unwrap_or_default();
    let (all, covered) = (rows("models"), rows("models_covered_only"));
    let coverage: Vec<f64> = json["coverage"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|v| v.as_f64().unwrap_or(f64::NAN))
        .collect();
    let _ = writeln!(
        md,
        "All held-back points:\n\n{}",
        table(&all, false).to_markdown()?
    );
    let _ = writeln!(
        md,
        "Only the held-back points inside the LUT's calibrated domain (the road samples' hull \
         in (r, α)); share of each class inside: {}. Outside it the LUT clamps to the nearest \
         road bin: a road-only reference sees no near-normal incidence.\n\n{}",
        CLASSES
            .iter()
            .zip(&coverage)
            .map(|(c, v)| format!("{} {:.1} %", c.1, 100.0 * v))
            .collect::<Vec<_>>()
            .join(", "),
        table(&covered, true).to_markdown()?
    );
    let cv_of = |rows: &[Value], model: &str| -> Vec<f64> {
        rows.iter()
            .find(|r| r["model"] == model)
            .and_then(|r| r["cv"].as_array())
            .map(|v| v.iter().filter_map(Value::as_f64).collect())
            .unwrap_or_default()
    };
    let (raw_cv, lut_cv) = (cv_of(&covered, "raw"), cv_of(&covered, "lut"));
    let better = raw_cv.iter().zip(&lut_cv).filter(|(r, l)| l < r).count();
    let _ = writeln!(
        md,
        "In the calibrated domain the LUT lowers the CV of {better} of {} classes against the raw \
         reflectance{}.\n",
        raw_cv.len(),
        if better * 2 < raw_cv.len() {
            ": on real KITTI it falls short of the simulated section. The spread that remains \
             is not a function of (r, α) alone; per-laser gains and surface texture are the \
             likely causes, not separated here (Khan calibrated the raw intensities of his own \
             2-D scanner, whereas KITTI ships a processed reflectance)"
        } else {
            ""
        }
    );
    Ok(md)
}

/// The JSON rows of CV and overlaps per model over the held-back samples (only those the LUT
/// covers when `covered_only`).
fn score(
    models: &[IntensityCorrection],
    classes: &[ClassSamples],
    lut: &IntensityLut,
    covered_only: bool,
) -> Vec<Value> {
    let mut rows = Vec::new();
    for model in models {
        let values: Vec<Vec<f64>> = classes
            .iter()
            .map(|c| {
                c.held
                    .iter()
                    .filter(|s| !covered_only || lut.covers(s.range_m, s.incidence_rad))
                    .filter_map(|s| model.relative(s.intensity, s.range_m, s.incidence_rad))
                    .filter(|v| v.is_finite())
                    .collect()
            })
            .collect();
        let cv: Vec<f64> = values.iter().map(|v| coefficient_of_variation(v)).collect();
        let mut pooled: Vec<f64> = values.iter().flatten().copied().collect();
        let (lo, hi) = (quantile(&mut pooled, 0.005), quantile(&mut pooled, 0.995));
        let ov = |i: usize, j: usize| overlap(&values[i], &values[j], lo, hi, 60);
        let overlaps = [ov(0, 1), ov(0, 2), ov(2, 3)];
        rows.push(json!({ "model": model.name(), "cv": cv, "overlap": overlaps }));
    }
    rows
}

/// The table of CV and overlaps per model from the JSON rows of [`score`].
fn table(rows: &[Value], covered_only: bool) -> Table {
    let mut header = vec![if covered_only {
        "model (real KITTI, frames 5–9, calibrated domain)".to_owned()
    } else {
        "model (real KITTI, held-back frames 5–9)".to_owned()
    }];
    header.extend(CLASSES.iter().map(|c| format!("CV {}", c.1)));
    header.extend(
        [
            "overlap road–sidewalk",
            "overlap road–building",
            "overlap building–vegetation",
        ]
        .map(String::from),
    );
    let mut table = Table::new(header);
    for row in rows {
        let numbers = |key: &str| -> Vec<String> {
            row[key]
                .as_array()
                .into_iter()
                .flatten()
                .map(|v| fmt_num(v.as_f64().unwrap_or(f64::NAN), 3))
                .collect()
        };
        let mut cells = vec![row["model"].as_str().unwrap_or_default().to_owned()];
        cells.extend(numbers("cv"));
        cells.extend(numbers("overlap"));
        table.row(cells);
    }
    table
}
