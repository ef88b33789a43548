//! The one-sided paired-sample t-test of Table 9.2 / 9.3.

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
    let x = nu / (nu + t * t);
    let half_tail = 0.5 * reg_inc_beta(0.5 * nu, 0.5, x);
    if t < 0.0 { half_tail } else { 1.0 - half_tail }
}

fn ln_gamma(z: f64) -> f64 {
    // Stirling series with shift to z ≥ 8 (relative error < 1e-13 there).
    let mut shift = 0.0;
    let mut z = z;
    while z < 8.0 {
        shift -= z.ln();
        z += 1.0;
    }
    let inv = 1.0 / z;
    let inv2 = inv * inv;
    let series = inv * (1.0 / 12.0 - inv2 * (1.0 / 360.0 - inv2 * (1.0 / 1260.0 - inv2 / 1680.0)));
    shift + (z - 0.5) * z.ln() - z + 0.5 * (2.0 * std::f64::consts::PI).ln() + series
}

/// Regularized incomplete beta `I_x(a, b)` by its continued fraction (modified Lentz).
fn reg_inc_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    if x > (a + 1.0) / (a + b + 2.0) {
        return 1.0 - reg_inc_beta(b, a, 1.0 - x);
    }
    let front =
        (a * x.ln() + b * (1.0 - x).ln() - (ln_gamma(a) + ln_gamma(b) - ln_gamma(a + b))).exp() / a;
    let tiny = 1e-300;
    let (mut c, mut d) = (1.0, 1.0 - (a + b) * x / (a + 1.0));
    if d.abs() < tiny {
        d = tiny;
    }
    d = 1.0 / d;
    let mut f = d;
    for m in 1..300 {
        let m = m as f64;
        for step in 0..2 {
            let num = if step == 0 {
                m * (b - m) * x / ((a + 2.0 * m - 1.0) * (a + 2.0 * m))
            } else {
                -(a + m) * (a + b + m) * x / ((a + 2.0 * m) * (a + 2.0 * m + 1.0))
            };
            d = 1.0 + num * d;
            if d.abs() < tiny {
                d = tiny;
            }
            c = 1.0 + num / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            f *= c * d;
        }
        if (c * d - 1.0).abs() < 1e-15 {
            break;
        }
    }
    front * f
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
    }
}
