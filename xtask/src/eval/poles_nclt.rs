//! `cargo xtask eval poles-nclt`: long-term pole-based localization on the simulated
//! NCLT-style sessions (Schaefer 2020, §12.4, Table 12.1).
//!
//! * Data: `datasets/generated/urban-nclt` — sessions months apart through one procedural
//!   street world with changes (parked cars, moved/removed/added sign posts and bollards, cut
//!   trees, shifted construction barrels, foliage), simulated HDL-32E scans, noisy odometry,
//!   NCLT layout (`raypath-sim`).
//! * Map (spec §3.2, `ncltpoles.py`): local maps every 1.5 m over 1.5 m along the
//!   ground truth; session 1 contributes all of them, later sessions only the local maps
//!   centred ≥ 10 m from every pose of the earlier sessions (`f_map` = fraction of a session's
//!   local maps added); the map keeps the overlap clusters with ≥ 3 detections.
//! * Localization of every session on that map: 5000 particles, 2.5 m / ±5° initial spread,
//!   the recorded odometry with its stated covariance × 4, online poles from local maps built
//!   along the **odometry** through the 2-of-3 filter, σ² = 1.5 m², ε = 0.1; 10 runs per
//!   session (2 in `--quick`), errors every 1 m.

use std::fmt::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use nalgebra::Point3;
use raypath_poles::{
    Drive, ExtractionTotals, LocalMap, OdometryNoise, Pole, Preset, detection_quality, local_maps,
    localize_run, merge_poles, online_poles,
};
use serde_json::json;

use super::poles_kitti::{RunSummary, near, speed_row, truth_near};
use super::{EvalContext, EvalReport};
use crate::table::{Table, fmt_num};

const NAME: &str = "poles-nclt";
/// Later sessions add local maps centred at least this far from earlier poses, metres.
const NEW_AREA_M: f64 = 10.0;

