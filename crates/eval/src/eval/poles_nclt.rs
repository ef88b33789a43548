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
//!
//! In stages (`--shard i/n`, `merge`): one unit per semi-NCLT session (`semi-nclt/<date>`;
//! each process builds the campus and the reference map once, so a shard repeats the map
//! but not the other sessions' localization) and, in the full run, one unit for the
//! `urban-nclt` set ([`protocol`] measures, [`page`] reports).

mod figure;
mod page;
mod protocol;
mod thesis;

use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use nalgebra::Point2;
use raypath_geometry::Pose3;
use raypath_io::sequence::{SweepFormat, SweepSequence};
use raypath_poles::Drive;
use raypath_sim::semi_nclt::{SemiNclt, SemiNcltConfig};
use serde_json::{Value, json};

use self::protocol::PoleMap;
use super::poles_kitti::truth_near;
use super::stages::{Staged, UnitResults};
use super::{EvalContext, EvalReport};

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

/// The stages of `eval poles-nclt`.
pub const STAGED: Staged = Staged {
    name: NAME,
    units,
    run_unit,
    report,
};

/// Localization runs per session: 10 as the thesis, 2 in `--quick`.
fn runs(quick: bool) -> usize {
    if quick { 2 } else { 10 }
}

/// The semi-NCLT configuration of this run (quick: two sessions of 100 scans).
fn semi_config(quick: bool) -> Result<SemiNcltConfig> {
    let mut config = SemiNcltConfig::from_data_dir()?;
    if quick {
        config.sessions = ["2012-01-08", "2013-02-23"].map(String::from).to_vec();
        config.scans_per_session = QUICK_SCANS;
    } else {
        config.scans_per_session = FULL_SCANS;
    }
    Ok(config)
}

/// One unit per semi-NCLT session, then (full run) the `urban-nclt` set.
fn units(ctx: &EvalContext) -> Result<Vec<String>> {
    let mut units: Vec<String> = semi_config(ctx.quick)?
        .sessions
        .iter()
        .map(|date| format!("semi-nclt/{date}"))
        .collect();
    if !ctx.quick {
        units.push("urban-nclt".to_owned());
    }
    Ok(units)
}

/// Measures one semi-NCLT session or the `urban-nclt` set.
fn run_unit(ctx: &EvalContext, unit: &str) -> Result<Value> {
    let started = Instant::now();
    if unit == "urban-nclt" {
        return urban(ctx, started);
    }
    let Some(date) = unit.strip_prefix("semi-nclt/") else {
        bail!("{unit:?} is not a unit of {NAME}");
    };
    let set = semi_set(ctx)?;
    let k = set
        .campus
        .config()
        .sessions
        .iter()
        .position(|d| d == date)
        .with_context(|| format!("{date} is not a semi-NCLT session of this run"))?;
    let session = protocol::localize(ctx, k, runs(ctx.quick), 7000, &set.map, &|k| {
        semi_session(&set.campus, k)
    })?;
    let figure = if k == 0 && !ctx.quick {
        Some(campus_figure(ctx, &set)?)
    } else {
        None
    };
    Ok(json!({
        "set": "semi",
        "map": set.map.json(),
        "campus": set.campus_json,
        "session": session,
        "figure": figure,
        "seconds": started.elapsed().as_secs_f64(),
    }))
}

/// The report from the unit results.
fn report(ctx: &EvalContext, results: &UnitResults) -> Result<EvalReport> {
    page::report(ctx, results).context("drawing the poles-nclt page")
}

/// The semi-NCLT campus of a run and its reference map.
struct SemiSet {
    quick: bool,
    campus: SemiNclt,
    map: PoleMap,
    /// What the page says about the campus (see [`campus_json`]).
    campus_json: Value,
}

thread_local! {
    /// The campus and map built by this process (units run one after the other).
    static SEMI: RefCell<Option<Rc<SemiSet>>> = const { RefCell::new(None) };
}

