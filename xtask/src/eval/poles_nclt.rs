//! `cargo xtask eval poles-nclt`: long-term pole-based localization in NCLT-style sessions
//! (Schaefer 2020, §12.4, Table 12.1).
//!
//! * Main data, **semi-NCLT** (`raypath_sim::semi_nclt`): the **real** NCLT pole layout
//!   (`nclt-poles/ground-truth-poles.csv`, 1205 poles) and the **real** path of the NCLT pole
//!   map (`pole-map-segment-positions.csv`, ≈ 6.5 km); simulated around them: the campus
//!   scenery, eight sessions with dates of Table 12.1 from 2012-01-08 to 2013-04-05 driving
//!   overlapping windows of the path (each shifted by a quarter window), the changes between
//!   them (parked cars, removed/moved/added sign posts, cut trees, shifted barrels, foliage),
//!   HDL-32E scans 0.75 m apart, noisy odometry. Streamed: scans are simulated when the
//!   pipeline asks for them, nothing is written to disk.
//! * Second table (full run only), **urban-nclt**: `datasets/generated/urban-nclt`, four
//!   sessions through a procedural street grid (NCLT layout on disk).
//! * Map (Schaefer 2020 Sec. 12.3, the reference code's `ncltpoles.py`): local maps every 1.5 m over 1.5 m along the ground
//!   truth; session 1 contributes all of them, later sessions only the local maps centred
//!   ≥ 10 m from every pose of the earlier sessions (`f_map` = fraction of a session's local
//!   maps added); the map keeps the overlap clusters with ≥ 3 detections.
//! * Localization of every session on that map: 5000 particles, 2.5 m / ±5° initial spread,
//!   the odometry with its stated covariance × 4, online poles from local maps built along
//!   the **odometry** through the 2-of-3 filter, σ² = 1.5 m², ε = 0.1; 10 runs per session
//!   (2 in `--quick`), errors every 1 m.
//! * `--quick` (CI): semi-NCLT only, sessions 2012-01-08 and 2013-02-23 of 100 scans, 2 runs.

mod figure;
mod thesis;

use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use nalgebra::{Point2, Point3};
use raypath_geometry::Pose3;
use raypath_io::sequence::{SweepFormat, SweepSequence};
use raypath_poles::{
    Drive, ExtractionTotals, LocalMap, OdometryNoise, Pole, Preset, detection_quality, local_maps,
    localize_run, merge_poles, online_poles,
};
use raypath_sim::semi_nclt::{SemiNclt, SemiNcltConfig};
use serde_json::json;

use super::poles_kitti::{RunSummary, near, speed_row, truth_near};
use super::{EvalContext, EvalReport, comparable};
use crate::table::{Table, fmt_num};

const NAME: &str = "poles-nclt";
/// Later sessions add local maps centred at least this far from earlier poses, metres.
const NEW_AREA_M: f64 = 10.0;
/// Detection quality is measured within this distance of a session's drive, metres.
const NEAR_M: f64 = 12.0;
/// Seed of the semi-NCLT campus and sessions.
const SEMI_SEED: u64 = 2012;
/// Scans per semi-NCLT session in the full run (0.75 m apart: 749 m per session).
const FULL_SCANS: usize = 1000;
/// Scans per session in `--quick`.
const QUICK_SCANS: usize = 100;

/// One session ready for the protocol.
struct Session {
    label: String,
    drive: Drive,
    /// Scans used: `0..end`.
    end: usize,
    /// True poles of this session within [`NEAR_M`] of the drive.
    truth: Vec<Point2<f64>>,
}

