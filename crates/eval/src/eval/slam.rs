//! `cargo xtask eval slam`: 2-D SLAM (`raypath-slam`) on the raw benchmark logs, scored by the
//! relation errors of Kümmerle et al. (2009) against the corrected logs, beside odometry, the
//! Hector front-end alone and the published figures of Cartographer, graph mapping and
//! GMapping; large loops without reference are shown as maps with a self-consistency measure.
//! Where the data directory holds the benchmark's own relation files
//! (`carmen/relations/<log>.relations`), every row is also scored against them, like for like
//! with the published figures.
//!
//! In stages (`--shard i/n`, `merge`): one unit per referenced log (`referenced/<log>`), per
//! log without reference (`unreferenced/<log>`), per held-out corrected log
//! (`held-out/<log>`, [`held_out`]) and per simulated world of the residual ablation
//! (`ablation/<world>`); [`page`] draws the report from their results.

mod held_out;
mod page;
mod refinement;

use std::time::Instant;

use anyhow::{Context, Result, bail};
use raypath_geometry::Pose2;
use raypath_io::relations::read_relations;
use raypath_io::sequence::{PlanarFrame, PlanarOptions, pair_reference, read_planar};
use raypath_reflectivity::benchmark::run_matcher;
use raypath_reflectivity::{PointFilter, ResidualMode};
use raypath_slam::benchmark::{
    ErrorSummary, LoopPairing, MatchedRelations, RefineConfig, Refined, check_loops,
    consecutive_relations, explicit_relation_errors, file_relation_errors, match_relation_file,
    random_relations, refine_relations, relation_errors, scan_supported, submap_disagreement,
};
use raypath_slam::graph::RobustKernel;
use raypath_slam::{Slam, SlamConfig, SlamOutput};
use serde_json::{Value, json};

use super::stages::{Staged, UnitResults};
use super::{EvalContext, EvalReport};

const NAME: &str = "slam";
/// Seed of the random-pair relations.
const SEED: u64 = 2009;
/// Random-pair relations per log.
const RANDOM_PAIRS: usize = 1000;

/// Logs with a corrected log: name, raw log, corrected log.
const REFERENCED: [(&str, &str, &str); 3] = super::BENCHMARK_LOGS;

/// Logs without a reference: name, raw log.
const UNREFERENCED: [(&str, &str); 4] = [
    ("fr-clinic", "carmen/raw/fr-clinic_robotlaser.clf.bz2"),
    ("mit-killian", "carmen/raw/mit-killian.clf.gz"),
    ("ual", "carmen/raw/ual-2014-05-23.clf.gz"),
    (
        "malaga-telecom",
        "carmen/raw/malaga-telecom-one-loop.clf.gz",
    ),
];

/// Published translational relation errors (m, mean ± std): Cartographer (Hess et al. 2016,
/// Table I; the values the issue recalls), graph mapping and GMapping (Kümmerle et al. 2009 as
/// quoted there; recalled, not re-checked against the paper).
const PUBLISHED: [(&str, &str, &str, &str); 3] = [
    ("intel", "0.0229 ± 0.0239", "0.031 ± 0.026", "0.070 ± 0.083"),
    ("fr079", "0.0452 ± 0.0354", "0.056 ± 0.042", "0.061 ± 0.044"),
    (
        "mit-csail",
        "0.0319 ± 0.0363",
        "0.004 ± 0.009",
        "0.049 ± 0.049",
    ),
];

/// The benchmark log kept out of all tuning since the benchmark's relation files arrived: no
/// default of raypath-slam was chosen by looking at its figures, so its row says how the
/// settings carry to a log they were not fitted on.
pub(super) const HELD_OUT: &str = "fr079";

/// One run's scores.
struct Scored {
    consecutive: ErrorSummary,
    /// Over the scan-supported consecutive relations only ([`scan_supported`]).
    supported: ErrorSummary,
    /// Over the scan-refined consecutive relations ([`refine_relations`]).
    refined: ErrorSummary,
    random: ErrorSummary,
    loops: usize,
    rejected: usize,
    wrong: usize,
    /// Wrong when each loop's scan is compared with the nearest node instead
    /// ([`LoopPairing::Nearest`]).
    wrong_nearest: usize,
    /// Of the wrong ones, those where the reference itself is disputed by the scans
    /// ([`raypath_slam::benchmark::LoopCheck::reference_disputed`]).
    disputed: usize,
    checked: usize,
    seconds: Took,
    scans: usize,
    /// Over the benchmark's own relation file, when the data set has it.
    benchmark: Option<ErrorSummary>,
    /// Over its relations between scans at most [`LOCAL_GAP_SECS`] apart (local accuracy) and
    /// over the others (relations across a loop), when the data set has the file.
    benchmark_local: Option<ErrorSummary>,
    benchmark_across: Option<ErrorSummary>,
}