/// Runs the evaluation.
pub fn run(ctx: &EvalContext) -> Result<EvalReport> {
    let root = crate::generate::ensure("urban-nclt", ctx.quick)?;
    let mut sessions = session_dirs(&root)?;
    let (runs, max_scans) = if ctx.quick {
        // The first session and the last (which revisits part of the first).
        if sessions.len() > 2 {
            sessions = vec![sessions[0].clone(), sessions[sessions.len() - 1].clone()];
        }
        (2, Some(100))
    } else {
        (10, None)
    };
    let preset = Preset::nclt();
    let mut drives = Vec::new();
    for dir in &sessions {
        let drive = Drive::open(dir).with_context(|| format!("opening {}", dir.display()))?;
        let end = max_scans.map_or(drive.len(), |m| m.min(drive.len()));
        drives.push((dir.clone(), drive, end));
    }

    // 1. The reference map.
    let mut contributing: Vec<LocalMap> = Vec::new();
    let mut earlier_positions: Vec<Point3<f64>> = Vec::new();
    let mut f_map = Vec::new();
    let mut map_totals = ExtractionTotals::default();
    for (k, (_, drive, end)) in drives.iter().enumerate() {
        let gt = drive.require_ground_truth()?;
        let bar = ctx.progress(0, "map");
        let (maps, totals) = local_maps_new_areas(
            drive,
            gt,
            *end,
            &preset,
            &earlier_positions,
            k == 0,
            |d, t| {
                bar.set_length(t as u64);
                bar.set_position(d as u64);
            },
        )?;
        bar.finish_and_clear();
        add_totals(&mut map_totals, &totals);
        f_map.push(maps.1 as f64 / maps.2.max(1) as f64);
        contributing.extend(maps.0);
        earlier_positions.extend(gt[..*end].iter().map(|p| Point3::from(p.translation())));
    }
    let all: Vec<Pole> = contributing
        .iter()
        .flat_map(|m| m.poles.iter().copied())
        .collect();
    let map = merge_poles(&all, preset.segments.min_map_detections);

    // 2. Localization of every session.
    let mut table = Table::new([
        "session",
        "f_map [%]",
        "Δ_pos [m]",
        "RMSE_pos [m]",
        "Δ_ang [°]",
        "RMSE_ang [°]",
        "diverged runs",
        "thesis Δ_pos [m]",
        "thesis RMSE_pos [m]",
        "thesis Δ_ang [°]",
        "thesis RMSE_ang [°]",
    ]);
    let mut detection = Table::new([
        "session",
        "scans",
        "map poles ≤ 12 m",
        "true poles ≤ 12 m",
        "precision",
        "recall",
        "centre error [m]",
    ]);
    let mut speed = Table::new([
        "session",
        "rays traced",
        "trace [s]",
        "score [s]",
        "points/s",
        "thesis points/s",
        "updates",
        "update rate [Hz]",
        "aim [Hz]",
    ]);
    let mut results = Vec::new();
    let mut means = Vec::new();
    for (k, (dir, drive, end)) in drives.iter().enumerate() {
        let date = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let gt = drive.require_ground_truth()?;
        let bar = ctx.progress(0, "online maps");
        let (online_maps, totals) =
            local_maps(drive, &drive.odometry, 0..*end, &preset, |d, t| {
                bar.set_length(t as u64);
                bar.set_position(d as u64);
            })?;
        bar.finish_and_clear();
        let online = online_poles(&online_maps, &preset);
        let bar = ctx.progress(runs as u64, "runs");
        let mut run_results = Vec::new();
        for r in 0..runs {
            run_results.push(localize_run(
                drive,
                0..*end,
                &map,
                &online,
                &drive.odometry,
                &preset.filter,
                OdometryNoise::Recorded {
                    std_scale: 2.0,
                    fallback: 0.02,
                },
                7000 + 100 * k as u64 + r as u64,
            )?);
            bar.inc(1);
        }
        bar.finish_and_clear();
        let s = RunSummary::of(&run_results);
        means.push((s.mean_pos, s.rmse_pos, s.mean_ang_deg, s.rmse_ang_deg));
        let thesis = THESIS.iter().find(|t| t.0 == date);
        let cell = |v: Option<f64>| v.map_or("-".to_string(), |v| fmt_num(v, 3));
        table.row([
            date.clone(),
            fmt_num(100.0 * f_map.get(k).copied().unwrap_or(0.0), 1),
            fmt_num(s.mean_pos, 3),
            fmt_num(s.rmse_pos, 3),
            fmt_num(s.mean_ang_deg, 3),
            fmt_num(s.rmse_ang_deg, 3),
            format!("{} / {}", s.diverged, s.runs),
            cell(thesis.map(|t| t.2)),
            cell(thesis.map(|t| t.3)),
            cell(thesis.map(|t| t.4)),
            cell(thesis.map(|t| t.5)),
        ]);
        let truth = truth_near(&dir.join("poles.csv"), &gt[..*end], 12.0)?;
        let near_map = near(&map, &gt[..*end], 12.0);
        let quality = detection_quality(&near_map, &truth, 1.0);
        detection.row([
            date.clone(),
            end.to_string(),
            near_map.len().to_string(),
            truth.len().to_string(),
            fmt_num(quality.precision, 3),
            fmt_num(quality.recall, 3),
            fmt_num(quality.mean_centre_error_m, 3),
        ]);
        speed.row(speed_row(&date, &totals, &run_results, 50.0));
        results.push(json!({
            "session": date,
            "scans": end,
            "f_map": f_map.get(k),
            "summary": s.json(),
            "detection": quality,
            "online_extraction": totals,
        }));
    }
    let n = means.len().max(1) as f64;
    let avg = |f: fn(&(f64, f64, f64, f64)) -> f64| means.iter().map(f).sum::<f64>() / n;
    table.row([
        "mean over sessions".to_string(),
        "".into(),
        fmt_num(avg(|m| m.0), 3),
        fmt_num(avg(|m| m.1), 3),
        fmt_num(avg(|m| m.2), 3),
        fmt_num(avg(|m| m.3), 3),
        "".into(),
        "0.284".into(),
        "".into(),
        "0.801".into(),
        "".into(),
    ]);

    let mut md = String::new();
    writeln!(
        md,
        "Simulated NCLT-style sessions (`urban-nclt`: HDL-32E scans, noisy odometry, a street \
         world changing between sessions; {} session(s){}). Reference map from session 1, later \
         sessions adding local maps ≥ 10 m from earlier poses ({} map poles); every session \
         localized on it with 5000 particles, {runs} runs each, errors every 1 m (means over \
         runs). The thesis columns are Table 12.1's rows of the same dates (real NCLT, 27 \
         sessions; mean Δ_pos 0.284 m, 0.200 m without 2013-02-23).\n",
        drives.len(),
        if ctx.quick {
            ", **quick run: the first and last sessions, first 100 scans each**"
        } else {
            ""
        },
        map.len(),
    )?;
    writeln!(
        md,
        "## Localization beside Table 12.1\n\n{}",
        table.to_markdown()
    )?;
    writeln!(
        md,
        "## Detection quality\n\nMap poles within 12 m of a session's drive against the \
         simulated poles of that session there (match: closest unused pair within 1 m). \
         Bollards (0.8–1.2 m) are below the NCLT grid, which starts 0.5 m below the sensor \
         (1.5 m above the road here) — they cannot be found.\n\n{}",
        detection.to_markdown()
    )?;
    writeln!(
        md,
        "## Speed\n\nOnline extraction per session (local maps along the odometry) and \
         measurement updates with 5000 particles. Map extraction: {} rays in {:.1} s ({:.2} M \
         points/s). Thesis: ≈ 0.5 M points/s with a GPU; aims ≥ 5 M points/s, ≥ 50 Hz. \
         Measured on a shared 2-core machine while other jobs ran.\n\n{}",
        map_totals.rays,
        map_totals.trace_secs + map_totals.score_secs,
        map_totals.points_per_sec() / 1e6,
        speed.to_markdown()
    )?;
    writeln!(
        md,
        "## Notes\n\n* Parameters: `PoleParams::nclt()` (0.2 m voxels, 30 × 30 × 5 m, widths \
         0.2–1.4 m, hull f = round_ties_even(2.5) = 2, μ_o = 0.2 (thesis; the code's 0.05 is \
         not used), q_min = 0.6 remapped, h_min = 1 m); map clusters ≥ 3 detections; odometry \
         std × 2 (covariance × 4).\n\
         * The simulated sessions drive partly different routes: `f_map` is large where a \
         session explores streets the first one never saw, and those parts are localized on \
         landmarks mapped from the same session's ground truth.\n"
    )?;
    Ok(EvalReport {
        name: NAME,
        title: "Long-term pole localization on simulated NCLT-style sessions (Table 12.1)".into(),
        markdown: md,
        json: json!({
            "runs": runs,
            "map_poles": map.len(),
            "map_extraction": map_totals,
            "sessions": results,
        }),
    })
}