/// The campus and reference map of this run, built once per process.
fn semi_set(ctx: &EvalContext) -> Result<Rc<SemiSet>> {
    if let Some(set) = SEMI.with(|s| s.borrow().clone())
        && set.quick == ctx.quick
    {
        return Ok(set);
    }
    let campus = SemiNclt::new(semi_config(ctx.quick)?, SEMI_SEED)?;
    let map = protocol::build_map(ctx, campus.len(), &|k| semi_session(&campus, k))?;
    let campus_json = campus_json(ctx, &campus)?;
    let set = Rc::new(SemiSet {
        quick: ctx.quick,
        campus,
        map,
        campus_json,
    });
    SEMI.with(|s| *s.borrow_mut() = Some(Rc::clone(&set)));
    Ok(set)
}

/// The campus figures the page states: real path and poles, the session plan, the changes
/// per session, and how far simulated scans are from real ones.
fn campus_json(ctx: &EvalContext, campus: &SemiNclt) -> Result<Value> {
    let c = campus.config();
    let length = campus.path().length_m();
    let changes: Vec<Value> = (0..campus.len())
        .filter_map(|k| {
            let (world, log) = campus.world(k)?;
            let (a, b) = c.window_m(k, length);
            Some(json!({
                "session": c.sessions.get(k).cloned().unwrap_or_default(),
                "window_m": [a, b],
                "poles_in_world": world.poles.len(),
                "removed": log.removed.len(),
                "moved": log.moved.len(),
                "added": log.added.len(),
                "parked_cars": log.parked_cars,
                "barrel_zones_shifted": log.barrel_shifts_m.iter().filter(|z| z.is_some()).count(),
                "barrel_zones": log.barrel_shifts_m.len(),
                "foliage": log.foliage,
            }))
        })
        .collect();
    Ok(json!({
        "poles_on_path": campus.poles_on_path.len(),
        "path_length_m": length,
        "sessions": c.sessions,
        "scans_per_session": c.scans_per_session,
        "scan_spacing_m": c.scan_spacing_m,
        "windows": (0..campus.len()).map(|k| c.window_m(k, length)).map(|(a, b)| [a, b])
            .collect::<Vec<_>>(),
        "parking_slots": campus.parking_slots,
        "construction_zones": campus.construction_zones,
        "changes": changes,
        "gap_note": super::sim::gap_note(ctx)?,
    }))
}

/// Writes the campus figure (path, poles, the sessions' drives, the map); its page path.
fn campus_figure(ctx: &EvalContext, set: &SemiSet) -> Result<&'static str> {
    let drives = (0..set.campus.len())
        .map(|k| {
            let s = set.campus.session(k)?;
            Ok((
                s.date.clone(),
                protocol::positions(&s.ground_truth, s.ground_truth.len()),
            ))
        })
        .collect::<Result<Vec<_>>>()?;
    let svg = figure::CampusFigure {
        path: &set.campus.config().path,
        poles: &set.campus.config().poles,
        sessions: drives,
        map: set
            .map
            .poles
            .iter()
            .map(|p| Point2::new(p.x, p.y))
            .collect(),
    }
    .svg();
    let path = ctx.figure_dir(NAME)?.join("campus.svg");
    std::fs::write(&path, svg).with_context(|| format!("writing {}", path.display()))?;
    Ok("poles-nclt/campus.svg")
}

/// The `urban-nclt` set (generated on disk): its map and every session's localization.
fn urban(ctx: &EvalContext, started: Instant) -> Result<Value> {
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
    let map = protocol::build_map(ctx, dirs.len(), &open)?;
    let sessions = (0..dirs.len())
        .map(|k| protocol::localize(ctx, k, runs(ctx.quick), 8000, &map, &open))
        .collect::<Result<Vec<_>>>()?;
    Ok(json!({
        "set": "urban",
        "map": map.json(),
        "sessions": sessions,
        "seconds": started.elapsed().as_secs_f64(),
    }))
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
