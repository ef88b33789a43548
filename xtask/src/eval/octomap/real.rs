//! The headline table: the real scans at r = 0.2 m, M = 8, beam-based, both fusion rules,
//! built from the run rows and variant rows the main loop records.

use serde_json::{Value, json};

use super::EQUAL_LABEL;
use super::data::Dataset;
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

/// The equal-value variant row of `data` (beam samples, r = 0.2 m, M = 8).
fn equal_variant<'a>(variants: &'a [Value], data: &str) -> Option<&'a Value> {
    variants
        .iter()
        .find(|v| v["data"] == data && v["variant"] == EQUAL_LABEL)
}

fn percent(v: &Value) -> String {
    v.as_f64()
        .map_or("—".into(), |v| format!("{:.1} %", 100.0 * v))
}

fn ratio(v: &Value) -> String {
    v.as_f64().map_or("—".into(), |v| fmt_num(v, 2))
}

/// The table over the real data sets and its JSON rows (`summary.real`).
pub fn table(sets: &[Dataset], rows: &[Value], variants: &[Value]) -> (Table, Vec<Value>) {
    let mut table = Table::new([
        "data (real)",
        "points",
        "OctoMap leaves",
        "leaf reduction: thesis rule / equal-value",
        "insert ratio: thesis rule / equal-value",
        "bytes ratio: thesis rule / equal-value",
        "like for like with thesis 28.5 % / > 1",
    ]);
    let mut json_rows = Vec::new();
    for set in sets.iter().filter(|s| s.real) {
        let Some(run) = headline_run(rows, &set.name) else {
            continue;
        };
        let equal = equal_variant(variants, &set.name)
            .cloned()
            .unwrap_or(Value::Null);
        table.row([
            set.name.clone(),
            set.graph.num_points().to_string(),
            run["octomap"]["leaves_pruned"]
                .to_string()
                .replace("null", "—"),
            format!(
                "{} / {}",
                percent(&run["leaf_reduction"]),
                percent(&equal["leaf_reduction"])
            ),
            format!(
                "{} / {}",
                ratio(&run["insertion_time_ratio"]),
                ratio(&equal["insertion_time_ratio"])
            ),
            format!(
                "{} / {}",
                ratio(&run["bytes_ratio"]),
                ratio(&equal["bytes_ratio"])
            ),
            NOT_LIKE_FOR_LIKE.into(),
        ]);
        json_rows.push(json!({
            "data": set.name,
            "points": set.graph.num_points(),
            "leaf_reduction": run["leaf_reduction"],
            "insertion_time_ratio": run["insertion_time_ratio"],
            "bytes_ratio": run["bytes_ratio"],
            "equal_value": {
                "leaf_reduction": equal["leaf_reduction"],
                "insertion_time_ratio": equal["insertion_time_ratio"],
                "bytes_ratio": equal["bytes_ratio"],
            },
        }));
    }
    (table, json_rows)
}
