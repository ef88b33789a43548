//! `cargo xtask eval synpeb`: PPE, the PEAC-style baseline and MSAC on the generated
//! SynPEB-style splits at the five noise levels and on the real 100 × 100 SynPEB sample,
//! beside Table 11.1 of Schaefer (2020). PPE runs with the preset of each noise level
//! (`PpeParams::preset("synpeb-<σ>")`, grid-searched on the training split).
//!
//! Metrics per scan (Hoover et al. with T = 0.8, `raypath_planes::compare`): f, k, per-ray
//! radial RMSE of the extracted planes (planes with RMSE ≥ 10 m excluded; Eq. 11.6 divides by the
//! number of planes, but the thesis' millimetre figures are per-ray values, so per ray here),
//! n_o, n_u, n_m, n_s and the extraction time; means over the scans of a split. The RMSE is
//! also given under the reference implementation's averaging (`ploteval.m` drops scans whose
//! RMSE exceeds 20 mm from the mean).
//!
//! In stages (`--shard i/n`, `merge`): one unit per noise level of the generated test split
//! (`generated/<σ>`), the real SynPEB sample (`real-sample`) and the real KITTI and Ouster
//! scans (`real-scans`); the page is drawn from their results alone.

use std::path::{Path, PathBuf};

use serde_json::{Value, json as value};

use anyhow::{Context, Result};
use raypath_io::pcd::{ReadOptions, read_pcd};
use raypath_planes::{MsacParams, PeacParams, PpeParams};

use super::planes::{HooverScore as Scan, Method, hoover_score, mean};
use super::stages::{Staged, UnitResults, field};
use super::{EvalContext, EvalReport, median};
use crate::table::{Table, fmt_num};

mod real;

const NAME: &str = "synpeb";
const LEVELS: [&str; 5] = ["0.0", "0.5", "1.0", "2.0", "4.0"];

fn run_scan(path: &Path, method: Method) -> Result<Scan> {
    let pcd = read_pcd(path, &ReadOptions::synpeb())
        .with_context(|| format!("reading {}", path.display()))?;
    let cloud = pcd.cloud;
    let (seg, secs) = method.run(&cloud, &path.display().to_string())?;
    let gt: Vec<Option<u32>> = cloud
        .label
        .clone()
        .unwrap_or_default()
        .into_iter()
        .map(Some)
        .collect();
    hoover_score(&gt, &seg, secs, None)
}

pub(super) fn pcd_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|it| {
            it.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "pcd"))
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}

/// Mean RMSE over the scans whose RMSE is at most 20 mm and their number (the averaging
/// of the reference implementation's `ploteval.m`).
fn rmse_ref(scans: &[Scan]) -> (f64, usize) {
    let kept: Vec<f64> = scans
        .iter()
        .map(|s| s.rmse_mm)
        .filter(|r| *r <= 20.0)
        .collect();
    if kept.is_empty() {
        (f64::NAN, 0)
    } else {
        (kept.iter().sum::<f64>() / kept.len() as f64, kept.len())
    }
}

fn row(t: &mut Table, name: &str, scans: &[Scan]) {
    let mut secs: Vec<f64> = scans.iter().map(|s| s.secs).collect();
    let (rref, kept) = rmse_ref(scans);
    t.row([
        name.to_owned(),
        scans.len().to_string(),
        fmt_num(mean(scans, |s| s.gt), 1),
        fmt_num(mean(scans, |s| s.planes), 1),
        fmt_num(mean(scans, |s| s.f), 1),
        fmt_num(mean(scans, |s| s.k), 1),
        fmt_num(mean(scans, |s| s.rmse_mm), 1),
        if kept == 0 {
            "–".to_owned()
        } else {
            format!("{} ({kept})", fmt_num(rref, 1))
        },
        fmt_num(mean(scans, |s| s.n_o), 1),
        fmt_num(mean(scans, |s| s.n_u), 1),
        fmt_num(mean(scans, |s| s.n_m), 1),
        fmt_num(mean(scans, |s| s.n_s), 1),
        fmt_num(median(&mut secs), 2),
    ]);
}

