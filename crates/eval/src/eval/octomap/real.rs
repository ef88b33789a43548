//! The headline table: the real scans at r = 0.2 m, M = 8, beam-based, both fusion rules
//! (the equal-value rule per scan from the thesis' selection, and fused every 10 scans from
//! every updated cell), built from the JSON rows of the tables of all runs and variants.

use serde_json::{Value, json};

use super::measure::SetInfo;
use super::{EQUAL_LABEL, EQUAL_UPDATED_BATCH_LABEL};
use crate::table::{Table, fmt_num};

/// Why no row of this table is like for like with the thesis' figure.
const NOT_LIKE_FOR_LIKE: &str = "no: thesis 81-scan Freiburg campus graph (not available), \
     C++ on other hardware";

/// The run row of `data` at r = 0.2 m, M = 8, beam-based.
fn headline_run<'a>(rows: &'a [Value], data: &str) -> Option<&'a Value> {
    rows.iter().find(|r| {
        r["data"] == data
            && r["model"] == "beam"
            && r["m"] == 8
            && r["resolution_m"]
                .as_f64()
                .is_some_and(|v| (v - 0.2).abs() < 1e-9)
    })
}

/// The row of variant `label` on `data` (r = 0.2 m, M = 8), or null.
fn variant(variants: &[Value], data: &str, label: &str) -> Value {
    variants
        .iter()
        .find(|v| v["data"] == data && v["variant"] == label)
        .cloned()
        .unwrap_or(Value::Null)
}

fn percent(v: &Value) -> String {
    v.as_f64()
        .map_or("—".into(), |v| format!("{:.1} %", 100.0 * v))
}

fn ratio(v: &Value) -> String {
    v.as_f64().map_or("—".into(), |v| fmt_num(v, 2))
}

/// The table over the real data sets and its JSON rows (`summary.real`).
pub fn table(sets: &[&SetInfo], rows: &[Value], variants: &[Value]) -> (Table, Vec<Value>) {
    let mut table = Table::new([
        "data (real)",
        "points",
        "OctoMap leaves",
        "leaf reduction: thesis rule / equal-value / equal-value, batched",
        "insert ratio: thesis rule / equal-value / equal-value, batched",
        "bytes ratio: thesis rule / equal-value / equal-value, batched",
        "like for like with thesis 28.5 % / > 1",
    ]);
    let mut json_rows = Vec::new();
    for set in sets.iter().filter(|s| s.real) {
        let Some(run) = headline_run(rows, &set.name) else {
            continue;
        };
        let equal = variant(variants, &set.name, EQUAL_LABEL);
        let batched = variant(variants, &set.name, EQUAL_UPDATED_BATCH_LABEL);
        let three = |key: &str, show: fn(&Value) -> String| {
            format!(
                "{} / {} / {}",
                show(&run[key]),
                show(&equal[key]),
                show(&batched[key])
            )
        };
        table.row([
            set.name.clone(),
            set.points.to_string(),
            run["octomap"]["leaves_pruned"]
                .to_string()
                .replace("null", "—"),
            three("leaf_reduction", percent),
            three("insertion_time_ratio", ratio),
            three("bytes_ratio", ratio),
            NOT_LIKE_FOR_LIKE.into(),
        ]);
        let figures = |v: &Value| {
            json!({
                "leaf_reduction": v["leaf_reduction"],
                "insertion_time_ratio": v["insertion_time_ratio"],
                "bytes_ratio": v["bytes_ratio"],
            })
        };
        json_rows.push(json!({
            "data": set.name,
            "points": set.points,
            "leaf_reduction": run["leaf_reduction"],
            "insertion_time_ratio": run["insertion_time_ratio"],
            "bytes_ratio": run["bytes_ratio"],
            "equal_value": figures(&equal),
            "equal_value_batched": figures(&batched),
        }));
    }
    (table, json_rows)
}

/// `lo to hi` of `values` with `digits` decimals (one value when they round alike).
pub fn span(values: &[f64], digits: usize) -> String {
    let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !lo.is_finite() {
        return "—".into();
    }
    let (a, b) = (fmt_num(lo, digits), fmt_num(hi, digits));
    if a == b { a } else { format!("{a} to {b}") }
}

