//! The measure stage of one semi-synthetic KITTI sequence: simulate the drive, build its
//! local maps, run the same-drive and later-pass protocols; the result is JSON only, so
//! shards can be written and merged (the page is drawn by [`super::page`]).

use std::ops::Range;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use nalgebra::Point2;
use raypath_geometry::Pose3;
use raypath_io::sequence::{SweepError, SweepFormat, SweepSequence};
use raypath_poles::{
    Drive, ExtractionTotals, LocalMap, OdometryNoise, Pole, Preset, RunResult, detection_quality,
    local_maps, localize_run, online_poles, reference_map,
};
use raypath_sim::datasets::DEFAULT_SEED;
use raypath_sim::semi_kitti::SemiKittiDrive;
use serde_json::{Value, json};

use super::revisits::{self, Revisit, find_revisits};
use super::{FULL_RUNS_MAX_SCANS, LONG_RUNS, MIN_REVISIT_M, RunSummary, SequencePlan};
use super::{near, points_near};
use crate::eval::EvalContext;

/// Measures one sequence: `{"skipped": note}` when its data is absent, otherwise the
/// sequence's figures (the `sequences` entries of the JSON report).
pub(super) fn measure(ctx: &EvalContext, plan: &SequencePlan, preset: &Preset) -> Result<Value> {
    let Some(mut config) = ctx.semi_kitti_config(plan.sequence, plan.max_scans)? else {
        let note = format!(
            "Sequence {} skipped: {} not found.",
            plan.sequence,
            ctx.data(&format!("kitti-poles/{}", plan.sequence))
                .display()
        );
        return Ok(json!({ "sequence": plan.sequence, "skipped": note }));
    };
    let started = Instant::now();
    let label = format!("semi-kitti {}", plan.sequence);
    config.stride = plan.stride;
    let sim = Arc::new(
        SemiKittiDrive::new(&config, DEFAULT_SEED)
            .with_context(|| format!("building the world of {label}"))?,
    );
    let gt = sim.world_from_velo.clone();
    let drive = simulated_drive(&label, &sim)?;
    let positions: Vec<Point2<f64>> = gt
        .iter()
        .map(|p| {
            let t = p.translation();
            Point2::new(t.x, t.y)
        })
        .collect();
    let mut stretches = if plan.later_pass {
        find_revisits(&positions, MIN_REVISIT_M)
    } else {
        Vec::new()
    };
    let ranges: Vec<Range<usize>> = match plan.window_scans {
        Some(window) => {
            stretches.truncate(1);
            stretches
                .iter_mut()
                .flat_map(|r| window_around(r, &positions, window))
                .collect()
        }
        None => std::iter::once(0..drive.len()).collect(),
    };
    let (maps, online, totals) = extract(ctx, plan, &drive, &gt, ranges, preset)?;
    let map = reference_map(&maps, preset);
    let scans = drive.len();
    let runs = if ctx.quick {
        3
    } else if scans <= FULL_RUNS_MAX_SCANS {
        50
    } else {
        LONG_RUNS
    };
    let mut entry = json!({
        "sequence": plan.sequence,
        "stride": plan.stride,
        "scans": scans,
        "length_m": sim.trajectory_length_m,
        "local_maps": maps.len(),
        "map_poles": map.len(),
        "extraction": totals,
        "points_per_sec": totals.points_per_sec(),
        "simulate_secs": totals.read_secs,
    });
    let mut run_results = Vec::new();
    let filter = Localize {
        drive: &drive,
        online: &online,
        gt: &gt,
        preset,
    };
    if plan.same_drive {
        let truth_poles: Vec<Point2<f64>> =
            sim.poles.iter().map(|p| Point2::new(p.x, p.y)).collect();
        let truth = points_near(&truth_poles, &gt, 12.0);
        let quality = detection_quality(&near(&map, &gt, 12.0), &truth, 1.0);
        let bar = ctx.progress(runs as u64, &format!("{} runs", plan.sequence));
        for r in 0..runs {
            run_results.push(filter.run(0..scans, &map, 1000 + r as u64)?);
            bar.inc(1);
        }
        bar.finish_and_clear();
        entry["detection"] = json!(quality);
        entry["true_poles_12m"] = json!(truth.len());
        entry["runs"] = json!(runs);
        entry["summary"] = RunSummary::of(&run_results).json();
    }
    if plan.later_pass {
        let later_runs = if ctx.quick { 2 } else { runs };
        let mut later_json = Vec::new();
        for stretch in &stretches {
            let bar = ctx.progress(
                2 * later_runs as u64,
                &format!("{} later {}", plan.sequence, stretch.start),
            );
            later_json.push(later_pass(
                &filter,
                &maps,
                &map,
                stretch,
                later_runs,
                || bar.inc(1),
            )?);
            bar.finish_and_clear();
        }
        entry["later_pass"] = json!(later_json);
    }
    let (updates, update_secs) = super::update_totals(&run_results);
    entry["updates"] = json!(updates);
    entry["update_secs"] = json!(update_secs);
    let total_secs = started.elapsed().as_secs_f64();
    entry["total_secs"] = json!(total_secs);
    // One line per sequence on stderr: progress of long runs in a log.
    eprintln!(
        "poles-kitti: sequence {} done in {total_secs:.0} s: {entry}",
        plan.sequence
    );
    Ok(entry)
}

