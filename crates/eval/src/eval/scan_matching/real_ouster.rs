//! Intensity calibration on real Ouster frames (Khan 2017 §3.3 on the Ouster channels). The
//! captures carry no labels, so the reference surface is the ground: returns below the sensor
//! whose PCA normal is within [`GROUND_NORMAL_DEG`] of vertical. The LUT `I_ref(r, α)` is
//! fitted on the ground of the even columns and scored on the odd ones, for the raw signal
//! (where the packet profile carries it) and for the sensor's own calibrated reflectivity.
//! One unit per capture.

use std::fmt::Write;

use anyhow::{Context, Result, bail};
use nalgebra::Point3;
use raypath_io::ouster::{self, OusterFrame, SensorInfo, XyzLut};
use raypath_reflectivity::lut::CalibrationSample;
use raypath_reflectivity::normals::incidence_angle;
use raypath_reflectivity::{IntensityCorrection, IntensityLut, LutConfig, RangePolynomial};
use raypath_registration::{RegistrationConfig, surface_normals};
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use super::at;
use super::real_calib::binned_means;
use super::stats::coefficient_of_variation;
use crate::eval::EvalContext;
use crate::table::{Table, fmt_num};

/// The captures (under `ouster/`) and the sensor named in the tables.
const CAPTURES: [(&str, &str); 3] = [
    ("OS-1-128_v2.3.0_1024x10_lb_n3.pcap", "OS-1-128 (3 frames)"),
    ("OS-2-128-U1_v2.3.0_1024x10.pcap", "OS-2-128"),
    (
        "OS-1-128_767798045_1024x10_20230712_120049.pcap",
        "OS-1-128 dual",
    ),
];
/// A return is ground when its normal is within this angle of vertical …
const GROUND_NORMAL_DEG: f64 = 15.0;
/// … and it lies this far below the sensor.
const GROUND_BELOW_M: f64 = 0.5;
/// Neighbours and radius of the PCA normals (as for the KITTI section).
const NORMAL_NEIGHBOURS: usize = 16;
const NORMAL_RADIUS_M: f64 = 0.6;
/// Every n-th return of a frame is used (normals of 130 k points per frame are slow).
const STRIDE: usize = 2;

/// The captures' names as units: the file names without `.pcap`.
pub(super) fn captures() -> impl Iterator<Item = &'static str> {
    CAPTURES
        .iter()
        .map(|&(file, _)| file.strip_suffix(".pcap").unwrap_or(file))
}

/// One capture's result.
#[derive(Debug, Default, Serialize, Deserialize)]
pub(super) struct CaptureUnit {
    /// The sensor named in the table.
    pub sensor: String,
    /// Whether the capture is absent.
    pub absent: bool,
    /// The page's JSON rows (`capture`, `channel`, `model`, `fit`, `held_back`, `cv`,
    /// `spearman_range`, `spearman_reflectivity`).
    pub rows: Vec<Value>,
    /// The channels left out, and why.
    pub notes: Vec<String>,
}

/// Ground samples of one channel, split by column parity.
#[derive(Default)]
struct Split {
    fit: Vec<CalibrationSample>,
    held: Vec<CalibrationSample>,
    /// The sensor's reflectivity of each held-back sample (for the signal channel).
    held_reflectivity: Vec<f64>,
}

/// One ground return.
struct Ground {
    column: usize,
    range_m: f64,
    incidence_rad: f64,
    reflectivity: f64,
    signal: Option<f64>,
}

/// The ground returns of one frame.
fn ground_samples(frame: &OusterFrame, lut: &XyzLut) -> Result<Vec<Ground>> {
    let cloud = lut.cloud(frame)?;
    let valid: Vec<usize> = (0..cloud.len())
        .filter(|&i| cloud.is_valid(i))
        .step_by(STRIDE)
        .collect();
    let points: Vec<Point3<f64>> = valid.iter().map(|&i| cloud.point_f64(i)).collect();
    let config = RegistrationConfig {
        normal_neighbours: NORMAL_NEIGHBOURS,
        normal_radius_m: NORMAL_RADIUS_M,
        ..RegistrationConfig::default()
    };
    let normals = surface_normals(&points, &Point3::origin(), &config);
    let vertical = GROUND_NORMAL_DEG.to_radians().cos();
    let mut out = Vec::new();
    for ((&i, p), n) in valid.iter().zip(&points).zip(&normals) {
        let Some(n) = n else { continue };
        if n.z.abs() < vertical || p.z > -GROUND_BELOW_M {
            continue;
        }
        let signal = frame
            .signal
            .as_ref()
            .and_then(|s| s.get(i))
            .map(|&v| f64::from(v));
        out.push(Ground {
            column: i % frame.width,
            range_m: p.coords.norm(),
            incidence_rad: incidence_angle([p.x, p.y, p.z], [n.x, n.y, n.z]),
            reflectivity: f64::from(frame.reflectivity[i]),
            signal,
        });
    }
    Ok(out)
}

