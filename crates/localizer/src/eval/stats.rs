//! Summary statistics of signed errors.

use serde::{Deserialize, Serialize};

/// Statistics of a list of signed errors (units of the errors). All zero for an empty list.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ErrorStats {
    /// Number of values.
    pub count: usize,
    /// Mean of the absolute values (Δ in Schaefer 2020, Tables 12.1 and 12.2).
    pub mean_abs: f64,
    /// Root mean square.
    pub rmse: f64,
    /// Mean of the signed values (bias).
    pub mean: f64,
    /// Standard deviation of the signed values (population, divides by n; σ in Table 12.2).
    pub std: f64,
    /// Largest absolute value.
    pub max_abs: f64,
}

impl ErrorStats {
    /// The statistics of `values`.
    pub fn from_values(values: impl IntoIterator<Item = f64>) -> Self {
        let (mut n, mut sum, mut sum_abs, mut sum_sq, mut max_abs) =
            (0usize, 0.0, 0.0, 0.0, 0.0f64);
        for v in values {
            n += 1;
            sum += v;
            sum_abs += v.abs();
            sum_sq += v * v;
            max_abs = max_abs.max(v.abs());
        }
        if n == 0 {
            return Self::default();
        }
        let nf = n as f64;
        let mean = sum / nf;
        Self {
            count: n,
            mean_abs: sum_abs / nf,
            rmse: (sum_sq / nf).sqrt(),
            mean,
            std: (sum_sq / nf - mean * mean).max(0.0).sqrt(),
            max_abs,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        let s = ErrorStats::from_values([3.0, -4.0]);
        assert_eq!(s.count, 2);
        assert!((s.mean_abs - 3.5).abs() < 1e-12);
        assert!((s.rmse - 12.5f64.sqrt()).abs() < 1e-12);
        assert!((s.mean + 0.5).abs() < 1e-12);
        assert!((s.std - 3.5).abs() < 1e-12);
        assert_eq!(s.max_abs, 4.0);
        assert_eq!(ErrorStats::from_values([]), ErrorStats::default());
    }
}
