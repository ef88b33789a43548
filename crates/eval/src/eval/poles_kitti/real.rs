//! The real section of `eval poles-kitti`: pole extraction with the KITTI preset on the real
//! KITTI HDL-64E frames of `RAYPATH_DATA/kitti/sequences/{00,01,04,07}` (frames 0–9, with
//! SemanticKITTI labels and SuMa poses), against reference poles clustered from the labelled
//! pole, trunk and traffic-sign points ([`raypath_poles::reference_poles`]); beside it the same
//! local map simulated by `raypath-sim` at the first ten poses of the `kitti-poles`
//! trajectory among the real pole map, scored the same way against the simulated labels.
//!
//! * Local map: all ten scans in one grid centred at the scan at the middle of their arc
//!   length (the thesis builds KITTI local maps from the scans of 5 m of trajectory, which
//!   ten frames at 0.1–1.3 m per frame roughly are); also every scan alone, pooled.
//! * Scored where the extractor can see: references and detections within 12 m of a scan
//!   position (as the semi-synthetic detection table) and 1 m inside the grid footprint;
//!   references from points in the grid's height band. A match is the closest unused pair
//!   within 1 m, jointly over all classes.
//! * Variants ([`Variant`]): the real frames traced from where the sensor was at each point
//!   (KITTI's sweeps are de-skewed sweeps of a moving sensor, [`SweepTiming::kitti`]) and,
//!   as before that change, from each scan's origin; the simulation with every beam from one
//!   pose (as the semi-synthetic drives), and with the sweeps of a moving sensor traced both
//!   ways.

use anyhow::{Context, Result};
use raypath_io::poles_csv::read_pole_csv;
use raypath_poles::{
    LabelledLocalMap, PoleClass, PoleParams, ReferencePole, ReferenceRule, SweepMotion,
    SweepTiming, greedy_matches,
};
use raypath_sim::datasets::DEFAULT_SEED;
use raypath_sim::semi_kitti::SemiKittiDrive;
use raypath_sim::urban::kinds::PoleKind;
use serde_json::{Value, json};

use super::super::EvalContext;

mod diagnose;
mod render;
mod tally;

use tally::{Evaluated, MARGIN_M, MATCH_M, RADIUS_M, Scored, evaluate, score};

/// The real sequences (10 frames each).
const REAL_SEQUENCES: [&str; 4] = ["00", "01", "04", "07"];
/// Frames per local map.
const FRAMES: usize = 10;

/// What is extracted and how its rays are traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Variant {
    /// The real frames, rays from where the sensor was at each point.
    Real,
    /// The real frames, rays from each scan's origin (the extractor before).
    RealFromOrigin,
    /// Simulated, every beam of a scan from one pose (as the semi-synthetic drives).
    Simulated,
    /// Simulated sweeps of a moving sensor, rays from each scan's origin.
    MovingFromOrigin,
    /// Simulated sweeps of a moving sensor, rays from where the sensor was.
    Moving,
}

impl Variant {
    const ALL: [Variant; 5] = [
        Variant::Real,
        Variant::RealFromOrigin,
        Variant::Simulated,
        Variant::MovingFromOrigin,
        Variant::Moving,
    ];

    /// The row label.
    fn label(self) -> &'static str {
        match self {
            Variant::Real => "real",
            Variant::RealFromOrigin => "real, rays from the scan origin (before)",
            Variant::Simulated => "simulated, one-pose scans",
            Variant::MovingFromOrigin => "simulated sweeps, rays from the scan origin",
            Variant::Moving => "simulated sweeps",
        }
    }

    /// The JSON key.
    fn key(self) -> &'static str {
        match self {
            Variant::Real => "real",
            Variant::RealFromOrigin => "real_rays_from_scan_origin",
            Variant::Simulated => "simulated_one_pose",
            Variant::MovingFromOrigin => "simulated_sweeps_rays_from_scan_origin",
            Variant::Moving => "simulated_sweeps",
        }
    }
}

/// Everything measured on one sequence.
struct SequenceResult {
    sequence: &'static str,
    variants: Vec<(Variant, Evaluated)>,
    /// Entries of `kitti-poles/NN/poles.csv` in the real scoring region, and how many of them
    /// match a real reference.
    csv: Option<(usize, usize)>,
    /// Poles placed in the simulated world in its scoring region, and the one-pose
    /// simulation's detections scored against them.
    placed: Option<(usize, Scored)>,
}

impl SequenceResult {
    fn get(&self, variant: Variant) -> Option<&Evaluated> {
        self.variants
            .iter()
            .find(|(v, _)| *v == variant)
            .map(|(_, e)| e)
    }
}

/// The simulated local map of a sequence: the first ten poses of `kitti-poles/NN` in the
/// world built around them among the real pole map (`moving`: sweeps of the moving sensor,
/// with their motions); also the poles placed in that world.
fn simulated(
    ctx: &EvalContext,
    sequence: &str,
    moving: bool,
) -> Result<Option<(LabelledLocalMap, Vec<ReferencePole>)>> {
    let Some(mut config) = ctx.semi_kitti_config(sequence, Some(FRAMES))? else {
        return Ok(None);
    };
    config.sweep_motion = moving;
    let sim = SemiKittiDrive::new(&config, DEFAULT_SEED)
        .with_context(|| format!("building the world of semi-kitti {sequence}"))?;
    let scans = (0..sim.len())
        .map(|i| Ok((sim.world_from_velo[i], sim.scan(i)?)))
        .collect::<Result<Vec<_>>>()?;
    let placed = sim
        .poles
        .iter()
        .map(|p| ReferencePole {
            x: p.x,
            y: p.y,
            class: match p.kind {
                PoleKind::TreeTrunk => PoleClass::Trunk,
                _ => PoleClass::Pole,
            },
            points: 0,
            z_min: p.base_z,
            z_max: p.base_z + p.height_m,
            sign_points: 0,
        })
        .collect();
    let mut map = LabelledLocalMap::new(scans)?;
    if moving {
        let timing = SweepTiming::kitti();
        let motions = sim
            .sweep_translation_m
            .iter()
            .map(|&translation_m| SweepMotion {
                translation_m,
                timing,
            })
            .collect();
        map = map.with_motions(motions)?;
    }
    Ok(Some((map, placed)))
}

