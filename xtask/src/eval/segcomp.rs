//! `cargo xtask eval segcomp`: PPE on the SegComp Perceptron test scans (Hoover et al. 1996)
//! beside the SegComp rows of Table 11.1 of Schaefer (2020), when the data is installed
//! under `RAYPATH_DATA/segcomp`; otherwise the report says it is missing and how to get it.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use raypath_io::segcomp::{read_gt_ang, read_gt_seg, read_perceptron};
use raypath_planes::hoover::angle_deviation;
use raypath_planes::{HooverParams, PpeParams, compare, extract};

use super::{EvalContext, EvalReport};
use crate::table::{Table, fmt_num};

const NAME: &str = "segcomp";

const HOW_TO_GET: &str = "SegComp is not redistributed with raypath. Download the Perceptron \
collection of the USF range segmentation comparison (Hoover et al. 1996; \
`http://marathon.csee.usf.edu/range/seg-comp/SegComp.html`, archives `perc.train.tar` / \
`perc.test.tar` of `compress`-ed files), unpack them into `$RAYPATH_DATA/segcomp/` so that \
files such as `perc.test.0`, `perc.test.0.gt-seg` and `perc.test.0.gt-ang` (optionally with \
`.Z`/`.gz` suffix) lie there, and rerun `cargo xtask eval segcomp`.";

/// Test range images: `perc.test.N` with an optional compression suffix.
fn test_scans(dir: &Path) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|it| it.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    out.retain(|p| {
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let stem = name
            .trim_end_matches(".Z")
            .trim_end_matches(".gz")
            .trim_end_matches(".bz2");
        stem.starts_with("perc.test.")
            && stem["perc.test.".len()..]
                .chars()
                .all(|c| c.is_ascii_digit())
    });
    out.sort();
    out
}

/// The companion file `<stem>.<ext>` with any compression suffix.
fn companion(scan: &Path, ext: &str) -> Option<PathBuf> {
    let name = scan.file_name()?.to_str()?;
    let stem = name
        .trim_end_matches(".Z")
        .trim_end_matches(".gz")
        .trim_end_matches(".bz2");
    ["", ".Z", ".gz", ".bz2"]
        .iter()
        .map(|s| scan.with_file_name(format!("{stem}.{ext}{s}")))
        .find(|p| p.is_file())
}

/// Runs the evaluation.
pub fn run(ctx: &EvalContext) -> Result<EvalReport> {
    let dir = ctx.data("segcomp");
    let mut scans = test_scans(&dir);
    let mut thesis = Table::new([
        "method (SegComp Perceptron)",
        "f [%]",
        "k [%]",
        "RMSE [mm]",
        "α [°]",
        "n_o",
        "n_u",
        "n_m",
        "n_s",
    ]);
    thesis.row([
        "PEAC (thesis)",
        "48.6",
        "91.3",
        "2.6",
        "2.6",
        "0.0",
        "0.1",
        "7.1",
        "2.0",
    ]);
    thesis.row([
        "MSAC (thesis)",
        "18.5",
        "76.7",
        "3.4",
        "3.9",
        "0.1",
        "0.2",
        "11.3",
        "3.4",
    ]);
    thesis.row([
        "PPE (thesis)",
        "60.7",
        "61.2",
        "2.9",
        "2.8",
        "1.4",
        "1.1",
        "1.5",
        "2.3",
    ]);
    if scans.is_empty() {
        let markdown = format!(
            "**SegComp data is missing**: no `perc.test.N` range images under `{}`.\n\n{HOW_TO_GET}\n\n\
             ### Table 11.1 (thesis, SegComp rows)\n\n{}",
            dir.display(),
            thesis.to_markdown()?
        );
        eprintln!(
            "segcomp: data missing under {} — {HOW_TO_GET}",
            dir.display()
        );
        return Ok(EvalReport {
            name: NAME,
            title: "PPE on SegComp Perceptron (Schaefer 2020, Table 11.1)".into(),
            markdown,
            json: serde_json::json!({"missing": true, "data_dir": dir.display().to_string()}),
            headline: None,
        });
    }
    if ctx.quick {
        scans.truncate(3);
    }
    let params = PpeParams::segcomp();
    let mut table = Table::new([
        "scan",
        "GT planes",
        "f [%]",
        "k [%]",
        "RMSE [mm]",
        "α [°]",
        "n_o",
        "n_u",
        "n_m",
        "n_s",
        "time [s]",
    ]);
    let mut rows = Vec::new();
    let bar = ctx.progress(scans.len() as u64, "segcomp");
    for scan in &scans {
        let perc = read_perceptron(scan).with_context(|| format!("reading {}", scan.display()))?;
        let gt_path = companion(scan, "gt-seg")
            .with_context(|| format!("no .gt-seg beside {}", scan.display()))?;
        let gt = read_gt_seg(&gt_path)?;
        let started = Instant::now();
        let seg = extract(&perc.cloud, &params)?;
        let secs = started.elapsed().as_secs_f64();
        let gt_labels: Vec<Option<u32>> = gt.labels.iter().copied().map(Some).collect();
        let h = compare(&gt_labels, &seg.labels, &HooverParams::default())?;
        let alpha = match companion(scan, "gt-ang")
            .map(|p| read_gt_ang(&p))
            .transpose()?
        {
            Some(angles) => {
                let pairs: Vec<(u32, u32, f64)> = angles
                    .pairs
                    .iter()
                    .map(|p| (p.label_a, p.label_b, p.angle_deg))
                    .collect();
                let (sum, count) = angle_deviation(&h, &pairs, |m| {
                    seg.planes.get(m as usize).map(|p| p.fit.normal())
                });
                if count == 0 {
                    f64::NAN
                } else {
                    sum / count as f64
                }
            }
            None => f64::NAN,
        };
        let vals = [
            h.gt_regions as f64,
            100.0 * h.fraction_correct(),
            100.0 * h.k_value(),
            1000.0 * seg.rmse_m(),
            alpha,
            h.over as f64,
            h.under as f64,
            h.missed as f64,
            h.noise as f64,
            secs,
        ];
        let name = scan
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or("?")
            .to_owned();
        let mut cells = vec![name];
        cells.extend(vals.iter().map(|v| fmt_num(*v, 1)));
        table.row(cells);
        rows.push(vals);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let n = rows.len() as f64;
    let mean = |i: usize| {
        let v: Vec<f64> = rows
            .iter()
            .map(|r| r[i])
            .filter(|x| x.is_finite())
            .collect();
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    let mut cells = vec![format!("mean of {n}")];
    cells.extend((0..10).map(|i| fmt_num(mean(i), 1)));
    table.row(cells);
    let markdown = format!(
        "PPE (preset `PpeParams::segcomp()`, not tuned on the real training scans) on the SegComp \
         Perceptron test scans under `{}`{}. Hoover et al. with T = 0.8.\n\n{}\n### Table 11.1 (thesis)\n\n{}",
        dir.display(),
        if ctx.quick {
            " (first 3 with --quick)"
        } else {
            ""
        },
        table.to_markdown()?,
        thesis.to_markdown()?
    );
    Ok(EvalReport {
        name: NAME,
        title: "PPE on SegComp Perceptron (Schaefer 2020, Table 11.1)".into(),
        markdown,
        json: serde_json::json!({"missing": false, "scans": rows.len(), "f": mean(1), "k": mean(2),
            "rmse_mm": mean(3), "alpha_deg": mean(4), "n_o": mean(5), "n_u": mean(6), "n_m": mean(7), "n_s": mean(8)}),
        headline: None,
    })
}
