//! The range-only baseline (Khan 2017 §3.5.1): a polynomial
//! `f(r) = Σ_{i=1}^{n+1} p_i r^{n+1−i}` fitted by least squares to the reference surface's
//! intensity near normal incidence; the corrected value is `I / f(r)` (α is ignored).

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::error::{ReflectivityError, Result};
use crate::lut::CalibrationSample;

/// A polynomial in range, evaluated on `r / range_scale_m` for conditioning.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RangePolynomial {
    /// Coefficients, constant term first, of the polynomial in `r / range_scale_m`.
    pub coefficients: Vec<f64>,
    /// Range normalisation, metres (the largest fitted range).
    pub range_scale_m: f64,
}

impl RangePolynomial {
    /// Fits a polynomial of `degree` to the samples with `α ≤ max_incidence_rad` (all
    /// samples when fewer than `degree + 1` qualify). The thesis does not give the degree;
    /// 3–5 is a reasonable choice.
    pub fn fit(
        samples: &[CalibrationSample],
        degree: usize,
        max_incidence_rad: f64,
    ) -> Result<Self> {
        let near: Vec<&CalibrationSample> = samples
            .iter()
            .filter(|s| s.incidence_rad <= max_incidence_rad)
            .collect();
        let used: Vec<&CalibrationSample> = if near.len() > degree + 1 {
            near
        } else {
            samples.iter().collect()
        };
        if used.len() <= degree || degree > 12 {
            return Err(ReflectivityError::BadInput(format!(
                "a degree-{degree} range polynomial needs more than {degree} samples, got {}",
                used.len()
            )));
        }
        if used
            .iter()
            .any(|s| !(s.range_m.is_finite() && s.intensity.is_finite()))
        {
            return Err(ReflectivityError::BadInput(
                "non-finite calibration sample".into(),
            ));
        }
        let scale = used.iter().map(|s| s.range_m.abs()).fold(0.0, f64::max);
        if scale.is_nan() || scale <= 0.0 {
            return Err(ReflectivityError::BadInput(
                "all sample ranges are zero".into(),
            ));
        }
        let a = DMatrix::from_fn(used.len(), degree + 1, |i, k| {
            used.get(i)
                .map_or(0.0, |s| (s.range_m / scale).powi(k as i32))
        });
        let b = DVector::from_iterator(used.len(), used.iter().map(|s| s.intensity));
        let x = a.svd(true, true).solve(&b, 1e-12).map_err(|e| {
            ReflectivityError::BadInput(format!("range polynomial fit failed: {e}"))
        })?;
        Ok(Self {
            coefficients: x.iter().copied().collect(),
            range_scale_m: scale,
        })
    }

    /// `f(r)`.
    pub fn evaluate(&self, range_m: f64) -> f64 {
        let t = range_m / self.range_scale_m;
        self.coefficients
            .iter()
            .rev()
            .fold(0.0, |acc, c| acc * t + c)
    }

    /// `I / f(r)`; `None` where `f(r) ≤ 0` or the input is not finite.
    pub fn relative(&self, intensity: f64, range_m: f64) -> Option<f64> {
        let f = self.evaluate(range_m);
        (f > 0.0 && f.is_finite() && intensity.is_finite()).then(|| intensity / f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_cubic() {
        let samples: Vec<CalibrationSample> = (0..50)
            .map(|i| {
                let r = 0.5 + 0.3 * i as f64;
                CalibrationSample {
                    range_m: r,
                    incidence_rad: 0.0,
                    intensity: 100.0 + 20.0 * r - 3.0 * r * r + 0.1 * r * r * r,
                }
            })
            .collect();
        let p = RangePolynomial::fit(&samples, 3, 0.1).unwrap();
        for r in [0.7, 3.3, 12.0] {
            let expect = 100.0 + 20.0 * r - 3.0 * r * r + 0.1 * r * r * r;
            assert!((p.evaluate(r) - expect).abs() < 1e-6);
        }
    }
}
