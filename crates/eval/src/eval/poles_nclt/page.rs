//! The report stage: the page and the JSON from the unit results alone (one result per
//! semi-NCLT session, carrying its set's map and campus figures, and the `urban-nclt` set).

use std::fmt::Write;

use anyhow::{Context, Result};
use raypath_poles::ExtractionTotals;
use serde_json::{Value, json};

use super::super::poles_kitti::{RunSummary, speed_cells};
use super::{NAME, thesis};
use crate::eval::stages::{UnitResults, field, number};
use crate::eval::{EvalContext, EvalReport, comparable};
use crate::table::{Table, fmt_num};

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

/// The tables of one set of sessions.
struct Outcome {
    localization: Table,
    detection: Table,
    speed: Table,
    map_poles: usize,
    map_totals: ExtractionTotals,
    json: Vec<Value>,
}

/// The tables of a set from its map's figures and its sessions' results; `ours` says what
/// the sessions' data are (for the "comparable" column).
fn outcome(map: &Value, sessions: &[&Value], runs: usize, ours: &str) -> Result<Outcome> {
    let mut localization = localization_table();
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
    let mut means = Vec::new();
    let mut json = Vec::new();
    for session in sessions {
        let date: String = field(session, "session")?;
        let s: RunSummary = field(session, "summary")?;
        let f_map: Option<f64> = field(session, "f_map")?;
        means.push((
            date.clone(),
            [s.mean_pos, s.rmse_pos, s.mean_ang_deg, s.rmse_ang_deg],
        ));
        let thesis = thesis::row(&date);
        let cell = |v: Option<f64>, d: usize| v.map_or("-".to_string(), |v| fmt_num(v, d));
        localization.row([
            date.clone(),
            field::<usize>(session, "scans")?.to_string(),
            fmt_num(100.0 * f_map.unwrap_or(0.0), 1),
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
        let quality = &session["detection"];
        detection.row([
            date.clone(),
            field::<usize>(session, "map_poles_near")?.to_string(),
            field::<usize>(session, "true_poles_near")?.to_string(),
            fmt_num(number(quality, "precision"), 3),
            fmt_num(number(quality, "recall"), 3),
            fmt_num(number(quality, "mean_centre_error_m"), 3),
        ]);
        let totals: ExtractionTotals = field(session, "online_extraction")?;
        let mut row = speed_cells(
            &date,
            &totals,
            field(session, "updates")?,
            field(session, "update_secs")?,
            50.0,
        );
        row.push(SPEED_COMPARABLE.to_owned());
        speed.row(row);
        let mut entry = (*session).clone();
        if let Some(object) = entry.as_object_mut() {
            for key in [
                "map_poles_near",
                "true_poles_near",
                "updates",
                "update_secs",
            ] {
                object.remove(key);
            }
        }
        json.push(entry);
    }
    mean_rows(&mut localization, &means, ours);
    Ok(Outcome {
        localization,
        detection,
        speed,
        map_poles: field(map, "map_poles")?,
        map_totals: field(map, "map_extraction")?,
        json,
    })
}

/// The page from the unit results: the semi-NCLT sessions (`semi-nclt/<date>`) and, in the
/// full run, the `urban-nclt` set.
pub(super) fn report(ctx: &EvalContext, results: &UnitResults) -> Result<EvalReport> {
    let runs = super::runs(ctx.quick);
    let semi: Vec<&Value> = results
        .iter()
        .filter(|(_, r)| r["set"] == "semi")
        .map(|(_, r)| r)
        .collect();
    let first = semi
        .first()
        .context("no semi-NCLT session in the results")?;
    let campus = &first["campus"];
    let sessions: Vec<&Value> = semi.iter().map(|r| &r["session"]).collect();
    let semi_outcome = outcome(&first["map"], &sessions, runs, SEMI_DATA)?;
    let semi_secs: f64 = semi
        .iter()
        .map(|r| r["seconds"].as_f64().unwrap_or(0.0))
        .sum();
    let urban = results
        .iter()
        .find(|(_, r)| r["set"] == "urban")
        .map(|(_, u)| -> Result<Outcome> {
            let sessions: Vec<&Value> = u["sessions"]
                .as_array()
                .context("urban-nclt sessions")?
                .iter()
                .collect();
            outcome(&u["map"], &sessions, runs, URBAN_DATA)
        })
        .transpose()?;
    let total_secs: f64 = results
        .iter()
        .map(|(_, r)| r["seconds"].as_f64().unwrap_or(0.0))
        .sum();
    let mut md = markdown(
        ctx,
        campus,
        runs,
        &semi_outcome,
        urban.as_ref(),
        semi_secs,
        total_secs,
    )?;
    if let Some(figure) = first["figure"].as_str() {
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
                "config": campus["sessions"],
                "scans_per_session": campus["scans_per_session"],
                "scan_spacing_m": campus["scan_spacing_m"],
                "path_length_m": campus["path_length_m"],
                "poles_left_out_on_path": campus["poles_on_path"],
                "map_poles": semi_outcome.map_poles,
                "map_extraction": semi_outcome.map_totals,
                "sessions": semi_outcome.json,
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

/// The page text; `campus` is the campus block of a semi-NCLT unit result.
fn markdown(
    ctx: &EvalContext,
    campus: &Value,
    runs: usize,
    semi: &Outcome,
    urban: Option<&Outcome>,
    semi_secs: f64,
    total_secs: f64,
) -> Result<String> {
    let dates: Vec<String> = field(campus, "sessions")?;
    let bounds: Vec<[f64; 2]> = field(campus, "windows")?;
    let scans_per_session: usize = field(campus, "scans_per_session")?;
    let scan_spacing_m: f64 = field(campus, "scan_spacing_m")?;
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
        field::<usize>(campus, "poles_on_path")?,
        field::<f64>(campus, "path_length_m")? / 1000.0,
    )?;
    let windows: Vec<String> = bounds
        .iter()
        .enumerate()
        .map(|(k, [a, b])| {
            format!(
                "{} {:.0}–{:.0} m",
                dates.get(k).map_or("", String::as_str),
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
        bounds.len(),
        if ctx.quick {
            " (**quick run**: two sessions of 100 scans)"
        } else {
            ""
        },
        scans_per_session,
        scan_spacing_m,
        scans_per_session.saturating_sub(1) as f64 * scan_spacing_m,
        windows.join(", "),
        scan_spacing_m / raypath_sim::semi_nclt::SCAN_PERIOD_S,
        field::<usize>(campus, "parking_slots")?,
        field::<usize>(campus, "construction_zones")?,
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
        field::<String>(campus, "gap_note")?,
        sessions_table(campus)?.to_markdown()?
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

/// The sessions of the campus and their changes (the campus block's `changes`).
fn sessions_table(campus: &Value) -> Result<Table> {
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
    for change in campus["changes"].as_array().context("campus changes")? {
        let [a, b]: [f64; 2] = field(change, "window_m")?;
        let count = |key: &str| field::<usize>(change, key).map(|n| n.to_string());
        table.row([
            field::<String>(change, "session")?,
            format!("{a:.0}–{b:.0}"),
            count("poles_in_world")?,
            count("removed")?,
            count("moved")?,
            count("added")?,
            count("parked_cars")?,
            format!(
                "{} / {}",
                count("barrel_zones_shifted")?,
                count("barrel_zones")?
            ),
            fmt_num(field(change, "foliage")?, 2),
        ]);
    }
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::*;
    use raypath_poles::{DetectionQuality, ExtractionTotals};

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

    /// One semi-NCLT unit result as `run_unit` writes it.
    fn semi_unit(date: &str, f_map: f64) -> Value {
        let summary = RunSummary {
            mean_pos: 0.05,
            rmse_pos: 0.06,
            mean_lat: 0.02,
            std_lat: 0.02,
            mean_lon: 0.03,
            std_lon: 0.03,
            mean_ang_deg: 0.2,
            std_ang_deg: 0.1,
            rmse_ang_deg: 0.25,
            diverged: 0,
            runs: 10,
        };
        json!({
            "set": "semi",
            "map": { "map_poles": 420, "map_extraction": ExtractionTotals { local_maps: 900,
                     rays: 9_000_000, trace_secs: 3.0, score_secs: 1.5, read_secs: 20.0 },
                     "f_map": [1.0, f_map] },
            "campus": { "poles_on_path": 12, "path_length_m": 6512.0,
                        "sessions": ["2012-01-08", "2013-02-23"], "scans_per_session": 1000,
                        "scan_spacing_m": 0.75, "windows": [[0.0, 749.0], [187.0, 936.0]],
                        "parking_slots": 300, "construction_zones": 4,
                        "changes": [{ "session": "2012-01-08", "window_m": [0.0, 749.0],
                                      "poles_in_world": 1190, "removed": 0, "moved": 0,
                                      "added": 0, "parked_cars": 150,
                                      "barrel_zones_shifted": 0, "barrel_zones": 4,
                                      "foliage": 1.0 }],
                        "gap_note": "Gap." },
            "session": { "session": date, "scans": 1000, "f_map": f_map,
                         "summary": summary.json(),
                         "detection": DetectionQuality { detected: 80, truth: 90, matched: 75,
                                                         precision: 0.9375, recall: 0.8333,
                                                         mean_centre_error_m: 0.07 },
                         "map_poles_near": 80, "true_poles_near": 90,
                         "online_extraction": ExtractionTotals { local_maps: 500,
                             rays: 5_000_000, trace_secs: 2.0, score_secs: 0.5,
                             read_secs: 10.0 },
                         "updates": 2000, "update_secs": 10.0,
                         "seconds": { "open": 0.1, "online_maps_with_scans": 12.0,
                                      "localization_runs": 30.0 } },
            "figure": null,
            "seconds": 100.0,
        })
    }

    /// The page from two semi-NCLT sessions: the tables get one row per session and the
    /// means, the campus block fills the session plan, the JSON keeps the keys of the
    /// single-process page, and the unit times add up.
    #[test]
    fn report_from_known_units() {
        let dir = std::env::temp_dir().join("raypath-poles-nclt-report-test");
        let ctx = EvalContext::scratch(&dir);
        let results = vec![
            (
                "semi-nclt/2012-01-08".to_owned(),
                semi_unit("2012-01-08", 1.0),
            ),
            (
                "semi-nclt/2013-02-23".to_owned(),
                semi_unit("2013-02-23", 0.25),
            ),
        ];
        let page = report(&ctx, &results).unwrap();
        let md = &page.markdown;
        assert!(
            md.contains("2012-01-08 0–749 m, 2013-02-23 187–936 m"),
            "{md}"
        );
        assert!(md.contains("| 1000  | 25.0 "), "{md}");
        assert!(md.contains("| mean without 2013-02-23 "), "{md}");
        assert!(md.contains("| 2012-01-08 | 0–749 "), "{md}");
        assert!(md.contains("2.00 M"), "{md}");
        assert!(md.contains("Total run time 200 s"), "{md}");
        assert!(md.contains("left out of the quick run"), "{md}");
        let semi = &page.json["semi_nclt"];
        assert_eq!(semi["map_poles"], 420);
        assert_eq!(semi["poles_left_out_on_path"], 12);
        assert_eq!(semi["sessions"][1]["f_map"], 0.25);
        assert!(semi["sessions"][1].get("updates").is_none());
        assert_eq!(page.json["runs"], 2);
        assert!(page.json["urban_nclt"].is_null());
        assert!(report(&ctx, &[]).is_err());
    }
}