/// Table 12.1 rows: (date, f_map %, Δ_pos, RMSE_pos, Δ_ang, RMSE_ang).
const THESIS: [(&str, f64, f64, f64, f64, f64); 4] = [
    ("2012-01-08", 100.0, 0.130, 0.178, 0.663, 0.857),
    ("2012-05-26", 0.4, 0.158, 0.217, 0.690, 0.889),
    ("2012-08-20", 3.8, 0.189, 0.264, 0.711, 0.941),
    ("2013-02-23", 0.0, 2.470, 5.480, 1.083, 1.769),
];

fn add_totals(total: &mut ExtractionTotals, t: &ExtractionTotals) {
    total.local_maps += t.local_maps;
    total.rays += t.rays;
    total.trace_secs += t.trace_secs;
    total.score_secs += t.score_secs;
    total.read_secs += t.read_secs;
}

/// Local maps of a session that add to the map: all for the first session, else those whose
/// centre is ≥ 10 m from every earlier pose. Returns (maps, added, segments).
#[allow(clippy::type_complexity)]
fn local_maps_new_areas(
    drive: &Drive,
    gt: &[raypath_geometry::Pose3],
    end: usize,
    preset: &Preset,
    earlier: &[Point3<f64>],
    first: bool,
    mut progress: impl FnMut(usize, usize),
) -> Result<((Vec<LocalMap>, usize, usize), ExtractionTotals)> {
    let positions: Vec<Point3<f64>> = gt[..end]
        .iter()
        .map(|p| Point3::from(p.translation()))
        .collect();
    let segs = raypath_poles::segments(
        &positions,
        preset.segments.interval_m,
        preset.segments.length_m,
    );
    let is_new = |c: &Point3<f64>| {
        first
            || earlier
                .iter()
                .all(|e| (e.x - c.x).powi(2) + (e.y - c.y).powi(2) >= NEW_AREA_M * NEW_AREA_M)
    };
    // Runs of consecutive new segments are extracted together (their scan range).
    let new: Vec<bool> = segs
        .iter()
        .map(|s| positions.get(s.center).is_some_and(is_new))
        .collect();
    let added = new.iter().filter(|&&b| b).count();
    let mut maps = Vec::new();
    let mut totals = ExtractionTotals::default();
    let mut k = 0;
    while k < segs.len() {
        if !new[k] {
            k += 1;
            continue;
        }
        let start = k;
        while k < segs.len() && new[k] {
            k += 1;
        }
        let lo = segs[start].scans.first().copied().unwrap_or(0);
        let hi = segs[k - 1].scans.last().copied().unwrap_or(lo) + 1;
        let (mut part, t) = local_maps(drive, gt, lo..hi, preset, |_, _| {})?;
        // Keep only the local maps centred in new areas.
        part.retain(|m| positions.get(m.center).is_some_and(is_new));
        add_totals(&mut totals, &t);
        maps.extend(part);
        progress(k, segs.len());
    }
    Ok(((maps, added, segs.len()), totals))
}

/// Session directories (named by date) under the set's root, sorted.
fn session_dirs(root: &Path) -> Result<Vec<PathBuf>> {
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(root)
        .with_context(|| format!("listing {}", root.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.is_dir()
                && p.file_name().is_some_and(|n| {
                    n.to_string_lossy()
                        .chars()
                        .take(4)
                        .all(|c| c.is_ascii_digit())
                })
        })
        .collect();
    dirs.sort();
    if dirs.is_empty() {
        anyhow::bail!("no sessions under {}", root.display());
    }
    Ok(dirs)
}