/// The drive's scans, simulated on demand, as a sweep sequence with ground-truth odometry.
fn simulated_drive(label: &str, sim: &Arc<SemiKittiDrive>) -> Result<Drive> {
    let gt = sim.world_from_velo.clone();
    let source = Arc::clone(sim);
    Ok(Drive::new(SweepSequence::from_fn(
        label,
        SweepFormat::Kitti,
        sim.times_s.clone(),
        Some(gt.clone()),
        Some(gt),
        Box::new(move |i| source.scan(i).map_err(|e| Box::new(e) as SweepError)),
    )?)?)
}

/// The local maps of the scan ranges, their online poles and the extraction totals.
type Extracted = (Vec<LocalMap>, Vec<(usize, Vec<Pole>)>, ExtractionTotals);

/// Builds the ground-truth local maps of `ranges` (with a progress bar each).
fn extract(
    ctx: &EvalContext,
    plan: &SequencePlan,
    drive: &Drive,
    gt: &[Pose3],
    ranges: Vec<Range<usize>>,
    preset: &Preset,
) -> Result<Extracted> {
    let (mut maps, mut online, mut totals) = (Vec::new(), Vec::new(), ExtractionTotals::default());
    for range in ranges {
        let bar = ctx.progress(0, &format!("{} maps", plan.sequence));
        let (part, part_totals) = local_maps(drive, gt, range, preset, |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        })?;
        bar.finish_and_clear();
        online.extend(online_poles(&part, preset));
        maps.extend(part);
        totals.local_maps += part_totals.local_maps;
        totals.rays += part_totals.rays;
        totals.trace_secs += part_totals.trace_secs;
        totals.score_secs += part_totals.score_secs;
        totals.read_secs += part_totals.read_secs;
    }
    Ok((maps, online, totals))
}

/// The localization set-up shared by every run of one sequence.
struct Localize<'a> {
    drive: &'a Drive,
    online: &'a [(usize, Vec<Pole>)],
    gt: &'a [Pose3],
    preset: &'a Preset,
}

impl Localize<'_> {
    /// One run over `range` on `map` with 2 % odometry noise, seeded by `seed`.
    fn run(&self, range: Range<usize>, map: &[Pole], seed: u64) -> Result<RunResult> {
        Ok(localize_run(
            self.drive,
            range,
            map,
            self.online,
            self.gt,
            &self.preset.filter,
            OdometryNoise::Relative { fraction: 0.02 },
            seed,
        )?)
    }
}

/// Quick mode: cuts `stretch` to its first `window` scans and returns the scan ranges to
/// extract: the earlier pass (the contiguous scans ≥ 100 m of arc before the stretch within
/// 30 m of the cut stretch that pass closest to its start), and the cut stretch.
fn window_around(
    stretch: &mut Revisit,
    positions: &[Point2<f64>],
    window: usize,
) -> Vec<Range<usize>> {
    stretch.end = stretch.end.min(stretch.start + window);
    let arc = revisits::arc_lengths(positions);
    stretch.length_m = arc[stretch.end - 1] - arc[stretch.start];
    let cut = &positions[stretch.start..stretch.end];
    let before = arc[stretch.start] - revisits::MIN_SEPARATION_M;
    let near: Vec<usize> = (0..stretch.map_end)
        .filter(|&i| arc[i] <= before && cut.iter().any(|q| (positions[i] - q).norm() <= 30.0))
        .collect();
    // Contiguous runs of near scans; the one passing closest to the stretch start.
    let mut runs: Vec<Range<usize>> = Vec::new();
    for &i in &near {
        match runs.last_mut() {
            Some(run) if run.end == i => run.end = i + 1,
            _ => runs.push(i..i + 1),
        }
    }
    let start = positions[stretch.start];
    let distance = |run: &Range<usize>| {
        run.clone()
            .map(|i| (positions[i] - start).norm())
            .fold(f64::INFINITY, f64::min)
    };
    let mut ranges: Vec<Range<usize>> = runs
        .into_iter()
        .min_by(|a, b| distance(a).total_cmp(&distance(b)))
        .into_iter()
        .collect();
    ranges.push(stretch.start..stretch.end);
    ranges
}

/// The later-pass protocol on one revisiting stretch: `runs` runs on the map of the earlier
/// pass and as many on the same-drive map (same seeds); `step` after each run.
fn later_pass(
    filter: &Localize,
    maps: &[LocalMap],
    same_drive_map: &[Pole],
    stretch: &Revisit,
    runs: usize,
    mut step: impl FnMut(),
) -> Result<Value> {
    let earlier: Vec<LocalMap> = maps
        .iter()
        .filter(|m| m.scans.iter().all(|&i| i < stretch.map_end))
        .cloned()
        .collect();
    let map = reference_map(&earlier, filter.preset);
    let (mut later_runs, mut same_runs) = (Vec::new(), Vec::new());
    for r in 0..runs {
        for (poles, out) in [
            (&map[..], &mut later_runs),
            (same_drive_map, &mut same_runs),
        ] {
            out.push(filter.run(stretch.start..stretch.end, poles, 2000 + r as u64)?);
            step();
        }
    }
    let map_scan_range = match (
        earlier.iter().filter_map(|m| m.scans.first()).min(),
        earlier.iter().filter_map(|m| m.scans.last()).max(),
    ) {
        (Some(lo), Some(hi)) => json!([lo, hi]),
        _ => Value::Null,
    };
    Ok(json!({
        "start_scan": stretch.start,
        "end_scan": stretch.end,
        "length_m": stretch.length_m,
        "separation_m": stretch.separation_m,
        "map_scans": stretch.map_end,
        "map_scan_range": map_scan_range,
        "local_maps": earlier.len(),
        "map_poles": map.len(),
        "runs": runs,
        "summary": RunSummary::of(&later_runs).json(),
        "same_drive_map_summary": RunSummary::of(&same_runs).json(),
    }))
}