/// Runs the evaluation.
pub fn run(ctx: &EvalContext) -> Result<EvalReport> {
    let started = Instant::now();
    let runs = if ctx.quick { 2 } else { 10 };
    let mut config = SemiNcltConfig::from_data_dir()?;
    if ctx.quick {
        config.sessions = ["2012-01-08", "2013-02-23"].map(String::from).to_vec();
        config.scans_per_session = QUICK_SCANS;
    } else {
        config.scans_per_session = FULL_SCANS;
    }
    let campus = SemiNclt::new(config, SEMI_SEED)?;
    let semi = evaluate(ctx, campus.len(), runs, 7000, SEMI_DATA, &|k| {
        semi_session(&campus, k)
    })?;
    let semi_secs = started.elapsed().as_secs_f64();
    let figure = if ctx.quick {
        None
    } else {
        let svg = figure::CampusFigure {
            path: &campus.config().path,
            poles: &campus.config().poles,
            sessions: semi.drives.clone(),
            map: semi.map.clone(),
        }
        .svg();
        let path = ctx.figure_dir(NAME)?.join("campus.svg");
        std::fs::write(&path, svg).with_context(|| format!("writing {}", path.display()))?;
        Some("poles-nclt/campus.svg")
    };
    let urban = if ctx.quick {
        None
    } else {
        let root = crate::generate::ensure("urban-nclt", false)?;
        let dirs = session_dirs(&root)?;
        let open = |k: usize| -> Result<Session> {
            let dir = dirs.get(k).context("no such session")?;
            let drive = Drive::open(dir).with_context(|| format!("opening {}", dir.display()))?;
            let end = drive.len();
            let gt = drive.require_ground_truth()?;
            let truth = truth_near(&dir.join("poles.csv"), &gt[..end], NEAR_M)?;
            let label = dir
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            Ok(Session {
                label,
                drive,
                end,
                truth,
            })
        };
        Some(evaluate(ctx, dirs.len(), runs, 8000, URBAN_DATA, &open)?)
    };
    let total_secs = started.elapsed().as_secs_f64();
    let mut md = report(
        ctx,
        &campus,
        runs,
        &semi,
        urban.as_ref(),
        semi_secs,
        total_secs,
    )?;
    if let Some(figure) = figure {
        writeln!(
            md,
            "## Campus\n\n![The real NCLT path (grey) and poles (dots), the windows the \
             sessions drive (colours) and the reference map (red rings)]({figure})\n"
        )?;
    }
    Ok(EvalReport {
        name: NAME,
        title: "Long-term pole localization in NCLT-style sessions: the real NCLT pole layout and \
                path with simulated scans (Table 12.1)"
            .into(),
        markdown: md,
        json: json!({
            "runs": runs,
            "semi_nclt": {
                "config": campus.config().sessions,
                "scans_per_session": campus.config().scans_per_session,
                "scan_spacing_m": campus.config().scan_spacing_m,
                "path_length_m": campus.path().length_m(),
                "poles_left_out_on_path": campus.poles_on_path.len(),
                "map_poles": semi.map_poles,
                "map_extraction": semi.map_totals,
                "sessions": semi.json,
                "elapsed_s": semi_secs,
            },
            "urban_nclt": urban.as_ref().map(|u| json!({
                "map_poles": u.map_poles,
                "map_extraction": u.map_totals,
                "sessions": u.json,
            })),
            "elapsed_s": total_secs,
        }),
        headline: None,
    })
}

/// Session `k` of the campus as an in-memory drive.
fn semi_session(campus: &SemiNclt, k: usize) -> Result<Session> {
    let s = campus.session(k)?;
    let scan = s.scan_fn();
    let mut sweeps = SweepSequence::from_fn(
        &format!("semi-nclt {}", s.date),
        SweepFormat::Nclt,
        s.stamps_secs.clone(),
        Some(s.ground_truth.to_vec()),
        Some(s.odometry.clone()),
        Box::new(move |i| scan(i).map_err(Into::into)),
    )?;
    sweeps.odometry_std = Some(s.odometry_std.clone());
    let drive = Drive::new(sweeps)?;
    let truth = s
        .poles
        .iter()
        .map(|p| Point2::new(p.x, p.y))
        .filter(|p| within(p, &s.ground_truth, NEAR_M))
        .collect();
    Ok(Session {
        label: s.date.clone(),
        end: drive.len(),
        drive,
        truth,
    })
}

