//! `raypath info`: what a file holds.

use std::path::PathBuf;

use raypath_io::{Format, Summary};

use super::Failure;

/// Arguments of `raypath info`.
#[derive(clap::Args)]
pub struct Args {
    /// A file (CARMEN log, PCD, OctoMap .bt/.graph, xyz text, KITTI/NCLT file, SegComp file,
    /// point CSV; plain, .gz or .bz2), a KITTI sequence / NCLT session directory, or a rosbag2
    /// bag (its directory with metadata.yaml, or its .mcap file: topics, types, counts, rates,
    /// time span), or an Ouster .pcap/.pcapng with its metadata .json beside it (frames,
    /// columns × beams, profile, valid returns, range span).
    pub path: PathBuf,
    /// Read the input as this format instead of detecting it (for example `carmen`, `pcd`,
    /// `xyz`, `octomap-bt`, `kitti`, `nclt`).
    #[arg(long, value_name = "NAME")]
    pub format: Option<String>,
}

/// Runs `raypath info`.
pub fn run(args: &Args) -> Result<(), Failure> {
    let format = match &args.format {
        Some(name) => Format::from_name(name).ok_or_else(|| {
            let names: Vec<_> = Format::ALL.iter().map(|f| f.name()).collect();
            Failure::input(format!(
                "unknown format {name:?}; choose one of {}",
                names.join(", ")
            ))
        })?,
        None => Format::detect(&args.path).map_err(Failure::input)?,
    };
    let summary = raypath_io::summarize_as(&args.path, format).map_err(Failure::input)?;
    if super::console::json() {
        let text =
            serde_json::to_string_pretty(&summary).map_err(|e| Failure::internal(e.to_string()))?;
        println!("{text}");
    } else {
        print!("{}", render_text(&args.path, &summary));
    }
    Ok(())
}

/// The human-readable report: one `key: value` line per field that applies.
pub fn render_text(path: &std::path::Path, s: &Summary) -> String {
    let mut lines = vec![(String::from("file"), path.display().to_string())];
    let mut push = |key: &str, value: String| lines.push((key.to_owned(), value));
    push("format", s.format.clone());
    if let Some(v) = s.scans {
        push("scans", v.to_string());
    }
    if let Some(v) = s.beams {
        let range = match (s.beams_min, s.beams_max) {
            (Some(lo), Some(hi)) => format!(" (most common; {lo} to {hi})"),
            _ => String::new(),
        };
        push("beams", format!("{v}{range}"));
    }
    for (key, value) in [
        ("points", s.points),
        ("poses", s.poses),
        ("odometry", s.odometry),
        ("nodes", s.nodes),
    ] {
        if let Some(v) = value {
            push(key, v.to_string());
        }
    }
    if let (Some(w), Some(h)) = (s.width, s.height) {
        push("size", format!("{w} × {h} (width × height)"));
    }
    if let Some(labels) = &s.labels {
        let shown: Vec<_> = labels.iter().take(20).map(u32::to_string).collect();
        let more = if labels.len() > 20 { ", …" } else { "" };
        push(
            "labels",
            format!("{} distinct: {}{more}", labels.len(), shown.join(", ")),
        );
    }
    if let Some(b) = &s.bbox {
        push(
            "bbox",
            format!(
                "[{:.3}, {:.3}, {:.3}] to [{:.3}, {:.3}, {:.3}] m",
                b.min[0], b.min[1], b.min[2], b.max[0], b.max[1], b.max[2]
            ),
        );
    }
    if let Some(t) = &s.time_span {
        push(
            "time span",
            format!("{:.6} to {:.6} s ({:.3} s)", t.start, t.end, t.duration),
        );
    }
    for (key, value) in &s.extra {
        if key != "topics" && key != "semantic_classes" {
            push(&key.replace('_', " "), render_value(value));
        }
    }
    let width = lines
        .iter()
        .map(|(k, _)| k.chars().count())
        .max()
        .unwrap_or(0)
        + 1;
    let mut text: String = lines
        .iter()
        .map(|(k, v)| format!("{:<width$}  {v}\n", format!("{k}:")))
        .collect();
    if let Some(serde_json::Value::Array(topics)) = s.extra.get("topics") {
        text.push_str(&render_topics(topics));
    }
    if let Some(classes) = s.extra.get("semantic_classes") {
        text.push_str(&render_classes(classes));
    }
    text
}

