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

    let reads = Reads {
        results,
        failures,
        unknown,
        unsupported,
        documentation: docs.len(),
    };
    let report = report(&reads)?;
    if !reads.failures.is_empty() {
        anyhow::bail!(
            "{} files failed to read: {}",
            reads.failures.len(),
            reads
                .failures
                .iter()
                .map(|(p, e)| format!("{p}: {e}"))
                .collect::<Vec<_>>()
                .join("; ")
        );
    }
    Ok(report)
}

/// What reading the data directory found.
struct Reads {
    /// Files read in full.
    results: Vec<FileResult>,
    /// `(path, error)` of files of a known format that failed to read.
    failures: Vec<(String, String)>,
    /// `(path, error)` of files whose format was not recognised.
    unknown: Vec<(String, String)>,
    /// `(path, refusal)` of files recognised but refused by design.
    unsupported: Vec<(String, String)>,
    /// Documentation files skipped.
    documentation: usize,
}

/// The page and the JSON of `reads`.
fn report(reads: &Reads) -> Result<EvalReport> {
    let Reads {
        results,
        failures,
        unknown,
        unsupported,
        documentation,
    } = reads;

    let mut markdown = String::new();
    markdown.push_str(
        "Every file under the data directory is detected and read in full by `raypath-io` \
         (the same code as `raypath info`); the read time is the median of repeated reads \
         (1 in `--quick`, 3 otherwise) from the page cache, single thread. Throughput is file \
         bytes on disk (compressed where the file is) per second. All rows are real data.\n\n",
    );

    // Per format.
    let mut per_format: BTreeMap<&str, (usize, u64, f64, u64, u64)> = BTreeMap::new();
    for r in results {
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
    for r in results {
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
        for (path, error) in failures.iter().chain(unknown) {
            markdown.push_str(&format!("- `{path}`: {error}\n"));
        }
        for (path, refusal) in unsupported {
            markdown.push_str(&format!(
                "- `{path}`: recognised, reading not supported (the reader refuses it: {refusal})\n"
            ));
        }
    }
    markdown.push_str(&format!(
        "\n{} documentation files (README, LICENSE, map pictures) skipped.\n",
        documentation
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
    Ok(EvalReport {
        name: "io",
        title: "I/O: every file under RAYPATH_DATA, read by raypath-io".into(),
        markdown,
        json,
        headline: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(path: &str, format: Format, bytes: u64, seconds: f64, summary: Summary) -> FileResult {
        FileResult {
            path: path.to_owned(),
            format,
            bytes,
            seconds,
            summary,
        }
    }

    fn row<'a>(md: &'a str, heading: &str, first: &str) -> Vec<&'a str> {
        let start = md.find(heading).unwrap();
        md[start..]
            .lines()
            .find(|l| l.starts_with(&format!("| {first} ")))
            .unwrap()
            .split('|')
            .map(str::trim)
            .collect()
    }

    fn known_reads() -> Reads {
        let intel = Summary {
            scans: Some(100),
            beams: Some(180),
            points: Some(18_000),
            poses: Some(100),
            odometry: Some(50),
            ..Summary::new("carmen")
        };
        let mixed = Summary {
            scans: Some(10),
            beams: Some(361),
            beams_min: Some(180),
            beams_max: Some(361),
            points: Some(3_000),
            ..Summary::new("carmen")
        };
        let pcd = Summary {
            scans: Some(1),
            points: Some(6_400),
            width: Some(100),
            height: Some(64),
            ..Summary::new("pcd")
        };
        Reads {
            results: vec![
                file("carmen/intel.log.gz", Format::Carmen, 2_000_000, 0.5, intel),
                file("carmen/mixed.log", Format::Carmen, 1_000_000, 0.5, mixed),
                file("planes/crop.pcd", Format::Pcd, 500_000, 0.25, pcd),
            ],
            failures: vec![("carmen/bad.log".into(), "truncated line 3".into())],
            unknown: vec![("notes.bin".into(), "unknown format".into())],
            unsupported: vec![("ouster/drive.osf".into(), "convert it first".into())],
            documentation: 3,
        }
    }

    /// Totals per format, one row per file, the files not read and the JSON.
    #[test]
    fn report_from_known_reads() {
        let report = report(&known_reads()).unwrap();
        let md = &report.markdown;
        assert_eq!(
            &row(md, "## Throughput per format", "carmen")[1..8],
            ["carmen", "2", "3.00", "110", "21000", "1.000", "3.0"]
        );
        assert_eq!(
            &row(md, "## Throughput per format", "pcd")[1..8],
            ["pcd", "1", "0.50", "1", "6400", "0.250", "2.0"]
        );
        assert_eq!(
            &row(md, "## Files", "carmen/intel.log.gz")[2..11],
            ["carmen", "100", "180", "18000", "100", "50", "", "", "4.0"]
        );
        assert_eq!(row(md, "## Files", "carmen/mixed.log")[4], "361 (180–361)");
        let crop = row(md, "## Files", "planes/crop.pcd");
        assert_eq!(crop[8], "100 × 64");
        assert_eq!(crop[10], "2.0");
        assert!(
            md.contains(
                "\n## Not read\n\n- `carmen/bad.log`: truncated line 3\n- `notes.bin`: unknown \
                 format\n- `ouster/drive.osf`: recognised, reading not supported (the reader \
                 refuses it: convert it first)\n"
            ),
            "{md}"
        );
        assert!(md.contains("\n3 documentation files (README, LICENSE, map pictures) skipped.\n"));
        assert!(!md.contains("No data found"));

        let json = &report.json;
        assert_eq!(json["formats"][0]["format"], "carmen");
        assert_eq!(json["formats"][0]["files"], 2);
        assert_eq!(json["formats"][0]["bytes"], 3_000_000);
        assert_eq!(json["formats"][0]["mb_per_s"], 3.0);
        assert_eq!(json["formats"][1]["points"], 6_400);
        assert_eq!(json["files"][2]["path"], "planes/crop.pcd");
        assert_eq!(json["files"][2]["summary"]["width"], 100);
        assert_eq!(json["files"][0]["summary"]["format"], "carmen");
        assert_eq!(json["failures"][0]["error"], "truncated line 3");
        assert_eq!(json["unknown"][0]["path"], "notes.bin");
        assert_eq!(json["unsupported"][0]["refusal"], "convert it first");
    }

    /// Nothing read: empty tables, no "Not read" section, and the pointer to the data.
    #[test]
    fn report_without_data() {
        let reads = Reads {
            results: Vec::new(),
            failures: Vec::new(),
            unknown: Vec::new(),
            unsupported: Vec::new(),
            documentation: 0,
        };
        let report = report(&reads).unwrap();
        let md = &report.markdown;
        assert!(md.contains(
            "## Throughput per format\n\n| format | files | MB  | scans | points | read s | MB/s |\n"
        ));
        assert!(!md.contains("## Not read"));
        assert!(md.contains("\n0 documentation files"));
        assert!(md.ends_with("(see datasets/README.md).\n"), "{md}");
        assert_eq!(report.json["formats"].as_array().unwrap().len(), 0);
    }
}
