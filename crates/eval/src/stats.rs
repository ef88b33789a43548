//! Small statistics shared by the evaluations: mean and standard deviation and the one-sided
//! paired-sample t-tests of the thesis tables (Table 8.x corridor, Tables 9.2 / 9.3), on `statrs`.

/// Mean and sample standard deviation.
pub fn mean_std(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    if x.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mean = x.iter().sum::<f64>() / n;
    if x.len() < 2 {
        return (mean, f64::NAN);
    }
    let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var.sqrt())
}

/// p-value of the one-sided paired t-test with H1: mean(a − b) < 0.
pub fn paired_less(a: &[f64], b: &[f64]) -> f64 {
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    if d.len() < 2 {
        return f64::NAN;
    }
    let (mean, sd) = mean_std(&d);
    if sd == 0.0 {
        return if mean < 0.0 { 0.0 } else { 1.0 };
    }
    let t = mean / (sd / (d.len() as f64).sqrt());
    student_cdf(t, d.len() as f64 - 1.0)
}

/// `P(T ≤ t)` for Student's t with `nu` degrees of freedom.
pub fn student_cdf(t: f64, nu: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    StudentsT::new(0.0, 1.0, nu).map_or(f64::NAN, |dist| dist.cdf(t))
}

/// p-value of the one-sided paired t-test with H1: mean(a − b) > 0.
pub fn paired_greater(a: &[f64], b: &[f64]) -> f64 {
    paired_less(b, a)
}

/// Median of a slice (sorted in place); NaN for none.
pub fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn student_quantiles() {
        // t_{0.975, 9} = 2.262157, t_{0.95, 4} = 2.131847
        assert!((student_cdf(2.262_157, 9.0) - 0.975).abs() < 1e-6);
        assert!((student_cdf(-2.131_847, 4.0) - 0.05).abs() < 1e-6);
        assert!((student_cdf(0.0, 3.0) - 0.5).abs() < 1e-12);
        // Upper tails: t = 2.228, df = 10 → 0.025; normal tail at 3.719 → 1.0e-4.
        assert!((student_cdf(-2.228_138_85, 10.0) - 0.025).abs() < 1e-6);
        assert!((student_cdf(-3.719_016, 1e6) / 1e-4 - 1.0).abs() < 1e-3);
    }

    #[test]
    fn paired_tests_are_mirror_images() {
        let a = [1.0, 2.0, 3.5, 4.0, 5.5];
        let b = [0.8, 2.1, 3.0, 3.2, 5.0];
        let greater = paired_greater(&a, &b);
        assert!(greater < 0.05, "{greater}");
        assert!((paired_less(&a, &b) + greater - 1.0).abs() < 1e-12);
    }
}