fn json(scans: &[Scan]) -> Value {
    let mut secs: Vec<f64> = scans.iter().map(|s| s.secs).collect();
    serde_json::json!({
        "scans": scans.len(),
        "f": mean(scans, |s| s.f), "k": mean(scans, |s| s.k), "rmse_mm": mean(scans, |s| s.rmse_mm),
        "rmse_ref_mm": rmse_ref(scans).0, "rmse_ref_scans": rmse_ref(scans).1,
        "n_o": mean(scans, |s| s.n_o), "n_u": mean(scans, |s| s.n_u),
        "n_m": mean(scans, |s| s.n_m), "n_s": mean(scans, |s| s.n_s),
        "gt_planes": mean(scans, |s| s.gt), "planes": mean(scans, |s| s.planes),
        "median_seconds": median(&mut secs),
    })
}

/// The stages of `eval synpeb`.
pub const STAGED: Staged = Staged {
    name: NAME,
    units,
    run_unit,
    report,
};

/// The noise levels of the generated split, the real sample, the real scans.
fn units(_ctx: &EvalContext) -> Result<Vec<String>> {
    Ok(LEVELS
        .iter()
        .map(|level| format!("generated/{level}"))
        .chain(["real-sample".to_owned(), "real-scans".to_owned()])
        .collect())
}