fn within(p: &Point2<f64>, poses: &[Pose3], radius: f64) -> bool {
    poses.iter().any(|q| {
        let t = q.translation();
        (t.x - p.x).powi(2) + (t.y - p.y).powi(2) <= radius * radius
    })
}

/// Tables and results of one set of sessions.
struct Outcome {
    localization: Table,
    detection: Table,
    speed: Table,
    map_poles: usize,
    map_totals: ExtractionTotals,
    json: Vec<serde_json::Value>,
    /// The reference map's pole positions.
    map: Vec<Point2<f64>>,
    /// Per session: label and ground-truth positions.
    drives: Vec<(String, Vec<Point2<f64>>)>,
}

/// What our semi-NCLT rows are, for the "comparable" column.
const SEMI_DATA: &str = "semi-synthetic: simulated HDL-32E scans, scenery and changes along a \
     window of the real NCLT path among its real poles";
/// What our urban-nclt rows are, for the "comparable" column.
const URBAN_DATA: &str =
    "simulated: procedural street grid, routes and poles (only the date is NCLT's)";
/// The "comparable" cell of the speed rows: the thesis' 0.5 M points/s beside ours.
const SPEED_COMPARABLE: &str = "no — thesis: real NCLT HDL-32E scans, Python with a GPU on a \
     2011 quad-core PC; ours: simulated scans, Rust on 2 shared CPU cores (same 0.2 m voxels)";

/// The "comparable" cell of a session row beside the thesis' session of the same date;
/// `ours` says what our data are.
fn session_comparable(ours: &str, runs: usize) -> String {
    let runs = if runs == 10 {
        String::new()
    } else {
        format!("; {runs} runs per session (thesis 10)")
    };
    comparable::no(&format!(
        "{ours}; thesis: the real NCLT session of that date (real scans, several km, map \
         from real sessions){runs}"
    ))
}

