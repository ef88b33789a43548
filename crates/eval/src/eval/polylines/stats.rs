//! Statistics over the scans of a set of results: mean ± standard error, medians, the
//! ranking of the methods and the JSON per variant.

use serde_json::json;

use super::measure::{Outcome, Results};
use super::{JS, VARIANTS};
use crate::eval::median;

/// Mean and standard error of the finite values.
pub fn mean_se(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = if v.len() > 1 {
        v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0)
    } else {
        0.0
    };
    (mean, (var / n).sqrt())
}

/// Mean and standard error of `f` for variant `v` at J index `j`.
pub fn stat(results: &Results, v: usize, j: usize, f: impl Fn(&Outcome) -> f64) -> (f64, f64) {
    mean_se(results[v][j].iter().map(f))
}

/// The index of the variant labelled `label`.
pub fn variant_index(label: &str) -> usize {
    VARIANTS.iter().position(|v| v.label == label).unwrap_or(0)
}

/// Mean, median and 95th percentile of the time per scan of variant `vi` at J index `ji`.
pub fn times(results: &Results, vi: usize, ji: usize) -> (f64, f64, f64) {
    let mut v: Vec<f64> = results[vi][ji].iter().map(|o| o.secs).collect();
    let med = median(&mut v);
    let p95 = v
        .get(((v.len() as f64) * 0.95) as usize)
        .copied()
        .unwrap_or(f64::NAN);
    let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
    (mean, med, p95)
}

/// Every variant's statistics per J, as JSON.
pub fn variant_json(results: &Results) -> serde_json::Value {
    let per_variant: Vec<_> = VARIANTS
        .iter()
        .enumerate()
        .map(|(vi, v)| {
            let per_j: Vec<_> = JS
                .iter()
                .enumerate()
                .map(|(ji, &j)| {
                    let s = |f: &dyn Fn(&Outcome) -> f64| {
                        let (m, se) = stat(results, vi, ji, f);
                        json!({"mean": m, "se": se})
                    };
                    let mut secs: Vec<f64> = results[vi][ji].iter().map(|o| o.secs).collect();
                    json!({
                        "j": j,
                        "rmse_m": s(&|o| o.rmse_m),
                        "f": s(&|o| o.f),
                        "a_gt": s(&|o| o.a_gt),
                        "a_printed": s(&|o| o.a_printed),
                        "iou": s(&|o| o.iou),
                        "secs": s(&|o| o.secs),
                        "secs_median": median(&mut secs),
                        "vertices": s(&|o| o.vertices as f64),
                    })
                })
                .collect();
            json!({"method": v.label, "optimizer": v.optimizer.name(), "per_j": per_j})
        })
        .collect();
    json!(per_variant)
}

/// Ranking of the five thesis methods by mean RMSE at each J ("PLE+ < PLE < …").
pub fn ranking(results: &Results) -> Vec<String> {
    JS.iter()
        .enumerate()
        .map(|(ji, j)| {
            let mut order: Vec<(f64, &str)> = VARIANTS
                .iter()
                .enumerate()
                .filter(|(_, v)| v.label != "PLE+ (NM)")
                .map(|(vi, v)| (stat(results, vi, ji, |o| o.rmse_m).0, v.label))
                .collect();
            order.sort_by(|a, b| a.0.total_cmp(&b.0));
            format!(
                "J = {j}: {}",
                order
                    .iter()
                    .map(|(m, l)| format!("{l} ({:.1} mm)", m * 1e3))
                    .collect::<Vec<_>>()
                    .join(" < ")
            )
        })
        .collect()
}

/// Median RMSE per method at J index `ji`, as "VVL 12.3 mm, …".
pub fn median_rmse(results: &Results, ji: usize) -> String {
    VARIANTS
        .iter()
        .enumerate()
        .map(|(vi, v)| {
            let mut values: Vec<f64> = results[vi][ji]
                .iter()
                .map(|o| o.rmse_m)
                .filter(|x| x.is_finite())
                .collect();
            format!("{} {:.1} mm", v.label, median(&mut values) * 1e3)
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Concatenates `parts` scan-wise: `[variant][j]` of every part, in order.
pub fn join(parts: &[&Results]) -> Results {
    (0..VARIANTS.len())
        .map(|v| {
            (0..JS.len())
                .map(|j| parts.iter().flat_map(|r| r[v][j].iter().copied()).collect())
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn results(rmse: &[f64]) -> Results {
        let outcome = |r: f64| Outcome {
            rmse_m: r,
            f: 1.0,
            a_gt: f64::NAN,
            a_printed: f64::NAN,
            iou: f64::NAN,
            secs: r,
            vertices: 3,
        };
        (0..VARIANTS.len())
            .map(|v| {
                (0..JS.len())
                    .map(|_| rmse.iter().map(|r| outcome(r + v as f64 * 1e-3)).collect())
                    .collect()
            })
            .collect()
    }

    #[test]
    fn joined_parts_give_the_statistics_of_the_whole() {
        let whole = results(&[0.01, 0.02, 0.04, f64::NAN]);
        let (a, b) = (results(&[0.01, 0.02]), results(&[0.04, f64::NAN]));
        let joined = join(&[&a, &b]);
        assert_eq!(joined[2][3].len(), 4);
        let (m, se) = stat(&joined, 0, 0, |o| o.rmse_m);
        assert_eq!((m, se), stat(&whole, 0, 0, |o| o.rmse_m));
        assert!((m - 0.07 / 3.0).abs() < 1e-12, "{m}");
        assert_eq!(ranking(&joined), ranking(&whole));
        assert!(ranking(&joined)[0].starts_with("J = 10: VVL (23.3 mm) < IEF"));
        assert_eq!(median_rmse(&joined, 1), median_rmse(&whole, 1));
        assert!(median_rmse(&joined, 1).starts_with("VVL 20.0 mm, IEF 21.0 mm"));
    }
}