/// SemanticKITTI label counts as a table: class id, name, points, share, instances.
fn render_classes(classes: &serde_json::Value) -> String {
    let rows = classes["classes"].as_array().map_or(&[][..], Vec::as_slice);
    let total: u64 = rows.iter().filter_map(|r| r["points"].as_u64()).sum();
    let mut text = format!(
        "semantic labels ({} labelled frames):\n  {:>5}  {:<22} {:>10} {:>7} {:>9}\n",
        classes["frames"], "class", "name", "points", "share", "instances"
    );
    for r in rows {
        let points = r["points"].as_u64().unwrap_or(0);
        text.push_str(&format!(
            "  {:>5}  {:<22} {:>10} {:>6.2}% {:>9}\n",
            r["class"],
            r["name"].as_str().unwrap_or(""),
            points,
            100.0 * points as f64 / total.max(1) as f64,
            r["instances"]
        ));
    }
    text
}

/// A bag's topics as a table: name, type, messages, rate, first and last log time.
fn render_topics(topics: &[serde_json::Value]) -> String {
    let rows: Vec<[String; 5]> = topics
        .iter()
        .map(|t| {
            let text = |key: &str| t[key].as_str().unwrap_or("").to_owned();
            let number = |key: &str, digits: usize| {
                t[key]
                    .as_f64()
                    .map_or_else(|| "-".to_owned(), |v| format!("{v:.digits$}"))
            };
            [
                text("name"),
                text("type"),
                t["message_count"].to_string(),
                number("rate_hz", 2),
                format!("{} to {}", number("first_secs", 3), number("last_secs", 3)),
            ]
        })
        .collect();
    let header = ["topic", "type", "messages", "rate Hz", "log time s"];
    let widths: Vec<usize> = (0..5)
        .map(|c| {
            rows.iter()
                .map(|r| r[c].chars().count())
                .chain([header[c].len()])
                .max()
                .unwrap_or(0)
        })
        .collect();
    let line = |cells: [&str; 5]| {
        let mut out = String::from(" ");
        for (c, cell) in cells.iter().enumerate() {
            out.push_str(&format!(" {cell:<w$}", w = widths[c]));
        }
        out.trim_end().to_owned() + "\n"
    };
    let mut out = format!("topics ({}):\n", rows.len());
    out.push_str(&line(header));
    for r in &rows {
        out.push_str(&line([&r[0], &r[1], &r[2], &r[3], &r[4]]));
    }
    out
}

/// A JSON value as text: strings bare, flat arrays and objects as lists, nested ones as JSON.
fn render_value(value: &serde_json::Value) -> String {
    use serde_json::Value;
    let scalar = |v: &Value| match v {
        Value::String(text) => Some(text.clone()),
        Value::Array(_) | Value::Object(_) => None,
        other => Some(other.to_string()),
    };
    match value {
        Value::Array(items) => items
            .iter()
            .map(scalar)
            .collect::<Option<Vec<_>>>()
            .map_or_else(|| value.to_string(), |items| items.join(", ")),
        Value::Object(map) => map
            .iter()
            .map(|(k, v)| scalar(v).map(|v| format!("{k} {v}")))
            .collect::<Option<Vec<_>>>()
            .map_or_else(|| value.to_string(), |items| items.join(", ")),
        other => scalar(other).unwrap_or_default(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_flat_values_as_lists() {
        let v = serde_json::json!({"FLASER": 910, "ODOM": 14541});
        assert_eq!(render_value(&v), "FLASER 910, ODOM 14541");
        assert_eq!(render_value(&serde_json::json!(["x", "y"])), "x, y");
        assert_eq!(render_value(&serde_json::json!("ascii")), "ascii");
        let nested = serde_json::json!({"min": [1, 2]});
        assert_eq!(render_value(&nested), nested.to_string());
    }
}