/// Relations of a relation file between scans at most this far apart in time are counted as
/// local (the robot moved a few metres at most), the others as across a loop, seconds.
pub(super) const LOCAL_GAP_SECS: f64 = 10.0;

/// The relations of `matched` whose two scans are at most (`local`) or more than (`!local`)
/// [`LOCAL_GAP_SECS`] apart by the frames' sensor time.
fn split_by_gap(
    matched: &MatchedRelations,
    frames: &[PlanarFrame],
    local: bool,
) -> MatchedRelations {
    let gap = |i: usize, j: usize| match (frames.get(i), frames.get(j)) {
        (Some(a), Some(b)) => (a.sensor_stamp_secs() - b.sensor_stamp_secs()).abs(),
        _ => f64::INFINITY,
    };
    MatchedRelations {
        relations: matched
            .relations
            .iter()
            .copied()
            .filter(|&(i, j, _)| (gap(i, j) <= LOCAL_GAP_SECS) == local)
            .collect(),
        unmatched: 0,
    }
}

fn read(ctx: &EvalContext, path: &str, limit: Option<usize>) -> Result<Vec<PlanarFrame>> {
    let file = ctx.data(path);
    let mut frames = read_planar(&file, &PlanarOptions::default())
        .with_context(|| format!("reading {}", file.display()))?;
    if let Some(n) = limit {
        frames.truncate(n);
    }
    Ok(frames)
}

/// How long a run took: wall-clock seconds and, where the system tells, the CPU seconds of
/// the thread that ran it (SLAM runs on one thread), which other work on the machine does
/// not inflate.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Took {
    pub(super) wall: f64,
    pub(super) cpu: Option<f64>,
}

impl Took {
    fn since(started: Instant, cpu_started: Option<f64>) -> Self {
        Self {
            wall: started.elapsed().as_secs_f64(),
            cpu: thread_cpu_seconds().zip(cpu_started).map(|(b, a)| b - a),
        }
    }
}

/// CPU seconds the calling thread has used (`/proc/thread-self/stat`, Linux, in clock ticks
/// of 10 ms); `None` where that file does not exist.
fn thread_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
    // Fields after the command name (which may hold spaces) start at field 3 (state);
    // utime and stime are fields 14 and 15.
    let rest = stat.rsplit_once(')')?.1;
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |k: usize| fields.get(k).and_then(|v| v.parse::<f64>().ok());
    Some((ticks(11)? + ticks(12)?) / 100.0)
}

fn run_slam(frames: &[PlanarFrame], config: SlamConfig) -> Result<(SlamOutput, Took)> {
    let (started, cpu) = (Instant::now(), thread_cpu_seconds());
    let mut slam = Slam::new(config)?;
    for f in frames {
        slam.process(f)?;
    }
    let out = slam.finish()?;
    Ok((out, Took::since(started, cpu)))
}

/// A log's reference and relation sets: they depend on the frames only, so every method run
/// on the log is scored against the same sets, computed once.
struct Relations {
    truth: Vec<Option<Pose2>>,
    consecutive: Vec<(usize, usize)>,
    supported: Vec<(usize, usize)>,
    /// The consecutive relations refined by aligning their scans.
    refined: Refined,
    random: Vec<(usize, usize)>,
    /// The benchmark's relation file (`carmen/relations/<log>.relations`), when present.
    file: Option<MatchedRelations>,
}

impl Relations {
    fn of(frames: &[PlanarFrame]) -> Result<Self> {
        let truth: Vec<Option<Pose2>> = frames.iter().map(|f| f.reference).collect();
        let referenced: Vec<usize> = (0..frames.len()).filter(|&i| truth[i].is_some()).collect();
        let consecutive = consecutive_relations(&referenced);
        let scans: Vec<&raypath_geometry::Scan2> = frames.iter().map(|f| &f.scan).collect();
        let supported = scan_supported(&scans, &truth, &consecutive);
        let refined = refine_relations(&scans, &truth, &consecutive, &RefineConfig::default())?;
        let random = random_relations(&referenced, RANDOM_PAIRS, SEED);
        Ok(Self {
            truth,
            consecutive,
            supported,
            refined,
            random,
            file: None,
        })
    }
}