/// The same map with every ray from its scan's origin.
fn from_origin(map: &LabelledLocalMap) -> LabelledLocalMap {
    LabelledLocalMap {
        motions: None,
        ..map.clone()
    }
}

/// All variants of one sequence; `None` when its real frames are missing.
fn run_sequence(
    ctx: &EvalContext,
    sequence: &'static str,
    params: &PoleParams,
    rule: &ReferenceRule,
    notes: &mut Vec<String>,
) -> Result<Option<SequenceResult>> {
    let dir = ctx.data(&format!("kitti/sequences/{sequence}"));
    if !dir.join("labels").is_dir() {
        notes.push(format!(
            "Real sequence {sequence} skipped: {} has no labels/.",
            dir.display()
        ));
        return Ok(None);
    }
    let bar = ctx.progress(5, &format!("real {sequence}"));
    let real = LabelledLocalMap::read_kitti(&dir, 0..FRAMES)
        .with_context(|| format!("reading {}", dir.display()))?;
    let mut variants = vec![(Variant::Real, evaluate(&real, params, rule)?)];
    bar.inc(1);
    variants.push((
        Variant::RealFromOrigin,
        evaluate(&from_origin(&real), params, rule)?,
    ));
    bar.inc(1);
    let region = real.region(&real.all(), params, RADIUS_M, MARGIN_M);
    let csv_path = ctx.data(&format!("kitti-poles/{sequence}/poles.csv"));
    let csv = if csv_path.exists() {
        let listed: Vec<(f64, f64)> = read_pole_csv(&csv_path)?
            .iter()
            .filter(|p| region.contains(p.x, p.y))
            .map(|p| (p.x, p.y))
            .collect();
        let refs: Vec<(f64, f64)> = variants[0]
            .1
            .references
            .iter()
            .filter(|r| region.contains(r.x, r.y))
            .map(|r| (r.x, r.y))
            .collect();
        Some((listed.len(), greedy_matches(&listed, &refs, MATCH_M).len()))
    } else {
        None
    };
    let mut placed = None;
    if let Some((sim, poles)) = simulated(ctx, sequence, false)? {
        let evaluated = evaluate(&sim, params, rule)?;
        let sim_region = sim.region(&sim.all(), params, RADIUS_M, MARGIN_M);
        let inside = poles
            .iter()
            .filter(|p| sim_region.contains(p.x, p.y))
            .count();
        placed = Some((inside, score(&evaluated.poles, &poles, &sim_region)));
        variants.push((Variant::Simulated, evaluated));
    } else {
        notes.push(format!(
            "Simulated {sequence} skipped: kitti-poles/{sequence} not found."
        ));
    }
    bar.inc(1);
    if let Some((moving, _)) = simulated(ctx, sequence, true)? {
        variants.push((
            Variant::MovingFromOrigin,
            evaluate(&from_origin(&moving), params, rule)?,
        ));
        bar.inc(1);
        variants.push((Variant::Moving, evaluate(&moving, params, rule)?));
    }
    bar.finish_and_clear();
    Ok(Some(SequenceResult {
        sequence,
        variants,
        csv,
        placed,
    }))
}

/// The real section's outputs.
pub(super) struct Section {
    pub markdown: String,
    pub json: Value,
    /// One sentence on how far the simulation is from the real frames (for the
    /// semi-synthetic part of the report).
    pub realism: String,
    /// The real half of the page's headline.
    pub headline: Option<String>,
}

/// The real section.
pub(super) fn section(ctx: &EvalContext, params: &PoleParams) -> Result<Section> {
    let rule = ReferenceRule::default();
    let mut notes = Vec::new();
    let mut results = Vec::new();
    for sequence in REAL_SEQUENCES {
        if let Some(result) = run_sequence(ctx, sequence, params, &rule, &mut notes)? {
            results.push(result);
        }
    }
    let markdown = render::markdown(&results, &rule, &notes)?;
    let sequences: Vec<Value> = results
        .iter()
        .map(|r| {
            let mut row = json!({ "sequence": r.sequence });
            for (variant, evaluated) in &r.variants {
                row[variant.key()] = evaluated.json();
            }
            if let Some((listed, matched)) = r.csv {
                row["kitti_poles_csv"] = json!({ "in_region": listed, "matched": matched });
            }
            if let Some((inside, scored)) = &r.placed {
                row["simulated_vs_placed"] = json!({ "placed_in_region": inside,
                                                     "scored": scored.json() });
            }
            row
        })
        .collect();
    let totals: serde_json::Map<String, Value> = Variant::ALL
        .iter()
        .map(|&v| {
            let (full, single) = render::pooled(&results, v);
            (
                v.key().to_string(),
                json!({ "full": full.json(), "single": single.json() }),
            )
        })
        .collect();
    let value = json!({
        "frames": FRAMES,
        "rule": rule,
        "radius_m": RADIUS_M,
        "margin_m": MARGIN_M,
        "match_m": MATCH_M,
        "sequences": sequences,
        "totals": totals,
        "notes": notes,
    });
    Ok(Section {
        markdown,
        json: value,
        realism: render::realism(&results),
        headline: render::headline(&results),
    })
}