/// The protocol on `n` sessions opened (twice each: mapping, then localization) by `open`;
/// `ours` says what the sessions' data are (for the "comparable" column).
fn evaluate(
    ctx: &EvalContext,
    n: usize,
    runs: usize,
    seed_base: u64,
    ours: &str,
    open: &dyn Fn(usize) -> Result<Session>,
) -> Result<Outcome> {
    let preset = Preset::nclt();
    // 1. The reference map.
    let mut contributing: Vec<LocalMap> = Vec::new();
    let mut earlier_positions: Vec<Point3<f64>> = Vec::new();
    let mut f_map = Vec::new();
    let mut map_totals = ExtractionTotals::default();
    for k in 0..n {
        let session = open(k)?;
        let gt = session.drive.require_ground_truth()?;
        let bar = ctx.progress(0, "map");
        let (maps, totals) = local_maps_new_areas(
            &session.drive,
            gt,
            session.end,
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
        earlier_positions.extend(
            gt[..session.end]
                .iter()
                .map(|p| Point3::from(p.translation())),
        );
    }
    let all: Vec<Pole> = contributing
        .iter()
        .flat_map(|m| m.poles.iter().copied())
        .collect();
    let map = merge_poles(&all, preset.segments.min_map_detections);
    eprintln!(
        "  map: {} poles from {} local maps (f_map {:?})",
        map.len(),
        contributing.len(),
        f_map
    );

    // 2. Localization of every session.
    let mut table = localization_table();
    let mut detection = Table::new([
        "session",
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
        comparable::HEADER,
    ]);
    let mut results = Vec::new();
    let mut means = Vec::new();
    let mut drives = Vec::new();
    for k in 0..n {
        let opened = Instant::now();
        let session = open(k)?;
        let (drive, end, date) = (&session.drive, session.end, &session.label);
        let gt = drive.require_ground_truth()?;
        let open_secs = opened.elapsed().as_secs_f64();
        let bar = ctx.progress(0, "online maps");
        let (online_maps, totals) =
            local_maps(drive, drive.odometry(), 0..end, &preset, |d, t| {
                bar.set_length(t as u64);
                bar.set_position(d as u64);
            })?;
        bar.finish_and_clear();
        let online = online_poles(&online_maps, &preset);
        let online_secs = opened.elapsed().as_secs_f64() - open_secs;
        let bar = ctx.progress(runs as u64, "runs");
        let mut run_results = Vec::new();
        for r in 0..runs {
            run_results.push(localize_run(
                drive,
                0..end,
                &map,
                &online,
                drive.odometry(),
                &preset.filter,
                OdometryNoise::Recorded {
                    std_scale: 2.0,
                    fallback: 0.02,
                },
                seed_base + 100 * k as u64 + r as u64,
            )?);
            bar.inc(1);
        }
        bar.finish_and_clear();
        let runs_secs = opened.elapsed().as_secs_f64() - open_secs - online_secs;
        let s = RunSummary::of(&run_results);
        drives.push((
            date.clone(),
            gt[..end]
                .iter()
                .map(|p| Point2::new(p.translation().x, p.translation().y))
                .collect(),
        ));
        means.push((
            date.clone(),
            [s.mean_pos, s.rmse_pos, s.mean_ang_deg, s.rmse_ang_deg],
        ));
        let thesis = thesis::row(date);
        let cell = |v: Option<f64>, d: usize| v.map_or("-".to_string(), |v| fmt_num(v, d));
        table.row([
            date.clone(),
            end.to_string(),
            fmt_num(100.0 * f_map.get(k).copied().unwrap_or(0.0), 1),
            fmt_num(s.mean_pos, 3),
            fmt_num(s.rmse_pos, 3),
            fmt_num(s.mean_ang_deg, 3),
            fmt_num(s.rmse_ang_deg, 3),
            format!("{} / {}", s.diverged, s.runs),
            cell(thesis.map(|t| t.1), 1),
            cell(thesis.map(|t| t.2), 3),
            cell(thesis.map(|t| t.3), 3),
            cell(thesis.map(|t| t.4), 3),
            cell(thesis.map(|t| t.5), 3),
            session_comparable(ours, runs),
        ]);
        let near_map = near(&map, &gt[..end], NEAR_M);
        let quality = detection_quality(&near_map, &session.truth, 1.0);
        detection.row([
            date.clone(),
            near_map.len().to_string(),
            session.truth.len().to_string(),
            fmt_num(quality.precision, 3),
            fmt_num(quality.recall, 3),
            fmt_num(quality.mean_centre_error_m, 3),
        ]);
        let mut row = speed_row(date, &totals, &run_results, 50.0);
        row.push(SPEED_COMPARABLE.to_owned());
        speed.row(row);
        eprintln!(
            "  {date}: {end} scans, Δ_pos {:.3} m, RMSE {:.3} m, {} / {} diverged ({:.0} s)",
            s.mean_pos,
            s.rmse_pos,
            s.diverged,
            s.runs,
            opened.elapsed().as_secs_f64()
        );
        results.push(json!({
            "session": date,
            "scans": end,
            "f_map": f_map.get(k),
            "summary": s.json(),
            "detection": quality,
            "online_extraction": totals,
            "seconds": {
                "open": open_secs,
                "online_maps_with_scans": online_secs,
                "localization_runs": runs_secs,
            },
        }));
    }
    mean_rows(&mut table, &means, ours);
    Ok(Outcome {
        localization: table,
        detection,
        speed,
        map_poles: map.len(),
        map_totals,
        json: results,
        map: map.iter().map(|p| Point2::new(p.x, p.y)).collect(),
        drives,
    })
}

/// The localization table beside Table 12.1 (header only).
fn localization_table() -> Table {
    Table::new([
        "session",
        "scans",
        "f_map [%]",
        "Δ_pos [m]",
        "RMSE_pos [m]",
        "Δ_ang [°]",
        "RMSE_ang [°]",
        "diverged runs",
        "thesis f_map [%]",
        "thesis Δ_pos [m]",
        "thesis RMSE_pos [m]",
        "thesis Δ_ang [°]",
        "thesis RMSE_ang [°]",
        comparable::HEADER,
    ])
}

/// "mean over sessions" and "mean without 2013-02-23" rows beside the thesis means (which
/// are over all 27 (26) thesis sessions, not over the dates above: the "comparable" cell
/// gives the thesis' Δ_pos over the same dates); `ours` says what our data are.
fn mean_rows(table: &mut Table, means: &[(String, [f64; 4])], ours: &str) {
    let mut row =
        |label: &str, rows: &[&(String, [f64; 4])], thesis: [&str; 2], sessions: usize| {
            let n = rows.len().max(1) as f64;
            let avg = |i: usize| fmt_num(rows.iter().map(|m| m.1[i]).sum::<f64>() / n, 3);
            let dates: Vec<&str> = rows.iter().map(|m| m.0.as_str()).collect();
            let cell = comparable::no(&format!(
                "{ours}; thesis: mean over its {sessions} real sessions{}",
                thesis_mean_text(&dates)
            ));
            table.row([
                label.to_string(),
                "".into(),
                "".into(),
                avg(0),
                avg(1),
                avg(2),
                avg(3),
                "".into(),
                "".into(),
                thesis[0].into(),
                "".into(),
                thesis[1].into(),
                "".into(),
                cell,
            ]);
        };
    row(
        "mean over sessions",
        &means.iter().collect::<Vec<_>>(),
        ["0.284", "0.801"],
        thesis::TABLE_12_1.len(),
    );
    if means.iter().any(|m| m.0 == "2013-02-23") && means.len() > 1 {
        row(
            "mean without 2013-02-23",
            &means
                .iter()
                .filter(|m| m.0 != "2013-02-23")
                .collect::<Vec<_>>(),
            ["0.200", ""],
            thesis::TABLE_12_1.len() - 1,
        );
    }
}

/// ", not the N dates above (over them: Δ_pos X m)" — the thesis' mean Δ_pos over the
/// dates of our rows that Table 12.1 has; empty when none has.
fn thesis_mean_text(dates: &[&str]) -> String {
    let found: Vec<f64> = dates
        .iter()
        .filter_map(|d| thesis::row(d))
        .map(|t| t.2)
        .collect();
    if found.is_empty() {
        return String::new();
    }
    format!(
        ", not the {} dates above (over them: Δ_pos {:.3} m)",
        found.len(),
        found.iter().sum::<f64>() / found.len() as f64
    )
}

/// The report text.
fn report(
    ctx: &EvalContext,
    campus: &SemiNclt,
    runs: usize,
    semi: &Outcome,
    urban: Option<&Outcome>,
    semi_secs: f64,
    total_secs: f64,
) -> Result<String> {
    let c = campus.config();
    let mut md = String::new();
    writeln!(
        md,
        "**What is real and what is simulated.** Real: the NCLT pole layout \
         (`nclt-poles/ground-truth-poles.csv`, 1205 poles from labelled NCLT scans; {} within \
         1 m of the path left out) and the path (`pole-map-segment-positions.csv`, one \
         continuous {:.2} km path in the NCLT frame). Simulated (`raypath_sim::semi_nclt`): the \
         campus scenery around the path (flat ground, sidewalks, facades, parked cars; pole \
         kinds and sizes drawn per pole), the sessions and their changes, the HDL-32E scans, \
         the odometry and the timing. Scans are simulated on demand and never written to \
         disk.\n",
        campus.poles_on_path.len(),
        campus.path().length_m() / 1000.0,
    )?;
    let windows: Vec<String> = (0..campus.len())
        .map(|k| {
            let (a, b) = c.window_m(k, campus.path().length_m());
            format!(
                "{} {:.0}–{:.0} m",
                c.sessions.get(k).map_or("", String::as_str),
                a,
                b
            )
        })
        .collect();
    writeln!(
        md,
        "**Session plan.** {} session(s){} with dates of Table 12.1, each {} scans {} m apart \
         ({:.0} m) along a window of the real path, every window shifted by a quarter window: \
         later sessions revisit three quarters of the previous one and add new parts ({}). The \
         stamps are 10 Hz, i.e. a vehicle at {:.1} m/s — NCLT's Segway drove ≈ 1–1.5 m/s, so \
         this is a Segway drive thinned to every 5th–7th scan to keep the run time sane. \
         Changes accumulate over the sessions ({} parking places redrawn per session at \
         30–75 % occupancy, 3 % of sign posts removed / moved / added and 1 % of trees cut per \
         session, {} construction zones whose barrels shift 1–3.5 m or vanish, crowns at 0.6 in \
         winter); odometry noise 1.5 % longitudinal, 0.5 % lateral, 2 % of the turn + \
         0.0002 rad/m (per increment, 10 sub-steps per scan; the filter uses the stated std × 2).\n",
        campus.len(),
        if ctx.quick {
            " (**quick run**: two sessions of 100 scans)"
        } else {
            ""
        },
        c.scans_per_session,
        c.scan_spacing_m,
        c.scans_per_session.saturating_sub(1) as f64 * c.scan_spacing_m,
        windows.join(", "),
        c.scan_spacing_m / raypath_sim::semi_nclt::SCAN_PERIOD_S,
        campus.parking_slots,
        campus.construction_zones,
    )?;
    writeln!(
        md,
        "**Protocol.** Reference map from session 1, later sessions adding the local maps \
         centred ≥ 10 m from earlier poses ({} map poles); every session localized on it with \
         5000 particles, {runs} runs each, errors every 1 m (means over runs). The thesis \
         columns are Table 12.1's rows of the same dates (real NCLT, 27 sessions of several km \
         each; mean Δ_pos 0.284 m, 0.200 m without 2013-02-23).\n",
        semi.map_poles,
    )?;
    writeln!(
        md,
        "## Semi-NCLT: sessions\n\nChanges with respect to the previous session (poles \
         removed / moved / added, cumulative: a removed pole stays removed), parked cars, \
         construction zones with barrels, leaf factor of the crowns. The quarter-window shift of \
         the session plan makes the reference map cover the first session's window and the \
         new quarters of the later ones.\n\n{}\n{}",
        super::sim::gap_note(ctx)?,
        sessions_table(campus).to_markdown()?
    )?;
    writeln!(
        md,
        "## Semi-NCLT: localization beside Table 12.1\n\n{}",
        semi.localization.to_markdown()?
    )?;
    writeln!(
        md,
        "## Semi-NCLT: detection quality\n\nMap poles within 12 m of a session's drive \
         against the true poles of that session there (after its changes; match: closest \
         unused pair within 1 m).\n\n{}",
        semi.detection.to_markdown()?
    )?;
    writeln!(
        md,
        "## Semi-NCLT: speed\n\nOnline extraction per session (local maps along the odometry) \
         and measurement updates with 5000 particles. Map extraction: {} rays in {:.1} s ({:.2} \
         M points/s). Thesis: ≈ 0.5 M points/s with a GPU; aims ≥ 5 M points/s, ≥ 50 Hz. \
         Absolute times were measured on a shared 2-core machine under load (another helper's \
         builds and runs); the semi-NCLT part took {:.0} s including the scan simulation.\n\n{}",
        semi.map_totals.rays,
        semi.map_totals.trace_secs + semi.map_totals.score_secs,
        semi.map_totals.points_per_sec() / 1e6,
        semi_secs,
        semi.speed.to_markdown()?
    )?;
    match urban {
        Some(u) => {
            writeln!(
                md,
                "## Procedural sessions (`urban-nclt`)\n\nFour sessions through a procedural \
                 street grid (simulated layout and routes, NCLT layout on disk), same \
                 protocol ({} map poles; map extraction {:.2} M points/s).\n\n{}\n\n{}",
                u.map_poles,
                u.map_totals.points_per_sec() / 1e6,
                u.localization.to_markdown()?,
                u.detection.to_markdown()?
            )?;
        }
        None => writeln!(
            md,
            "The procedural `urban-nclt` sessions (second table of the full run) are left out \
             of the quick run: they are generated on disk.\n"
        )?,
    }
    writeln!(
        md,
        "## Notes\n\n* Parameters: `PoleParams::nclt()` (0.2 m voxels, 30 × 30 × 5 m, widths \
         0.2–1.4 m, hull f = round_ties_even(2.5) = 2, μ_o = 0.2 (thesis; the code's 0.05 is \
         not used), q_min = 0.6 remapped, h_min = 1 m); map clusters ≥ 3 detections; odometry \
         std × 2 (covariance × 4).\n\
         * Unlike real NCLT, the simulated scenery is the same street model everywhere (no \
         lawns, open squares or parking lots), the ground is flat and the sensor moves without \
         motion distortion; poles are ideal cylinders. The thesis' sessions are longer (several \
         km each) and their f_map is below 10 % after the first.\n\
         * Total run time {:.0} s.\n",
        total_secs,
    )?;
    Ok(md)
}

/// The sessions of the campus and their changes.
fn sessions_table(campus: &SemiNclt) -> Table {
    let mut table = Table::new([
        "session",
        "window [m]",
        "poles in world",
        "removed",
        "moved",
        "added",
        "parked cars",
        "zones with barrels",
        "foliage",
    ]);
    let c = campus.config();
    for k in 0..campus.len() {
        let Some((world, log)) = campus.world(k) else {
            continue;
        };
        let (a, b) = c.window_m(k, campus.path().length_m());
        table.row([
            c.sessions.get(k).cloned().unwrap_or_default(),
            format!("{a:.0}–{b:.0}"),
            world.poles.len().to_string(),
            log.removed.len().to_string(),
            log.moved.len().to_string(),
            log.added.len().to_string(),
            log.parked_cars.to_string(),
            format!(
                "{} / {}",
                log.barrel_shifts_m.iter().filter(|z| z.is_some()).count(),
                log.barrel_shifts_m.len()
            ),
            fmt_num(log.foliage, 2),
        ]);
    }
    table
}

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
    gt: &[Pose3],
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean rows fit the localization table and name the thesis' mean over the same
    /// dates (Table 12.1's 0.284 m is over all 27 sessions).
    #[test]
    fn mean_rows_name_the_thesis_mean_over_the_same_dates() {
        let mut table = localization_table();
        let means = vec![
            ("2012-01-08".to_owned(), [0.03, 0.04, 0.1, 0.14]),
            ("2013-02-23".to_owned(), [0.05, 0.06, 0.1, 0.17]),
        ];
        mean_rows(&mut table, &means, SEMI_DATA);
        let md = table.to_markdown().expect("rows fit the header");
        let line = |start: &str| md.lines().find(|l| l.starts_with(start)).unwrap();
        let all = line("| mean over sessions");
        assert!(all.contains("| 0.284 "), "{all}");
        assert!(all.contains("mean over its 27 real sessions"), "{all}");
        // (0.130 + 2.470) / 2 = 1.300.
        assert!(
            all.contains("not the 2 dates above (over them: Δ_pos 1.300 m)"),
            "{all}"
        );
        let without = line("| mean without 2013-02-23");
        assert!(without.contains("its 26 real sessions"), "{without}");
        assert!(without.contains("(over them: Δ_pos 0.130 m)"), "{without}");
        assert!(
            session_comparable(URBAN_DATA, 2).contains("2 runs per session (thesis 10)"),
            "{}",
            session_comparable(URBAN_DATA, 2)
        );
    }
}