/// Where the benchmark's relation file of `log` is looked for under the data directory.
fn relation_file(log: &str) -> String {
    format!("carmen/relations/{log}.relations")
}

/// The benchmark's relation file of `log` matched to the frames' ipc time stamps, when the
/// data set has it.
fn read_relation_file(
    ctx: &EvalContext,
    log: &str,
    frames: &[PlanarFrame],
) -> Result<Option<MatchedRelations>> {
    let path = ctx.data(&relation_file(log));
    if !path.exists() {
        return Ok(None);
    }
    let relations = read_relations(&path)?;
    let stamps: Vec<_> = frames.iter().map(|f| f.ipc_stamp_secs).collect();
    Ok(Some(match_relation_file(&stamps, &relations)))
}

fn score(
    rel: &Relations,
    frames: &[PlanarFrame],
    poses: &[Pose2],
    out: Option<&SlamOutput>,
    seconds: Took,
) -> Scored {
    let truth = &rel.truth;
    let consecutive = relation_errors(truth, poses, &rel.consecutive);
    let supported = relation_errors(truth, poses, &rel.supported);
    let refined = explicit_relation_errors(poses, &rel.refined.relations);
    let random = relation_errors(truth, poses, &rel.random);
    let benchmark = rel.file.as_ref().map(|m| file_relation_errors(poses, m));
    let part = |local: bool| {
        rel.file
            .as_ref()
            .map(|m| file_relation_errors(poses, &split_by_gap(m, frames, local)))
    };
    let (benchmark_local, benchmark_across) = (part(true), part(false));
    let (mut wrong, mut checked, mut loops, mut rejected, mut disputed) = (0, 0, 0, 0, 0);
    let mut wrong_nearest = 0;
    if let Some(out) = out {
        loops = out.loop_closures.len();
        rejected = out.rejected_loop_closures.len();
        let checks;
        let scans: Vec<&raypath_geometry::Scan2> = frames.iter().map(|f| &f.scan).collect();
        (checked, wrong, checks) = check_loops(out, &scans, truth, 50, LoopPairing::Overlap);
        (_, wrong_nearest, _) = check_loops(out, &scans, truth, 50, LoopPairing::Nearest);
        disputed = raypath_slam::benchmark::wrong_at_disputed_reference(&checks, &scans, truth);
    }
    Scored {
        consecutive,
        supported,
        refined,
        random,
        loops,
        rejected,
        wrong,
        wrong_nearest,
        disputed,
        checked,
        seconds,
        scans: poses.len(),
        benchmark,
        benchmark_local,
        benchmark_across,
    }
}

/// A scored method on a log as JSON: the keys of the report's rows (`page::table_row`).
fn row_json(log: &str, method: &str, s: &Scored) -> Value {
    let sps = if s.seconds.wall > 0.0 {
        s.scans as f64 / s.seconds.wall
    } else {
        f64::NAN
    };
    json!({
        "log": log, "method": method, "summary": s.consecutive, "random_pairs": s.random,
        "scan_supported": s.supported, "scan_refined": s.refined,
        "loop_closures": s.loops, "rejected_loop_closures": s.rejected,
        "wrong_loop_closures": s.wrong, "loop_closures_checked": s.checked,
        "wrong_loop_closures_nearest_node": s.wrong_nearest,
        "wrong_loop_closures_reference_disputed": s.disputed,
        "benchmark_relations": s.benchmark,
        "benchmark_relations_local": s.benchmark_local,
        "benchmark_relations_across_loops": s.benchmark_across,
        "seconds": s.seconds.wall, "cpu_seconds": s.seconds.cpu, "scans": s.scans,
        "scans_per_second": sps,
    })
}

/// The variants run on every referenced log: (label, configuration change).
fn variants(quick: bool) -> Vec<(&'static str, SlamConfig)> {
    let full = SlamConfig::default();
    let no_loops = SlamConfig {
        loops: None,
        ..SlamConfig::default()
    };
    let mut no_robust = SlamConfig::default();
    no_robust.solver.loop_kernel = RobustKernel::None;
    let mut v = vec![("raypath-slam", full), ("  without loop closure", no_loops)];
    if !quick {
        v.push(("  without robust kernel", no_robust));
    }
    v
}