/// Spearman's rank correlation of two equally long samples.
fn spearman(a: &[f64], b: &[f64]) -> f64 {
    let ranks = |v: &[f64]| {
        let mut order: Vec<usize> = (0..v.len()).collect();
        order.sort_by(|&i, &j| v[i].total_cmp(&v[j]));
        let mut r = vec![0.0; v.len()];
        let mut k = 0;
        while k < order.len() {
            let mut m = k;
            while m + 1 < order.len() && v[order[m + 1]] == v[order[k]] {
                m += 1;
            }
            for &idx in &order[k..=m] {
                r[idx] = (k + m) as f64 / 2.0; // ties share the mean rank
            }
            k = m + 1;
        }
        r
    };
    let (ra, rb) = (ranks(a), ranks(b));
    let n = ra.len() as f64;
    let (ma, mb) = (ra.iter().sum::<f64>() / n, rb.iter().sum::<f64>() / n);
    let cov: f64 = ra.iter().zip(&rb).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = ra.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = rb.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

/// The ground samples of every channel of `frames`, split by column parity: the sensor's
/// reflectivity, and the raw signal where a frame carries it.
fn channels(frames: &[OusterFrame], lut: &XyzLut) -> Result<Vec<(&'static str, Split)>> {
    let mut channels: Vec<(&str, Split)> = vec![("reflectivity", Split::default())];
    if frames.iter().any(|f| f.signal.is_some()) {
        channels.push(("signal", Split::default()));
    }
    for frame in frames {
        for g in ground_samples(frame, lut)? {
            for (name, split) in &mut channels {
                let intensity = if *name == "signal" {
                    g.signal.unwrap_or(f64::NAN)
                } else {
                    g.reflectivity
                };
                let sample = CalibrationSample {
                    range_m: g.range_m,
                    incidence_rad: g.incidence_rad,
                    intensity,
                };
                if g.column % 2 == 0 {
                    split.fit.push(sample);
                } else {
                    split.held.push(sample);
                    split.held_reflectivity.push(g.reflectivity);
                }
            }
        }
    }
    Ok(channels)
}

/// Fits and scores the models on the ground of one capture (the unit `ouster/<capture>`).
pub(super) fn measure(ctx: &EvalContext, capture: &str) -> Result<CaptureUnit> {
    let Some(&(file, sensor)) = CAPTURES
        .iter()
        .find(|(file, _)| file.strip_suffix(".pcap") == Some(capture))
    else {
        bail!("no Ouster capture named {capture:?}");
    };
    let mut unit = CaptureUnit {
        sensor: sensor.to_owned(),
        ..CaptureUnit::default()
    };
    let pcap = ctx.data(&format!("ouster/{file}"));
    if !pcap.is_file() {
        eprintln!("scan-matching: {} absent, skipping it", pcap.display());
        unit.absent = true;
        return Ok(unit);
    }
    let json_path = ouster::find_metadata(&pcap)?;
    let info = SensorInfo::read(&json_path)?;
    let lut = XyzLut::new(&info)?;
    let frames = ouster::read_frames(&pcap, &json_path)
        .with_context(|| format!("reading {}", pcap.display()))?;
    for (channel, split) in &channels(&frames, &lut)? {
        let reference = binned_means(&split.fit);
        if reference.len() < 3 || split.held.is_empty() {
            unit.notes.push(format!(
                "{sensor}: too little ground for the {channel} channel ({} ground returns \
                 in the fit columns, {} (r, α) bins); left out.",
                split.fit.len(),
                reference.len()
            ));
            continue;
        }
        let table_lut = IntensityLut::fit(&reference, &LutConfig::default())?;
        let poly = RangePolynomial::fit(&split.fit, 4, std::f64::consts::FRAC_PI_2)?;
        let models = [
            IntensityCorrection::Raw,
            IntensityCorrection::Range(poly),
            IntensityCorrection::Lut(table_lut),
        ];
        for model in &models {
            unit.rows.push(score(file, channel, split, model));
        }
    }
    Ok(unit)
}

/// One model on the held-back ground of one channel: the page's JSON row.
fn score(file: &str, channel: &str, split: &Split, model: &IntensityCorrection) -> Value {
    let (values, ranges, refl): (Vec<f64>, Vec<f64>, Vec<f64>) = split
        .held
        .iter()
        .zip(&split.held_reflectivity)
        .filter_map(|(s, &r)| {
            let v = model.relative(s.intensity, s.range_m, s.incidence_rad)?;
            v.is_finite().then_some((v, s.range_m, r))
        })
        .fold(Default::default(), |(mut a, mut b, mut c), (v, r, f)| {
            a.push(v);
            b.push(r);
            c.push(f);
            (a, b, c)
        });
    let cv = coefficient_of_variation(&values);
    let with_range = spearman(&values, &ranges);
    let with_reflectivity = (channel == "signal").then(|| spearman(&values, &refl));
    json!({
        "capture": file, "channel": channel, "model": model.name(),
        "fit": split.fit.len(), "held_back": split.held.len(), "cv": cv,
        "spearman_range": with_range, "spearman_reflectivity": with_reflectivity,
    })
}

/// The section from every capture's result: its text and table, the notes and the finding
/// on the signal channel, and its JSON.
pub(super) fn section(ctx: &EvalContext, captures: &[CaptureUnit]) -> Result<(String, Value)> {
    let mut md = String::new();
    let rows: Vec<Value> = captures.iter().flat_map(|c| c.rows.clone()).collect();
    let notes: Vec<String> = captures.iter().flat_map(|c| c.notes.clone()).collect();
    if rows.is_empty() {
        let _ = writeln!(
            md,
            "*Skipped: no Ouster captures under `{}`.*\n",
            ctx.data("ouster").display()
        );
        return Ok((md, json!({ "skipped": "no Ouster captures" })));
    }
    let mut table = Table::new([
        "capture (real)",
        "channel",
        "ground fit / held back",
        "model",
        "CV ground (held back)",
        "Spearman with range",
        "Spearman with sensor reflectivity",
    ]);
    for capture in captures {
        for row in &capture.rows {
            let text = |key: &str| row[key].as_str().unwrap_or_default().to_owned();
            table.row([
                capture.sensor.clone(),
                text("channel"),
                format!("{} / {}", row["fit"], row["held_back"]),
                text("model"),
                fmt_num(at(row, "/cv"), 3),
                fmt_num(at(row, "/spearman_range"), 2),
                row["spearman_reflectivity"]
                    .as_f64()
                    .map_or("—".into(), |v| fmt_num(v, 2)),
            ]);
        }
    }
    let _ = writeln!(
        md,
        "**Real data, Ouster.** The captures carry no labels, so the reference surface is the \
         ground: returns more than {GROUND_BELOW_M} m below the sensor whose PCA normal \
         ({NORMAL_NEIGHBOURS} neighbours within {NORMAL_RADIUS_M} m, every {STRIDE}nd return) \
         is within {GROUND_NORMAL_DEG}° of vertical. The LUT and the range polynomial are \
         fitted on the ground of the even columns, scored on the odd columns. Channels: the \
         sensor's **reflectivity** (already calibrated by Ouster for range; a remaining \
         dependence on r and α is what the LUT could remove) and, where the packet profile \
         carries it, the raw **signal** (photon counts, falling with range — what Khan's \
         calibration is for; its rank correlation with the sensor's reflectivity shows how \
         close the LUT comes to the vendor's calibration). Ground of one kind is assumed; \
         asphalt, paint and grass in one scene add spread no (r, α) model removes.\n\n{}",
        table.to_markdown()?
    );
    for note in &notes {
        let _ = writeln!(md, "* {note}");
    }
    if let Some(finding) = signal_finding(&rows) {
        let _ = writeln!(md, "\n{finding}\n");
    }
    Ok((md, json!({ "rows": rows, "notes": notes })))
}

/// One sentence on the signal channel: what the corrections do to its spread, its range
/// dependence and its agreement with the sensor's reflectivity.
fn signal_finding(rows: &[Value]) -> Option<String> {
    let row = |model: &str| {
        rows.iter()
            .find(|r| r["channel"] == "signal" && r["model"] == model)
    };
    let (raw, range, lut) = (row("raw")?, row("range")?, row("lut")?);
    let f = |r: &Value, key: &str| r[key].as_f64().unwrap_or(f64::NAN);
    Some(format!(
        "On the ground of the capture with a signal channel, the LUT changes the raw \
         signal's CV from {:.2} to {:.2} (range-only polynomial: {:.2}) and its rank \
         correlation with range from {:.2} to {:.2}; its rank agreement with the sensor's \
         reflectivity goes from {:.2} to {:.2}. The sensor's reflectivity is not a ground \
         truth here: its own rank correlation with range on this ground is in the \
         reflectivity rows.",
        f(raw, "cv"),
        f(lut, "cv"),
        f(range, "cv"),
        f(raw, "spearman_range"),
        f(lut, "spearman_range"),
        f(raw, "spearman_reflectivity"),
        f(lut, "spearman_reflectivity"),
    ))
}
