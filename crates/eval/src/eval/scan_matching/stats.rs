//! Statistics of corrected intensities shared by the calibration sections: histogram overlap,
//! coefficient of variation, quantiles.

/// Histogram overlap Σ min(p, q) of two samples over common bins.
pub(super) fn overlap(a: &[f64], b: &[f64], lo: f64, hi: f64, bins: usize) -> f64 {
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

/// Standard deviation over mean.
pub(super) fn coefficient_of_variation(v: &[f64]) -> f64 {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
    var.sqrt() / mean
}

/// The `q` quantile of `v` (sorted in place; the nearest rank); NaN for none.
pub(super) fn quantile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let k = ((v.len() - 1) as f64 * q).round() as usize;
    v.get(k).copied().unwrap_or(f64::NAN)
}
