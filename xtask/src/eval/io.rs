//! `cargo xtask eval io`: read every file under `RAYPATH_DATA` with raypath-io, report what
//! each holds and how fast each format reads.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;
use raypath_io::{Format, Summary};

use super::{EvalContext, EvalReport, median};
use crate::table::{Table, fmt_num};

/// Files that are documentation or pictures, not data.
fn is_documentation(path: &Path) -> bool {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    name.ends_with(".md")
        || name.ends_with(".png")
        || name.starts_with("license")
        || name.starts_with('.')
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<_> = entries.flatten().map(|e| e.path()).collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            walk(&path, out);
        } else {
            out.push(path);
        }
    }
}

struct FileResult {
    path: String,
    format: Format,
    bytes: u64,
    seconds: f64,
    summary: Summary,
}

/// Runs the evaluation.
pub fn run(ctx: &EvalContext) -> Result<EvalReport> {
    let mut files = Vec::new();
    walk(&ctx.data_dir, &mut files);
    let (docs, data): (Vec<_>, Vec<_>) = files.into_iter().partition(|p| is_documentation(p));
    let repetitions = if ctx.quick { 1 } else { 3 };

    let bar = ctx.progress(data.len() as u64, "reading");
    let mut results = Vec::new();
    let mut failures = Vec::new();
    let mut unknown = Vec::new();
    let mut unsupported = Vec::new();
    for path in &data {
        let relative = path
            .strip_prefix(&ctx.data_dir)
            .unwrap_or(path)
            .display()
            .to_string();
        bar.set_message(relative.clone());
        let format = match Format::detect(path) {
            // Recognised, and refused by design with the command that converts it.
            Ok(Format::OusterOsf) => {
                let refusal = raypath_io::summarize_as(path, Format::OusterOsf)
                    .err()
                    .map_or_else(String::new, |e| e.to_string());
                unsupported.push((relative, refusal));
                bar.inc(1);
                continue;
            }
            Ok(format) => format,
            Err(error) => {
                unknown.push((relative, error.to_string()));
                bar.inc(1);
                continue;
            }
        };
        let bytes = std::fs::metadata(path).map_or(0, |m| m.len());
        let mut times = Vec::new();
        let mut outcome = None;
        for _ in 0..repetitions {
            let started = Instant::now();
            let result = raypath_io::summarize_as(path, format);
            times.push(started.elapsed().as_secs_f64());
            outcome = Some(result);
        }
        match outcome {
            Some(Ok(summary)) => results.push(FileResult {
                path: relative,
                format,
                bytes,
                seconds: median(&mut times),
                summary,
            }),
            Some(Err(error)) => failures.push((relative, error.to_string())),
            None => {}
        }
        bar.inc(1);
    }
    bar.finish_and_clear();

    let mut markdown = String::new();
    markdown.push_str(
        "Every file under the data directory is detected and read in full by `raypath-io` \
         (the same code as `raypath info`); the read time is the median of repeated reads \
         (1 in `--quick`, 3 otherwise) from the page cache, single thread. Throughput is file \
         bytes on disk (compressed where the file is) per second. All rows are real data.\n\n",
    );

    // Per format.
    let mut per_format: BTreeMap<&str, (usize, u64, f64, u64, u64)> = BTreeMap::new();
    for r in &results {
        let entry = per_format.entry(r.format.name()).or_default();
        entry.0 += 1;
        entry.1 += r.bytes;
        entry.2 += r.seconds;
        entry.3 += r.summary.scans.unwrap_or(0);
        entry.4 += r.summary.points.unwrap_or(0);
    }
    let mut table = Table::new(["format", "files", "MB", "scans", "points", "read s", "MB/s"]);
    for (format, (n, bytes, seconds, scans, points)) in &per_format {
        let mb = *bytes as f64 / 1e6;
        table.row([
            format.to_string(),
            n.to_string(),
            fmt_num(mb, 2),
            scans.to_string(),
            points.to_string(),
            fmt_num(*seconds, 3),
            fmt_num(mb / seconds.max(1e-9), 1),
        ]);
    }
    markdown.push_str("## Throughput per format\n\n");
    markdown.push_str(&table.to_markdown()?);

    // Per file.
    let mut table = Table::new([
        "file", "format", "scans", "beams", "points", "poses", "odometry", "w × h", "nodes", "MB/s",
    ]);
    let opt = |v: Option<u64>| v.map_or(String::new(), |v| v.to_string());
    for r in &results {
        let s = &r.summary;
        let beams = match (s.beams, s.beams_min, s.beams_max) {
            (Some(b), Some(lo), Some(hi)) => format!("{b} ({lo}–{hi})"),
            (b, _, _) => opt(b),
        };
        let wh = match (s.width, s.height) {
            (Some(w), Some(h)) => format!("{w} × {h}"),
            _ => String::new(),
        };
        table.row([
            r.path.clone(),
            r.format.name().to_owned(),
            opt(s.scans),
            beams,
            opt(s.points),
            opt(s.poses),
            opt(s.odometry),
            wh,
            opt(s.nodes),
            fmt_num(r.bytes as f64 / 1e6 / r.seconds.max(1e-9), 1),
        ]);
    }
    markdown.push_str("\n## Files\n\n");
    markdown.push_str(&table.to_markdown()?);

    if !failures.is_empty() || !unknown.is_empty() || !unsupported.is_empty() {
        markdown.push_str("\n## Not read\n\n");
        for (path, error) in failures.iter().chain(&unknown) {
            markdown.push_str(&format!("- `{path}`: {error}\n"));
        }
        for (path, refusal) in &unsupported {
            markdown.push_str(&format!(
                "- `{path}`: recognised, reading not supported (the reader refuses it: {refusal})\n"
            ));
        }
    }
    markdown.push_str(&format!(
        "\n{} documentation files (README, LICENSE, map pictures) skipped.\n",
        docs.len()
    ));
    if results.is_empty() {
        markdown.push_str(
            "\n**No data found.** Point `RAYPATH_DATA` at a data directory (see datasets/README.md).\n",
        );
    }

    let json = serde_json::json!({
        "formats": per_format.iter().map(|(format, (n, bytes, seconds, scans, points))| {
            serde_json::json!({
                "format": format, "files": n, "bytes": bytes, "seconds": seconds,
                "scans": scans, "points": points,
                "mb_per_s": *bytes as f64 / 1e6 / seconds.max(1e-9),
            })
        }).collect::<Vec<_>>(),
        "files": results.iter().map(|r| serde_json::json!({
            "path": r.path, "bytes": r.bytes, "seconds": r.seconds, "summary": r.summary,
        })).collect::<Vec<_>>(),
        "failures": failures.iter().map(|(p, e)| serde_json::json!({"path": p, "error": e})).collect::<Vec<_>>(),
        "unknown": unknown.iter().map(|(p, e)| serde_json::json!({"path": p, "error": e})).collect::<Vec<_>>(),
        "unsupported": unsupported.iter().map(|(p, e)| serde_json::json!({"path": p, "refusal": e})).collect::<Vec<_>>(),
    });
    if !failures.is_empty() {
        anyhow::bail!(
            "{} files failed to read: {}",
            failures.len(),
            failures
                .iter()
                .map(|(p, e)| format!("{p}: {e}"))
                .collect::<Vec<_>>()
                .join("; ")
        );
    }
    Ok(EvalReport {
        name: "io",
        title: "I/O: every file under RAYPATH_DATA, read by raypath-io".into(),
        markdown,
        json,
        headline: None,
    })
}
