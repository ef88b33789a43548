//! Logs nobody tuned on: the corrected CARMEN logs that are not SLAM-benchmark logs, their real
//! scans with wheel odometry drawn from the odometry motion model (seeded), scored against the
//! corrected poses. The corrected logs carry no raw odometry (their odometry fields repeat the
//! corrected pose), so the odometry is simulated: **semi-real** rows. They test what the
//! benchmark logs cannot: whether the settings chosen on Intel and MIT CSAIL hold on seven other
//! buildings, and whether a map breaks (relations off by more than a metre).

use anyhow::{Context, Result};
use rand::SeedableRng;
use raypath_geometry::Pose2;
use raypath_io::sequence::{PlanarFrame, PlanarOptions, read_planar};
use raypath_reflectivity::benchmark::relation_error_lists;
use raypath_slam::SlamConfig;
use raypath_slam::benchmark::{
    consecutive_relations, random_relations, relation_errors, submap_disagreement,
};
use serde_json::{Value, json};

use crate::eval::EvalContext;

/// Intel's corrected log (the calibration row: a building the settings were tuned on, in the
/// same semi-real form), then the corrected logs no setting of raypath-slam was chosen on:
/// name, file.
pub(super) const LOGS: [(&str, &str); 8] = [
    (CALIBRATION, "carmen/corrected/intel-corrected.log.gz"),
    ("aces", "carmen/corrected/aces-corrected.log.gz"),
    ("acapulco", "carmen/corrected/acapulco-corrected.log.gz"),
    ("belgioioso", "carmen/corrected/belgioioso-corrected.log.gz"),
    ("fhw", "carmen/corrected/fhw-corrected.log.gz"),
    (
        "freiburg-101",
        "carmen/corrected/freiburg-101-corrected.log.gz",
    ),
    (
        "freiburg-campus",
        "carmen/corrected/freiburg-campus-corrected.log.gz",
    ),
    (
        "infinite-corridor",
        "carmen/corrected/infinite-corridor-corrected.log.gz",
    ),
];

/// `[α₁, α₂, α₃, α₄]` of the odometry motion model (Thrun et al. 2005, Table 5.6), applied once
/// between consecutive scans (0.6–1.0 m and 0.07–0.34 rad apart on these logs). Chosen so that
/// Intel's corrected scans get odometry like the raw Intel log's: on its 909 consecutive
/// relations 0.0599 ± 0.0513 m and 2.79 ± 2.38° (the raw log's odometry: 0.0585 ± 0.0320 m,
/// 2.74 ± 2.19°, `docs/results/slam.md`).
pub(super) const ALPHAS: [f64; 4] = [0.001, 0.002, 0.009, 0.0003];

/// The calibration row's log.
pub(super) const CALIBRATION: &str = "intel";

/// Seed of the odometry noise (one stream per log, offset by its index).
const SEED: u64 = 35;

/// A random-pair relation whose translational error exceeds this is counted as a broken map,
/// metres.
pub(super) const BROKEN_M: f64 = 1.0;

/// The frames of `file` with their corrected pose as reference and seeded drifting odometry.
fn frames_with_odometry(file: &std::path::Path, seed: u64) -> Result<Vec<PlanarFrame>> {
    let mut frames = read_planar(file, &PlanarOptions::default())
        .with_context(|| format!("reading {}", file.display()))?;
    let truth: Vec<Pose2> = frames.iter().map(|f| f.world_from_laser).collect();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let odometry =
        raypath_sim::indoor::odometry::simulate(&ALPHAS, &truth, Pose2::identity(), &mut rng);
    for (f, (odom, reference)) in frames.iter_mut().zip(odometry.into_iter().zip(truth)) {
        let robot_from_laser = f.robot_from_laser();
        f.reference = Some(reference);
        f.world_from_laser = odom;
        f.world_from_robot = odom * robot_from_laser.inverse();
    }
    Ok(frames)
}

/// Share of `relations` whose translational error is above [`BROKEN_M`].
fn broken_share(
    reference: &[Option<Pose2>],
    estimate: &[Pose2],
    relations: &[(usize, usize)],
) -> f64 {
    let (t, _) = relation_error_lists(
        |i| reference.get(i).and_then(Option::as_ref),
        estimate,
        relations,
    );
    t.iter().filter(|&&e| e > BROKEN_M).count() as f64 / t.len().max(1) as f64
}

/// One held-out log: odometry and raypath-slam (default settings) scored against the corrected
/// poses, the submap disagreement and the map picture.
pub(super) fn run(ctx: &EvalContext, name: &str) -> Result<Value> {
    let Some(k) = LOGS.iter().position(|(n, _)| *n == name) else {
        anyhow::bail!("{name:?} is not a held-out log");
    };
    let file = ctx.data(LOGS[k].1);
    if !file.exists() {
        return Ok(json!({ "skipped": format!("`{}` missing: {name} skipped.", LOGS[k].1) }));
    }
    let mut frames = frames_with_odometry(&file, SEED + k as u64)?;
    if ctx.quick {
        frames.truncate(300);
    }
    let truth: Vec<Option<Pose2>> = frames.iter().map(|f| f.reference).collect();
    let all: Vec<usize> = (0..frames.len()).collect();
    let consecutive = consecutive_relations(&all);
    let random = random_relations(&all, super::RANDOM_PAIRS, super::SEED);
    let score = |poses: &[Pose2]| {
        json!({
            "consecutive": relation_errors(&truth, poses, &consecutive),
            "random_pairs": relation_errors(&truth, poses, &random),
            "broken_share": broken_share(&truth, poses, &random),
        })
    };
    let odometry: Vec<Pose2> = frames.iter().map(|f| f.world_from_laser).collect();
    let (out, took) = super::run_slam(&frames, SlamConfig::default())?;
    let png = format!("held-out-{name}.png");
    crate::eval::slam_map::write_png(&out, &ctx.figure_dir(super::NAME)?.join(&png))?;
    let (disagreement, _) = submap_disagreement(&out);
    Ok(json!({
        "log": name, "scans": frames.len(),
        "odometry": score(&odometry), "slam": score(&out.world_from_sensor),
        "loop_closures": out.loop_closures.len(),
        "rejected_loop_closures": out.rejected_loop_closures.len(),
        "disagreement": disagreement, "seconds": took.wall, "cpu_seconds": took.cpu, "map": png,
    }))
}
