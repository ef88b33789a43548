//! The scan-refined relations of `eval slam`: how far each corrected log's consecutive
//! relations sit from what their scans say, and a check of the refinement on the simulated
//! worlds, whose reference is exact.

use anyhow::Result;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use raypath_geometry::Pose2;
use raypath_io::sequence::PlanarFrame;
use raypath_slam::benchmark::{
    ErrorSummary, RefineConfig, explicit_relation_errors, refine_relations, relation_errors,
};
use serde_json::{Value, json};

use super::{Relations, SEED};
use crate::table::{Table, fmt_num};

/// Noise put on each exact reference pose of a simulated world for the check: σ per axis,
/// metres, and σ of the heading, degrees — a corrected log's local error, about what the
/// refinement measures on the real logs.
const CHECK_NOISE: (f64, f64) = (0.02, 0.3);

/// The refinement of a log's consecutive relations: kept, dropped by reason, and how far the
/// kept ones moved their reference.
pub(super) fn of_reference(log: &str, rel: &Relations) -> Value {
    let (moved, moved_std) = rel.refined.correction_m();
    json!({
        "log": log, "consecutive": rel.consecutive.len(),
        "kept": rel.refined.relations.len(), "dropped": rel.refined.dropped,
        "reference_moved_m": moved, "reference_moved_std_m": moved_std,
    })
}

/// On a simulated world: the refinement from the exact reference, and from the exact
/// reference with [`CHECK_NOISE`] on every pose (seeded), each scored against the truth.
pub(super) fn check(world: &str, frames: &[PlanarFrame], rel: &Relations) -> Result<Value> {
    let truth: Vec<Pose2> = rel.truth.iter().map(|p| p.unwrap_or_default()).collect();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(SEED);
    let (Ok(along), Ok(turn)) = (
        Normal::new(0.0, CHECK_NOISE.0),
        Normal::new(0.0, CHECK_NOISE.1.to_radians()),
    ) else {
        anyhow::bail!("the check's noise must be finite and positive");
    };
    let noisy: Vec<Option<Pose2>> = rel
        .truth
        .iter()
        .map(|p| {
            let noise = Pose2::new(
                along.sample(&mut rng),
                along.sample(&mut rng),
                turn.sample(&mut rng),
            );
            p.map(|p| p * noise)
        })
        .collect();
    let noisy_poses: Vec<Pose2> = noisy.iter().map(|p| p.unwrap_or_default()).collect();
    let scans: Vec<&raypath_geometry::Scan2> = frames.iter().map(|f| &f.scan).collect();
    let from_noisy = refine_relations(&scans, &noisy, &rel.consecutive, &RefineConfig::default())?;
    Ok(json!({
        "world": world, "consecutive": rel.consecutive.len(),
        "noise_m": CHECK_NOISE.0, "noise_deg": CHECK_NOISE.1,
        "exact_kept": rel.refined.relations.len(),
        "exact_refined_error": explicit_relation_errors(&truth, &rel.refined.relations),
        "noisy_reference_error": relation_errors(&rel.truth, &noisy_poses, &rel.consecutive),
        "noisy_kept": from_noisy.relations.len(),
        "noisy_refined_error": explicit_relation_errors(&truth, &from_noisy.relations),
    }))
}

fn summary(v: &Value, key: &str) -> Result<ErrorSummary> {
    Ok(serde_json::from_value(v[key].clone())?)
}

fn pm(s: &ErrorSummary) -> String {
    format!(
        "{} ± {} m, {} ± {}°",
        fmt_num(s.trans_error_m, 4),
        fmt_num(s.trans_error_std_m, 4),
        fmt_num(s.rot_error_deg, 2),
        fmt_num(s.rot_error_std_deg, 2)
    )
}

/// The table of the real logs' refinements (`of_reference` values).
pub(super) fn reference_table(refinements: &[&Value]) -> Result<String> {
    let mut t = Table::new([
        "log",
        "consecutive relations",
        "refined (kept)",
        "dropped: ambiguous / unconstrained / unsupported / far / unaligned",
        "reference moved by the refinement, m",
    ]);
    for v in refinements {
        let d = &v["dropped"];
        let n = |key: &str| d[key].as_u64().unwrap_or(0);
        t.row([
            v["log"].as_str().unwrap_or_default().to_string(),
            v["consecutive"].as_u64().unwrap_or(0).to_string(),
            v["kept"].as_u64().unwrap_or(0).to_string(),
            format!(
                "{} / {} / {} / {} / {}",
                n("ambiguous"),
                n("unconstrained"),
                n("unsupported"),
                n("far_from_reference"),
                n("unaligned")
            ),
            format!(
                "{} ± {}",
                fmt_num(v["reference_moved_m"].as_f64().unwrap_or(f64::NAN), 4),
                fmt_num(v["reference_moved_std_m"].as_f64().unwrap_or(f64::NAN), 4)
            ),
        ]);
    }
    t.to_markdown()
}

/// The table of the checks on simulated worlds (`check` values).
pub(super) fn check_table(checks: &[&Value]) -> Result<String> {
    let mut t = Table::new([
        "world (simulated)",
        "consecutive relations",
        "refined from the exact reference: kept, error",
        "reference with noise: error",
        "refined from it: kept, error",
    ]);
    for v in checks {
        t.row([
            v["world"].as_str().unwrap_or_default().to_string(),
            v["consecutive"].as_u64().unwrap_or(0).to_string(),
            format!(
                "{}, {}",
                v["exact_kept"].as_u64().unwrap_or(0),
                pm(&summary(v, "exact_refined_error")?)
            ),
            pm(&summary(v, "noisy_reference_error")?),
            format!(
                "{}, {}",
                v["noisy_kept"].as_u64().unwrap_or(0),
                pm(&summary(v, "noisy_refined_error")?)
            ),
        ]);
    }
    t.to_markdown()
}