/// The scores of the three methods on `files` (PPE with `ppe`).
fn run_methods(ctx: &EvalContext, files: &[PathBuf], ppe: PpeParams, label: &str) -> Result<Value> {
    let bar = ctx.progress(files.len() as u64, label);
    let (mut scans, mut peacs, mut msacs) = (Vec::new(), Vec::new(), Vec::new());
    for f in files {
        scans.push(run_scan(f, Method::Ppe(ppe))?);
        peacs.push(run_scan(f, Method::Peac(PeacParams::synpeb()))?);
        msacs.push(run_scan(f, Method::Msac(MsacParams::synpeb()))?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(value!({ "ppe": scans, "peac": peacs, "msac": msacs }))
}

/// Measures one unit.
fn run_unit(ctx: &EvalContext, unit: &str) -> Result<Value> {
    if let Some(level) = unit.strip_prefix("generated/") {
        let name = format!("synpeb-{level}");
        let params = PpeParams::preset(&name).with_context(|| format!("no PPE preset {name}"))?;
        let set = crate::generate::ensure("synpeb", ctx.quick)?;
        let per_level = if ctx.quick { 2 } else { usize::MAX };
        let files: Vec<PathBuf> = pcd_files(&set.join("test").join(level))
            .into_iter()
            .take(per_level)
            .collect();
        return run_methods(ctx, &files, params, &format!("σ {level} cm"));
    }
    match unit {
        "real-sample" => {
            let sample = ctx.data(SAMPLE);
            if sample.is_file() {
                run_methods(ctx, &[sample], PpeParams::synpeb(), "real sample")
            } else {
                Ok(value!({ "absent": sample.display().to_string() }))
            }
        }
        "real-scans" => {
            let (markdown, json) = real::run(ctx)?;
            Ok(value!({ "markdown": markdown, "json": json }))
        }
        _ => anyhow::bail!("{unit:?} is not a unit of {NAME}"),
    }
}

/// The real SynPEB sample under `RAYPATH_DATA`.
const SAMPLE: &str = "planes/synpeb-sample-100x100.pcd";

/// The page from the unit results.
fn report(ctx: &EvalContext, results: &UnitResults) -> Result<EvalReport> {
    let params = PpeParams::synpeb();
    let unit = |name: &str| {
        results
            .iter()
            .find(|(u, _)| u == name)
            .map(|(_, v)| v)
            .with_context(|| format!("no result of unit {name}"))
    };
    let mut headers = vec![
        "data",
        "scans",
        "GT planes",
        "planes",
        "f [%]",
        "k [%]",
        "RMSE [mm]",
        "RMSE ≤ 20 [mm] (scans)",
    ];
    headers.extend(["n_o", "n_u", "n_m", "n_s", "time/scan [s]"]);
    let mut table = Table::new(headers);
    let mut presets = Table::new([
        "σ [cm]",
        "preset",
        "√e [m]",
        "l_max [m]",
        "min rays",
        "refine rounds",
    ]);
    let mut results_json = serde_json::Map::new();
    let mut level_scans = Vec::new();
    let msac_params = MsacParams::synpeb();
    let peac_params = PeacParams::synpeb();
    for level in LEVELS {
        let name = format!("synpeb-{level}");
        let level_params =
            PpeParams::preset(&name).with_context(|| format!("no PPE preset {name}"))?;
        presets.row([
            level.to_owned(),
            format!("`{name}`"),
            fmt_num(level_params.max_increment_m2.sqrt(), 2),
            fmt_num(level_params.l_max_m, 2),
            level_params.min_points.to_string(),
            level_params.refine_rounds.to_string(),
        ]);
        let measured = unit(&format!("generated/{level}"))?;
        let scans: Vec<Scan> = field(measured, "ppe")?;
        let peacs: Vec<Scan> = field(measured, "peac")?;
        let msacs: Vec<Scan> = field(measured, "msac")?;
        for (method, list) in [("PPE", &scans), ("PEAC-style", &peacs), ("MSAC", &msacs)] {
            row(
                &mut table,
                &format!("{method}, generated test, σ = {level} cm"),
                list,
            );
        }
        results_json.insert(format!("generated_{level}"), json(&scans));
        results_json.insert(format!("peac_generated_{level}"), json(&peacs));
        results_json.insert(format!("msac_generated_{level}"), json(&msacs));
        level_scans.push((level, scans, peacs));
    }
    let sample = unit("real-sample")?;
    let sample_note = match sample["absent"].as_str() {
        None => {
            for (method, key, out) in [
                ("PPE", "ppe", "real_sample"),
                ("PEAC-style", "peac", "peac_real_sample"),
                ("MSAC", "msac", "msac_real_sample"),
            ] {
                let scans: Vec<Scan> = field(sample, key)?;
                row(
                    &mut table,
                    &format!("{method}, real SynPEB sample 100 × 100"),
                    &scans,
                );
                results_json.insert(out.into(), json(&scans));
            }
            String::new()
        }
        Some(path) => format!("The real sample `{path}` is absent (see datasets/README.md).\n\n"),
    };
    let (at2, peac2) = level_scans
        .iter()
        .find(|(l, _, _)| *l == "2.0")
        .map(|(_, s, p)| (s.clone(), p.clone()))
        .unwrap_or_default();
    let mut peac_secs2: Vec<f64> = peac2.iter().map(|s| s.secs).collect();
    let peac_t2 = median(&mut peac_secs2);
    let mut secs2: Vec<f64> = at2.iter().map(|s| s.secs).collect();
    let (f2, rmse2, t2) = (
        mean(&at2, |s| s.f),
        mean(&at2, |s| s.rmse_mm),
        median(&mut secs2),
    );
    let mut aims = Table::new(["aim (σ = 2 cm)", "thesis", "measured", "met"]);
    aims.row([
        "f ≥ 73.6 %".to_owned(),
        "73.6".into(),
        fmt_num(f2, 1),
        yes_no(f2 >= 73.6).into(),
    ]);
    aims.row([
        "RMSE ≤ 14.5 mm".to_owned(),
        "14.5".into(),
        fmt_num(rmse2, 1),
        yes_no(rmse2 <= 14.5).into(),
    ]);
    aims.row([
        "≤ 1 s per 500 × 500 scan".to_owned(),
        "5760 (1.6 h)".into(),
        fmt_num(t2, 2),
        yes_no(t2 <= 1.0).into(),
    ]);
    let mut thesis = Table::new([
        "method (SynPEB, σ = 2 cm)",
        "f [%]",
        "k [%]",
        "RMSE [mm]",
        "n_o",
        "n_u",
        "n_m",
        "n_s",
    ]);
    thesis.row([
        "PEAC (thesis)",
        "29.1",
        "60.4",
        "28.6",
        "0.7",
        "1.0",
        "26.7",
        "7.4",
    ]);
    thesis.row([
        "MSAC (thesis)",
        "7.3",
        "35.6",
        "34.3",
        "0.3",
        "1.0",
        "36.3",
        "10.9",
    ]);
    thesis.row([
        "PPE (thesis)",
        "73.6",
        "77.9",
        "14.5",
        "1.5",
        "1.1",
        "7.1",
        "16.5",
    ]);
    aims.row([
        "PEAC-style baseline: time per scan [s]".to_owned(),
        "0.033 (PEAC)".into(),
        format!("{} (PPE/PEAC = {:.0}×)", fmt_num(peac_t2, 3), t2 / peac_t2),
        "–".into(),
    ]);
    let real_scans = unit("real-scans")?;
    let real_md: String = field(real_scans, "markdown")?;
    let real_json = real_scans["json"].clone();
    let headline = headline(&real_json, f2, t2, peac_t2);
    results_json.insert("real_scans".into(), real_json);
    let threads = rayon::current_num_threads();
    let markdown = format!(
        "PPE (`raypath_planes::extract` with the preset of each noise level, below), the \
         PEAC-style baseline (`raypath_planes::peac`, Feng et al. 2014: {bs} × {bs} blocks, \
         admissible RMS distance {sig:.4} r² + {it:.3} m for blocks and {sig:.4} r² + {mt:.3} m \
         for merges, depth discontinuity at {disc:.2} r, planes ≥ {pmin} rays, refinement \
         within {rs:.0} RMS) and MSAC (`raypath_planes::msac`, inlier distance {md:.3} m, \
         remaining fraction {mf:.2}, {mi} hypotheses per plane, not grid-searched), each timed in \
         the same run on the same scans, on the generated SynPEB-style test split \
         (`datasets/generated/synpeb`, 500 × 500, {which}) and on the real 100 × 100 SynPEB \
         sample (PPE preset `synpeb`). Hoover et al. with T = 0.8; f, k, RMSE and n_* are means \
         over the scans; RMSE is the per-ray radial RMSE of all extracted planes (Eq. 11.6 divides by the number of planes, but the thesis' millimetre figures, below the 20 mm noise, are per-ray values); \
         \"RMSE ≤ 20\" averages only the scans whose RMSE is at most 20 mm, as the reference \
         implementation's `ploteval.m` does (number of scans kept in brackets). Time is the \
         median extraction time per scan (PCD reading excluded) with {threads} rayon threads on \
         a machine shared with other jobs (absolute times are taken under load; compare the \
         methods side by side).\n\n{table}\n{sample_note}### PPE presets\n\n{presets}\n{GRID}\n\
         ### Table 11.1 (thesis, real SynPEB)\n\n{thesis}\n### Aims\n\n{aims}\nThe generated scans are ours (raypath-sim), not the SynPEB \
         download, so the figures are comparable in kind, not in value.\n\n{RMSE_NOTE}\n\
         **Closing note:** at σ = 2 cm PPE takes a median {t2:.2} s per 500 × 500 scan here, \
         {speedup:.0}× faster than the thesis' 1.6 h (5760 s) per scan, with f = {f2:.1} % and \
         RMSE = {rmse2:.1} mm on our generated scans; the PEAC-style baseline takes {peac_t2:.3} s.\n\n\
         {real_md}",
        bs = peac_params.block_size,
        sig = peac_params.depth_sigma_per_m,
        it = peac_params.init_tol_m,
        mt = peac_params.merge_tol_m,
        disc = peac_params.discontinuity_rel,
        pmin = peac_params.min_points,
        rs = peac_params.refine_sigmas,
        md = msac_params.max_distance_m,
        mf = msac_params.remaining_fraction,
        mi = msac_params.iterations,
        which = if ctx.quick {
            "first 2 scans per noise level (--quick)"
        } else {
            "all test scans"
        },
        table = table.to_markdown()?,
        presets = presets.to_markdown()?,
        thesis = thesis.to_markdown()?,
        aims = aims.to_markdown()?,
        speedup = 5760.0 / t2,
    );
    Ok(EvalReport {
        name: NAME,
        title: "PPE on SynPEB-style scans (Schaefer 2020, Table 11.1)".into(),
        markdown,
        json: serde_json::json!({"params": {"e_m2": params.max_increment_m2, "l_max_m": params.l_max_m,
            "min_points": params.min_points, "refine_rounds": params.refine_rounds},
            "msac_params": {"max_distance_m": msac_params.max_distance_m,
            "remaining_fraction": msac_params.remaining_fraction, "iterations": msac_params.iterations},
            "peac_params": {"block_size": peac_params.block_size, "depth_sigma_per_m": peac_params.depth_sigma_per_m,
            "init_tol_m": peac_params.init_tol_m, "merge_tol_m": peac_params.merge_tol_m,
            "discontinuity_rel": peac_params.discontinuity_rel, "min_points": peac_params.min_points,
            "refine_sigmas": peac_params.refine_sigmas},
            "results": results_json}),
        headline,
    })
}

/// How the presets were chosen (offline grid search on the training split).
const GRID: &str = "Grid search (as the thesis did, on the 10 training scans of each level; \
`cargo run --release -p raypath-planes --example ppe_scan -- --refine 3 --e E --lmax D \
datasets/generated/synpeb/train/<σ>/*.pcd`), mean f [%] on the training split. d = 0.10 and \
0.20 m (the top of the reference implementation's d grid) for every √e; d = 0.30 and 0.40 m \
only around the best √e (– = not run). The preset takes the best cell of its level (bold; \
ties to the larger d, then the larger √e):

| σ [cm] | d [m] | √e 0.06 | √e 0.10 | √e 0.14 | √e 0.20 | √e 0.28 | √e 0.40 |
| --- | --- | --- | --- | --- | --- | --- | --- |
| 0.0 | 0.10 | 80.4 | 79.8 | 78.1 | 72.6 | 70.0 | 66.8 |
| 0.0 | 0.20 | 84.8 | 84.1 | 82.1 | 77.5 | 75.3 | 70.7 |
| 0.0 | 0.30 | 85.0 | 84.9 | – | – | – | – |
| 0.0 | 0.40 | **85.7** | 85.3 | – | – | – | – |
| 0.5 | 0.10 | 80.4 | 80.4 | 79.3 | 73.1 | 69.1 | 66.1 |
| 0.5 | 0.20 | 84.0 | 83.6 | 82.3 | 76.8 | 73.3 | 70.0 |
| 0.5 | 0.30 | 84.1 | 84.2 | – | – | – | – |
| 0.5 | 0.40 | 84.5 | **84.5** | – | – | – | – |
| 1.0 | 0.10 | 74.7 | 76.6 | 75.4 | 72.4 | 69.1 | 66.7 |
| 1.0 | 0.20 | 76.9 | 79.4 | 78.7 | 75.6 | 72.7 | 67.7 |
| 1.0 | 0.30 | – | 79.4 | 79.5 | – | – | – |
| 1.0 | 0.40 | – | **79.5** | 79.2 | – | – | – |
| 2.0 | 0.10 | 4.9 | 60.8 | 66.7 | 66.9 | 66.5 | 62.1 |
| 2.0 | 0.20 | 6.8 | 61.9 | 70.0 | 69.7 | 68.5 | 65.9 |
| 2.0 | 0.30 | – | – | 70.3 | 70.0 | 69.8 | – |
| 2.0 | 0.40 | – | – | 71.2 | **71.2** | 70.0 | – |
| 4.0 | 0.10 | 0.2 | 0.8 | 5.4 | 42.3 | 53.7 | 53.6 |
| 4.0 | 0.20 | 0.2 | 1.2 | 9.0 | 45.2 | 56.0 | 57.2 |
| 4.0 | 0.30 | – | – | – | – | **57.3** | 57.0 |
| 4.0 | 0.40 | – | – | – | – | 56.2 | 57.0 |

Checks off this grid at √e = 0.20 m: σ = 2: d = 0.60 m → 68.9, d = ∞ → 69.1; σ = 4 \
(√e = 0.40): d = 0.60 → 56.0. The post-processing (`refine_rounds`, not in the thesis) on \
the σ = 2 cm training split at √e = d = 0.20 m: none 64.0 %, boundary refinement and \
adjacent merges 66.0 %, plus merging the pieces of a face split by an occluder 69.7 % \
(n_o 2.7 → 0.7, n_s 30.3 → 20.9). The PEAC-style preset comes from its own grid at \
σ = 2 cm (see `PeacParams::synpeb`); MSAC is not grid-searched.
";

/// How the thesis' RMSE is defined and why ours differs.
const RMSE_NOTE: &str = "RMSE definition: the reference implementation (`evalexp.m`) takes, \
per scan, the RMS of the radial residuals r − r̂ of every ray of every extracted plane (planes \
of at least 2 rays, planes with RMSE ≥ 10 m left out) against the plane parameters from the \
extraction — the definition we use (we leave out planes under 10 rays; keeping every regular \
plane of ≥ 4 rays leaves the σ = 2 cm training mean at 19.9 mm). Its `ploteval.m` then \
averages over the test scans **without the scans whose RMSE exceeds 20 mm** (column \"RMSE \
≤ 20\") and reads the curve at √e = 0.24 m. A plane fitted to n rays with radial noise σ \
leaves an expected RMS residual of σ √(1 − 3/n) ≈ σ, so 14.5 mm at σ = 20 mm is not \
reachable under this definition on scans whose radial noise really is 20 mm: unless the \
SynPEB \"2.0\" scans carry less effective radial noise than the thesis states, no extractor \
(nor the ground-truth segmentation) meets that aim here. Our RMSE sits at the noise level at \
every σ, which is what an unbiased fit gives.
";

fn yes_no(b: bool) -> &'static str {
    if b { "yes" } else { "no" }
}

/// The page's headline: PPE and PEAC-style on the held-out real KITTI frames, then PPE on the
/// generated SynPEB-style scans at σ = 2 cm.
fn headline(real: &Value, f2: f64, t2: f64, peac_t2: f64) -> Option<String> {
    let held =
        |method: &str, key: &str| real["kitti"][format!("{method}_kitti_held_out")][key].as_f64();
    let real_part = match (held("ppe", "f1"), held("peac", "f1"), held("msac", "f1")) {
        (Some(ppe), Some(peac), Some(msac)) => format!(
            "Real KITTI 01, 04, 07 (held out; tuned on 00; SemanticKITTI planar classes): PPE \
             F1 {:.1} % at {:.2} s per frame, PEAC-style {:.1} %, MSAC {:.1} %. ",
            100.0 * ppe,
            held("ppe", "median_seconds").unwrap_or(f64::NAN),
            100.0 * peac,
            100.0 * msac,
        ),
        _ => String::new(),
    };
    f2.is_finite().then(|| {
        format!(
            "{real_part}Generated SynPEB-style scans (simulated, σ = 2 cm): PPE f {f2:.1} % at \
             {t2:.2} s per 500 × 500 scan (PEAC-style {peac_t2:.2} s), thesis f 73.6 % on the \
             real SynPEB (not like for like: our own scans)."
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan(f: f64, rmse_mm: f64, secs: f64) -> Scan {
        Scan {
            f,
            k: 90.0,
            rmse_mm,
            gt: 10.0,
            planes: 12.0,
            secs,
            ..Scan::default()
        }
    }

    /// Means over the scans, the RMSE ≤ 20 mm average with its count, the median time.
    #[test]
    fn row_writes_means_the_reference_rmse_and_the_median_time() {
        let scans = [
            scan(60.0, 10.0, 1.0),
            scan(80.0, 30.0, 3.0),
            scan(70.0, 20.0, 2.0),
        ];
        let mut t = Table::new([
            "set",
            "scans",
            "gt",
            "planes",
            "f",
            "k",
            "rmse",
            "rmse ≤ 20",
            "n_o",
            "n_u",
            "n_m",
            "n_s",
            "time",
        ]);
        row(&mut t, "test", &scans);
        let md = t.to_markdown().unwrap();
        let line = md.lines().last().unwrap();
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        assert_eq!(
            &cells[1..8],
            ["test", "3", "10.0", "12.0", "70.0", "90.0", "20.0"]
        );
        assert_eq!(cells[8], "15.0 (2)");
        assert_eq!(cells[13], "2.00");
        let j = json(&scans);
        assert_eq!(j["rmse_ref_scans"], 2);
        assert_eq!(j["median_seconds"], 2.0);
    }

    /// The headline leads with the real KITTI figures and says the σ = 2 cm row is simulated.
    #[test]
    fn headline_leads_with_real_data_and_marks_the_simulated_part() {
        let real = serde_json::json!({"kitti": {
            "ppe_kitti_held_out": {"f1": 0.84, "median_seconds": 0.5},
            "peac_kitti_held_out": {"f1": 0.815},
            "msac_kitti_held_out": {"f1": 0.812},
        }});
        let h = headline(&real, 74.1, 1.9, 0.09).unwrap();
        assert!(h.starts_with("Real KITTI 01, 04, 07"), "{h}");
        assert!(h.contains("PPE F1 84.0 % at 0.50 s"), "{h}");
        assert!(
            h.contains("(simulated, σ = 2 cm): PPE f 74.1 % at 1.90 s"),
            "{h}"
        );
        assert!(h.contains("not like for like"), "{h}");
        assert!(headline(&serde_json::json!({}), f64::NAN, 0.0, 0.0).is_none());
    }

    /// The page from known unit results (two scans per level, the sample absent): every
    /// level has its three rows, the σ = 2 cm aims read its scans, the real section and
    /// its JSON come through, and a NaN angle survives the unit JSON.
    #[test]
    fn report_from_known_units() {
        let mut with_nan = scan(70.0, 15.0, 1.0);
        with_nan.alpha_deg = f64::NAN;
        let methods = value!({
            "ppe": [with_nan, scan(80.0, 16.0, 3.0)],
            "peac": [scan(30.0, 20.0, 0.1), scan(40.0, 22.0, 0.1)],
            "msac": [scan(10.0, 30.0, 0.5), scan(12.0, 31.0, 0.5)],
        });
        let back: Vec<Scan> = field(&methods, "ppe").unwrap();
        assert!(back[0].alpha_deg.is_nan());
        let mut results: Vec<(String, Value)> = LEVELS
            .iter()
            .map(|l| (format!("generated/{l}"), methods.clone()))
            .collect();
        results.push((
            "real-sample".into(),
            value!({ "absent": "/nowhere/sample.pcd" }),
        ));
        results.push((
            "real-scans".into(),
            value!({ "markdown": "## Real scans\n", "json": { "kitti": {} } }),
        ));
        let ctx = EvalContext::scratch(&std::env::temp_dir().join("raypath-synpeb-report-test"));
        let page = report(&ctx, &results).unwrap();
        let md = &page.markdown;
        assert!(md.contains("| PPE, generated test, σ = 2.0 cm "), "{md}");
        assert!(md.contains("| MSAC, generated test, σ = 4.0 cm "), "{md}");
        assert!(md.contains("`/nowhere/sample.pcd` is absent"), "{md}");
        assert!(md.contains("| f ≥ 73.6 %"), "{md}");
        assert!(md.ends_with("## Real scans\n"), "{md}");
        assert_eq!(page.json["results"]["generated_2.0"]["scans"], 2);
        assert!(page.headline.unwrap().contains("PPE f 75.0 % at 2.00 s"));
    }
}
