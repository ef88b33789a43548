//! The measure stage of the protocol (Schaefer 2020, §12.4): the reference map from every
//! session of a set, then the localization of one session on it; results are JSON, so
//! shards can be written and merged (the page is drawn by [`super::page`]).

use std::time::Instant;

use anyhow::Result;
use nalgebra::{Point2, Point3};
use raypath_geometry::Pose3;
use raypath_poles::{
    Drive, ExtractionTotals, LocalMap, OdometryNoise, Pole, Preset, detection_quality, local_maps,
    localize_run, merge_poles, online_poles,
};
use serde_json::{Value, json};

use super::super::poles_kitti::{RunSummary, near, update_totals};
use super::{NEAR_M, NEW_AREA_M, Session};
use crate::eval::EvalContext;

/// The reference map of a set of sessions.
pub(super) struct PoleMap {
    /// The merged map poles.
    pub poles: Vec<Pole>,
    /// Per session: the fraction of its local maps added to the map.
    pub f_map: Vec<f64>,
    /// Extraction totals of the map's local maps.
    pub totals: ExtractionTotals,
}

impl PoleMap {
    /// The map's figures for the report.
    pub fn json(&self) -> Value {
        json!({
            "map_poles": self.poles.len(),
            "map_extraction": self.totals,
            "f_map": self.f_map,
        })
    }
}

/// The reference map from the `n` sessions opened by `open`: session 1 contributes every
/// local map, later sessions those centred ≥ [`NEW_AREA_M`] from every earlier pose; the
/// map keeps the clusters with enough detections.
pub(super) fn build_map(
    ctx: &EvalContext,
    n: usize,
    open: &dyn Fn(usize) -> Result<Session>,
) -> Result<PoleMap> {
    let preset = Preset::nclt();
    let mut contributing: Vec<LocalMap> = Vec::new();
    let mut earlier_positions: Vec<Point3<f64>> = Vec::new();
    let mut f_map = Vec::new();
    let mut totals = ExtractionTotals::default();
    for k in 0..n {
        let session = open(k)?;
        let gt = session.drive.require_ground_truth()?;
        let bar = ctx.progress(0, "map");
        let (maps, session_totals) = local_maps_new_areas(
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
        add_totals(&mut totals, &session_totals);
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
    let poles = merge_poles(&all, preset.segments.min_map_detections);
    eprintln!(
        "  map: {} poles from {} local maps (f_map {:?})",
        poles.len(),
        contributing.len(),
        f_map
    );
    Ok(PoleMap {
        poles,
        f_map,
        totals,
    })
}

/// Localizes session `k` (opened by `open`) on `map`: `runs` runs seeded from `seed_base`;
/// the session's figures as JSON.
pub(super) fn localize(
    ctx: &EvalContext,
    k: usize,
    runs: usize,
    seed_base: u64,
    map: &PoleMap,
    open: &dyn Fn(usize) -> Result<Session>,
) -> Result<Value> {
    let preset = Preset::nclt();
    let opened = Instant::now();
    let session = open(k)?;
    let (drive, end, date) = (&session.drive, session.end, &session.label);
    let gt = drive.require_ground_truth()?;
    let open_secs = opened.elapsed().as_secs_f64();
    let bar = ctx.progress(0, "online maps");
    let (online_maps, totals) = local_maps(drive, drive.odometry(), 0..end, &preset, |d, t| {
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
            &map.poles,
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
    let near_map = near(&map.poles, &gt[..end], NEAR_M);
    let quality = detection_quality(&near_map, &session.truth, 1.0);
    let (updates, update_secs) = update_totals(&run_results);
    eprintln!(
        "  {date}: {end} scans, Δ_pos {:.3} m, RMSE {:.3} m, {} / {} diverged ({:.0} s)",
        s.mean_pos,
        s.rmse_pos,
        s.diverged,
        s.runs,
        opened.elapsed().as_secs_f64()
    );
    Ok(json!({
        "session": date,
        "scans": end,
        "f_map": map.f_map.get(k),
        "summary": s.json(),
        "detection": quality,
        "map_poles_near": near_map.len(),
        "true_poles_near": session.truth.len(),
        "online_extraction": totals,
        "updates": updates,
        "update_secs": update_secs,
        "seconds": {
            "open": open_secs,
            "online_maps_with_scans": online_secs,
            "localization_runs": runs_secs,
        },
    }))
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

/// The ground-truth positions of a session's scans `0..end` on the ground plane.
pub(super) fn positions(gt: &[Pose3], end: usize) -> Vec<Point2<f64>> {
    gt[..end]
        .iter()
        .map(|p| Point2::new(p.translation().x, p.translation().y))
        .collect()
}
