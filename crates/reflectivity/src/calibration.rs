//! Intensity models for relative reflectivity (Khan 2017 §3.5.1): raw, range-only
//! and the LUT, and the sample file of `raypath calibrate-intensity`.
//!
//! Sample CSV: one `range_m,incidence_rad,intensity` triple per line (metres, radians,
//! sensor units); a header line naming the columns, blank lines and `#` comments are
//! skipped.

use std::io::BufRead;

use serde::{Deserialize, Serialize};

use crate::error::{ReflectivityError, Result};
use crate::lut::{CalibrationSample, IntensityLut};
use crate::range_model::RangePolynomial;

/// How an intensity becomes a relative reflectivity.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "kebab-case")]
pub enum IntensityCorrection {
    /// The raw intensity (baseline 1).
    Raw,
    /// `I / f(r)` (baseline 2).
    Range(RangePolynomial),
    /// `I / I_ref(r, α)` (the thesis).
    Lut(IntensityLut),
}

impl IntensityCorrection {
    /// The model's name: `raw`, `range` or `lut`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Raw => "raw",
            Self::Range(_) => "range",
            Self::Lut(_) => "lut",
        }
    }

    /// The corrected value of intensity `I` at range `r` and incidence `α` (`None` when the
    /// model cannot correct it, for example the LUT without a normal).
    pub fn relative(&self, intensity: f64, range_m: f64, incidence_rad: f64) -> Option<f64> {
        match self {
            Self::Raw => intensity.is_finite().then_some(intensity),
            Self::Range(p) => p.relative(intensity, range_m),
            Self::Lut(lut) => lut.relative(intensity, range_m, incidence_rad),
        }
    }
}

fn parse_row(line: &str) -> Option<Option<CalibrationSample>> {
    let mut fields = line.split([',', ';', ' ', '\t']).filter(|f| !f.is_empty());
    let mut next = || fields.next().map(str::parse::<f64>);
    let (Some(r), Some(a), Some(i)) = (next(), next(), next()) else {
        return None;
    };
    match (r, a, i) {
        (Ok(r), Ok(a), Ok(i)) => Some(Some(CalibrationSample {
            range_m: r,
            incidence_rad: a,
            intensity: i,
        })),
        _ => Some(None),
    }
}

/// Reads calibration samples from CSV text (module docs); errors name `name` and the line.
pub fn read_samples_csv(reader: impl BufRead, name: &str) -> Result<Vec<CalibrationSample>> {
    let mut samples = Vec::new();
    for (k, line) in reader.lines().enumerate() {
        let n = k + 1;
        let line = line.map_err(|e| ReflectivityError::BadInput(format!("{name}:{n}: {e}")))?;
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        match parse_row(t) {
            Some(Some(s)) => {
                let ok = s.range_m.is_finite()
                    && s.range_m >= 0.0
                    && s.incidence_rad.is_finite()
                    && (0.0..=std::f64::consts::FRAC_PI_2 + 1e-9).contains(&s.incidence_rad)
                    && s.intensity.is_finite();
                if !ok {
                    return Err(ReflectivityError::BadInput(format!(
                        "{name}:{n}: need range ≥ 0 m, incidence in [0, π/2] rad and a finite intensity, got {t:?}"
                    )));
                }
                samples.push(s);
            }
            Some(None) if samples.is_empty() && t.chars().any(|c| c.is_ascii_alphabetic()) => {} // header
            _ => {
                return Err(ReflectivityError::BadInput(format!(
                    "{name}:{n}: expected range_m,incidence_rad,intensity, got {t:?}"
                )));
            }
        }
    }
    if samples.is_empty() {
        return Err(ReflectivityError::BadInput(format!("{name}: no samples")));
    }
    Ok(samples)
}