/// The stages of `eval slam`.
pub const STAGED: Staged = Staged {
    name: NAME,
    units,
    run_unit,
    report,
};

/// The simulated worlds of the residual ablation.
fn worlds(quick: bool) -> &'static [&'static str] {
    if quick {
        &["lab"]
    } else {
        &["lab", "hall", "office"]
    }
}

/// The referenced logs, the logs without reference, the held-out corrected logs, then the
/// ablation's worlds (quick: the first referenced log, the last unreferenced one, the first
/// held-out log, one world).
fn units(ctx: &EvalContext) -> Result<Vec<String>> {
    let (referenced, unreferenced) = if ctx.quick {
        (&REFERENCED[..1], &UNREFERENCED[3..])
    } else {
        (&REFERENCED[..], &UNREFERENCED[..])
    };
    Ok(referenced
        .iter()
        .map(|(name, _, _)| format!("referenced/{name}"))
        .chain(
            unreferenced
                .iter()
                .map(|(name, _)| format!("unreferenced/{name}")),
        )
        .chain(held_out_logs(ctx.quick).map(|name| format!("held-out/{name}")))
        .chain(worlds(ctx.quick).iter().map(|w| format!("ablation/{w}")))
        .collect())
}

/// The held-out corrected logs run (quick: the first).
fn held_out_logs(quick: bool) -> impl Iterator<Item = &'static str> {
    let n = if quick { 1 } else { held_out::LOGS.len() };
    held_out::LOGS[..n].iter().map(|(name, _)| *name)
}

/// Measures one unit.
fn run_unit(ctx: &EvalContext, unit: &str) -> Result<Value> {
    match unit.split_once('/') {
        Some(("referenced", name)) => match REFERENCED.iter().find(|(n, _, _)| *n == name) {
            Some((name, raw, corrected)) => referenced(ctx, name, raw, corrected),
            None => bail!("{name:?} is not a referenced log"),
        },
        Some(("unreferenced", name)) => match UNREFERENCED.iter().find(|(n, _)| *n == name) {
            Some((name, raw)) => unreferenced(ctx, name, raw),
            None => bail!("{name:?} is not a log without reference"),
        },
        Some(("held-out", name)) => held_out::run(ctx, name),
        Some(("ablation", world)) => ablation(ctx, world),
        _ => bail!("{unit:?} is not a unit of {NAME}"),
    }
}

/// The report from the unit results.
fn report(ctx: &EvalContext, results: &UnitResults) -> Result<EvalReport> {
    page::report(ctx, results).context("drawing the slam page")
}

/// A referenced log: odometry, the front-end alone and the SLAM variants, scored against the
/// corrected log; `{"skipped": note}` when a file is missing.
fn referenced(ctx: &EvalContext, name: &str, raw: &str, corrected: &str) -> Result<Value> {
    if !ctx.data(raw).exists() || !ctx.data(corrected).exists() {
        return Ok(
            json!({ "skipped": format!("`{raw}` or `{corrected}` missing: {name} skipped.") }),
        );
    }
    let limit = ctx.quick.then_some(2000);
    let mut frames = read(ctx, raw, limit)?;
    let reference = read(ctx, corrected, None)?;
    pair_reference(&mut frames, &reference);
    let mut relations = Relations::of(&frames)?;
    relations.file = read_relation_file(ctx, name, &frames)?;
    let unmatched = relations.file.as_ref().map(|m| m.unmatched);
    let odometry: Vec<Pose2> = frames.iter().map(|f| f.world_from_laser).collect();
    let mut rows = vec![row_json(
        name,
        "odometry",
        &score(&relations, &frames, &odometry, None, Took::default()),
    )];
    let (started, cpu) = (Instant::now(), thread_cpu_seconds());
    let matcher = raypath_reflectivity::MatcherConfig {
        map: raypath_reflectivity::MapConfig {
            size_m: 160.0,
            ..Default::default()
        },
        ..Default::default()
    };
    let (_, results) = run_matcher(&frames, matcher, &PointFilter::default(), None, true)?;
    let hector: Vec<Pose2> = results.iter().map(|r| r.world_from_sensor).collect();
    let s = score(
        &relations,
        &frames,
        &hector,
        None,
        Took::since(started, cpu),
    );
    rows.push(row_json(name, "front-end alone (Hector, one map)", &s));
    let mut map = None;
    for (label, config) in variants(ctx.quick) {
        let (out, seconds) = run_slam(&frames, config)?;
        if map.is_none() {
            // The map of the full system (the first variant), a picture per log.
            let png = format!("{name}.png");
            super::slam_map::write_png(&out, &ctx.figure_dir(NAME)?.join(&png))?;
            map = Some(png);
        }
        let s = score(
            &relations,
            &frames,
            &out.world_from_sensor,
            Some(&out),
            seconds,
        );
        rows.push(row_json(name, label, &s));
    }
    Ok(json!({
        "rows": rows, "relation_file_unmatched": unmatched, "map": map,
        "scan_refinement": refinement::of_reference(name, &relations),
    }))
}