/// The results page's headline: the real rows (ranges over the real data sets), then the
/// simulated set of the earlier summary.
pub fn headline(real_rows: &[Value], simulated: Option<&(String, f64)>) -> Option<String> {
    if real_rows.is_empty() {
        return None;
    }
    let values = |path: &[&str], scale: f64| -> Vec<f64> {
        real_rows
            .iter()
            .filter_map(|r| path.iter().fold(r, |v, k| &v[*k]).as_f64())
            .map(|v| v * scale)
            .collect()
    };
    let names: Vec<&str> = real_rows
        .iter()
        .filter_map(|r| r["data"].as_str())
        .collect();
    let simulated = simulated.map_or(String::new(), |(name, v)| {
        format!(
            "; simulated `{name}`: thesis rule {} % fewer leaves",
            fmt_num(100.0 * v, 1)
        )
    });
    Some(format!(
        "Real scans ({}; r = 0.2 m, M = 8, OctoMap 1.9 in the same run): the thesis' fusion \
         rule gives {} % fewer leaves than pruned OctoMap at {}× its insertion time; \
         equal-value fusion (ours) {} % fewer leaves at {}× the insertion time and {}× the \
         bytes, and fused every 10 scans from every updated cell {} % fewer leaves at {}× \
         the insertion time and {}× the bytes (negative: more leaves){simulated}. Not like \
         for like with the thesis' 28.5 % (its Freiburg campus graph is not available).",
        names.join(", "),
        span(&values(&["leaf_reduction"], 100.0), 1),
        span(&values(&["insertion_time_ratio"], 1.0), 2),
        span(&values(&["equal_value", "leaf_reduction"], 100.0), 1),
        span(&values(&["equal_value", "insertion_time_ratio"], 1.0), 2),
        span(&values(&["equal_value", "bytes_ratio"], 1.0), 2),
        span(
            &values(&["equal_value_batched", "leaf_reduction"], 100.0),
            1
        ),
        span(
            &values(&["equal_value_batched", "insertion_time_ratio"], 1.0),
            2
        ),
        span(&values(&["equal_value_batched", "bytes_ratio"], 1.0), 2),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn span_gives_a_range_or_one_value() {
        assert_eq!(span(&[1.234, 5.0, 2.0], 1), "1.2 to 5.0");
        assert_eq!(span(&[0.801, 0.799], 2), "0.80");
        assert_eq!(span(&[], 2), "—");
    }

    /// Ranges over the real rows, the simulated set after them, and the comparability note.
    #[test]
    fn headline_over_known_real_rows() {
        let rows = [
            json!({"data": "scan.dat", "leaf_reduction": -0.5, "insertion_time_ratio": 0.2,
                   "equal_value": {"leaf_reduction": 0.6, "insertion_time_ratio": 0.8, "bytes_ratio": 0.4},
                   "equal_value_batched": {"leaf_reduction": 0.7, "insertion_time_ratio": 0.5, "bytes_ratio": 0.3}}),
            json!({"data": "kitti-00", "leaf_reduction": 0.1, "insertion_time_ratio": 2.0,
                   "equal_value": {"leaf_reduction": 0.2, "insertion_time_ratio": 3.0, "bytes_ratio": 0.9},
                   "equal_value_batched": {"leaf_reduction": 0.45, "insertion_time_ratio": 0.7, "bytes_ratio": 0.6}}),
        ];
        let h = headline(&rows, Some(&("urban".to_owned(), 0.064))).unwrap();
        assert!(h.starts_with("Real scans (scan.dat, kitti-00;"), "{h}");
        assert!(h.contains("gives -50.0 to 10.0 % fewer leaves"), "{h}");
        assert!(h.contains("at 0.20 to 2.00× its insertion time"), "{h}");
        assert!(
            h.contains("equal-value fusion (ours) 20.0 to 60.0 % fewer leaves"),
            "{h}"
        );
        assert!(
            h.contains("every updated cell 45.0 to 70.0 % fewer leaves at 0.50 to 0.70×"),
            "{h}"
        );
        assert!(h.contains("0.40 to 0.90× the bytes"), "{h}");
        assert!(
            h.contains("simulated `urban`: thesis rule 6.4 % fewer leaves"),
            "{h}"
        );
        assert!(
            h.ends_with("(its Freiburg campus graph is not available)."),
            "{h}"
        );
        assert!(headline(&[], None).is_none());
    }
}
