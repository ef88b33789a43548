//! The tables of every run and every variant, with their JSON rows, from the measurements.

use serde_json::{Value, json};

use super::measure::{Compared, RunRecord, SetInfo, VariantRecord, model_name};
use crate::table::{Table, fmt_num};

/// `—` for a missing value, else `v` with `digits` decimals.
fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("—".to_owned(), |v| fmt_num(v, digits))
}

/// A share as `12.3 %`, `—` for a missing one.
fn percent(v: Option<f64>) -> String {
    v.map_or("—".into(), |v| format!("{:.1} %", 100.0 * v))
}

/// The agreement as `all / known`, `—` without OctoMap.
fn agree(c: &Compared) -> String {
    c.agreement
        .map_or("—".into(), |(a, k)| format!("{:.3} / {:.3}", a, k))
}

/// µs per point of `secs` over `set`'s points.
fn per_point_us(set: &SetInfo, secs: f64) -> f64 {
    secs / set.points.max(1) as f64 * 1e6
}

/// The table of all runs and its JSON rows (`runs`).
pub fn runs(sets: &[&SetInfo]) -> (Table, Vec<Value>) {
    let mut table = Table::new([
        "data",
        "model",
        "r [m]",
        "M",
        "leaves",
        "fused",
        "nodes",
        "height",
        "bytes",
        "insert [µs/pt]",
        "access [ms]",
        "OctoMap leaves (pruned)",
        "OctoMap inner",
        "OctoMap bytes",
        "OctoMap insert [µs/pt]",
        "OctoMap access [ms]",
        "leaf reduction",
        "insert ratio",
        "bytes ratio",
        "agree (all / known)",
    ]);
    let mut rows = Vec::new();
    for set in sets {
        for run in &set.runs {
            table.row(run_row(set, run));
            rows.push(run_json(set, run));
        }
    }
    (table, rows)
}

fn run_row(set: &SetInfo, run: &RunRecord) -> [String; 20] {
    let (ours, peer) = (&run.compared.ours, run.compared.peer.as_ref());
    [
        set.name.clone(),
        model_name(run.endpoint).to_owned(),
        format!("{}", run.resolution_m),
        run.m.to_string(),
        ours.leaves.to_string(),
        ours.fused.to_string(),
        ours.nodes.to_string(),
        ours.height.to_string(),
        ours.bytes.to_string(),
        fmt_num(per_point_us(set, ours.insert_secs), 3),
        fmt_num(ours.access_secs * 1e3, 3),
        peer.map_or("—".into(), |p| p.leaves.to_string()),
        peer.map_or("—".into(), |p| p.inner_nodes.to_string()),
        peer.map_or("—".into(), |p| p.memory_bytes.to_string()),
        opt(peer.map(|p| per_point_us(set, p.insert_secs)), 3),
        opt(peer.map(|p| p.access_secs * 1e3), 3),
        percent(run.compared.reduction()),
        opt(run.compared.insert_ratio(), 2),
        opt(run.compared.bytes_ratio(), 2),
        agree(&run.compared),
    ]
}

fn run_json(set: &SetInfo, run: &RunRecord) -> Value {
    let c = &run.compared;
    let ours = &c.ours;
    json!({
        "data": set.name, "model": model_name(run.endpoint), "resolution_m": run.resolution_m,
        "m": run.m, "points": set.points,
        "ours": {"leaves": ours.leaves, "fused_leaves": ours.fused, "nodes": ours.nodes,
            "height": ours.height, "bytes": ours.bytes, "insert_secs": ours.insert_secs,
            "access_secs": ours.access_secs, "occupied_leaves": ours.occupied},
        "octomap": c.peer.as_ref().map(|p| json!({"leaves_pruned": p.leaves,
            "leaves_built": p.leaves_built, "inner_nodes": p.inner_nodes, "nodes": p.nodes,
            "memory_bytes": p.memory_bytes, "insert_secs": p.insert_secs,
            "access_secs": p.access_secs, "occupied_leaves": p.occupied_leaves})),
        "leaf_reduction": c.reduction(), "insertion_time_ratio": c.insert_ratio(),
        "bytes_ratio": c.bytes_ratio(),
        "agreement_all": c.agreement.map(|a| a.0), "agreement_known": c.agreement.map(|a| a.1),
    })
}

/// The table of our variants and its JSON rows (`variants`).
pub fn variants(sets: &[&SetInfo]) -> (Table, Vec<Value>) {
    let mut table = Table::new([
        "data",
        "variant",
        "leaves",
        "fused",
        "bytes",
        "insert [µs/pt]",
        "leaf reduction",
        "insert ratio",
        "agree (all / known)",
    ]);
    let mut rows = Vec::new();
    for set in sets {
        for variant in &set.variants {
            let (c, ours) = (&variant.compared, &variant.compared.ours);
            table.row([
                set.name.clone(),
                variant.label.clone(),
                ours.leaves.to_string(),
                ours.fused.to_string(),
                ours.bytes.to_string(),
                fmt_num(per_point_us(set, ours.insert_secs), 3),
                percent(c.reduction()),
                opt(c.insert_ratio(), 2),
                agree(c),
            ]);
            rows.push(variant_json(set, variant));
        }
    }
    (table, rows)
}

fn variant_json(set: &SetInfo, v: &VariantRecord) -> Value {
    let c = &v.compared;
    json!({
        "data": set.name, "variant": v.label, "fusion": v.fusion,
        "fusion_rule": v.fusion_rule, "selection": v.selection,
        "split_on_unclamp": v.split_on_unclamp,
        "fusion_interval_scans": v.fusion_interval_scans,
        "leaves": c.ours.leaves, "fused_leaves": c.ours.fused, "bytes": c.ours.bytes,
        "insert_secs": c.ours.insert_secs,
        "leaf_reduction": c.reduction(),
        "insertion_time_ratio": c.insert_ratio(),
        "bytes_ratio": c.bytes_ratio(),
    })
}