/// A log without reference: SLAM with and without loop closure, the submap disagreement of
/// both, and the map as a picture.
fn unreferenced(ctx: &EvalContext, name: &str, raw: &str) -> Result<Value> {
    if !ctx.data(raw).exists() {
        return Ok(json!({ "skipped": format!("`{raw}` missing: {name} skipped.") }));
    }
    let frames = read(ctx, raw, None)?;
    let no_loops = SlamConfig {
        loops: None,
        ..SlamConfig::default()
    };
    let (base, _) = run_slam(&frames, no_loops)?;
    let (out, took) = run_slam(&frames, SlamConfig::default())?;
    let (d0, _) = submap_disagreement(&base);
    let (d, compared) = submap_disagreement(&out);
    let png = format!("{name}.png");
    super::slam_map::write_png(&out, &ctx.figure_dir(NAME)?.join(&png))?;
    let sps = frames.len() as f64 / took.wall;
    Ok(json!({
        "log": name, "scans": frames.len(), "nodes": out.nodes.len(),
        "submaps": out.submaps.len(),
        "loop_closures": out.loop_closures.len(), "rejected_loop_closures": out.rejected_loop_closures.len(),
        "disagreement_without_loops": d0, "disagreement": d, "cells_compared": compared,
        "seconds": took.wall, "cpu_seconds": took.cpu, "scans_per_second": sps, "map": png,
    }))
}

/// Occupancy against combined residual on one generated indoor world with remissions
/// (simulated): the same SLAM with the simulator's intensity LUT.
fn ablation(ctx: &EvalContext, world: &str) -> Result<Value> {
    let Some((raw, corrected)) = crate::generate::indoor_logs(world, ctx.quick)? else {
        return Ok(json!({
            "skipped": format!("the generated `indoor/{world}` logs are missing: skipped.")
        }));
    };
    let lut = super::scan_matching::simulated_lut(if ctx.quick { 4000 } else { 20000 })?;
    let options = PlanarOptions::default();
    let mut frames = read_planar(&raw, &options)?;
    if ctx.quick {
        frames.truncate(600);
    }
    pair_reference(&mut frames, &read_planar(&corrected, &options)?);
    let relations = Relations::of(&frames)?;
    let check = refinement::check(world, &frames, &relations)?;
    let mut notes = Vec::new();
    let modes: &[ResidualMode] = if frames.iter().any(|f| f.scan.intensities.is_some()) {
        &[ResidualMode::Occupancy, ResidualMode::Combined]
    } else {
        notes.push(format!(
            "`indoor/{world}` has no remissions (FLASER lines): occupancy only."
        ));
        &[ResidualMode::Occupancy]
    };
    let mut rows = Vec::new();
    for &mode in modes {
        let mut config = SlamConfig::default();
        config.matcher.mode = mode;
        let (started, cpu) = (Instant::now(), thread_cpu_seconds());
        let mut slam = Slam::new(config)?.with_correction(lut.clone());
        for f in &frames {
            slam.process(f)?;
        }
        let out = slam.finish()?;
        let s = score(
            &relations,
            &frames,
            &out.world_from_sensor,
            Some(&out),
            Took::since(started, cpu),
        );
        let mut v = row_json(world, mode.name(), &s);
        if let Some(obj) = v.as_object_mut() {
            obj.insert("simulated".into(), json!(true));
        }
        rows.push(v);
    }
    Ok(json!({ "rows": rows, "notes": notes, "refinement_check": check }))
}
