//! `cargo xtask eval mcl`: Monte-Carlo localization error per sensor model (Schaefer 2020,
//! Table 7.2), filter update rates, and the ch. 8 corridor.
//!
//! * **Real 2-D** (Radish raw logs `intel`, `fr079`): odometry and scans from the raw log,
//!   the map (0.1 m) from the corrected log's scans at their corrected poses, ground truth =
//!   corrected poses paired with raw scans by identical readings
//!   (`raypath_io::sequence::pair_reference`). The filter runs on the raw
//!   scans (an update whenever the odometry moved 0.2 m / 0.2 rad, and at every scan with
//!   ground truth); the error is evaluated every 1 m of ground-truth path
//!   (`raypath_localizer::eval`).
//! * **Simulated 2-D** (`datasets/generated/indoor`): the same pipeline.
//! * **Simulated 3-D** (`datasets/generated/urban-kitti`): 6-DOF, 300 particles, 0.5 m
//!   voxels, map from the even scans, localization on the odd ones; campus*-style variant
//!   with 10 % of the rays set to `r_min`.
//!
//! Initial particles: Gaussian (1 m, 0.2 m, 0.1 rad) around a mean that is itself drawn
//! from that Gaussian around the true start (thesis ch. 7). Every model gets the same
//! filter, seeds, likelihood exponent and outlier mixture (`LidarConfig::default()`: the
//! scan counts as 8 independent beams; every beam is mixed with a random reading of weight
//! ε = 0.05, AMCL's `z_rand`, because the ray-casting models have no false-detection term
//! and single no-return or unmapped-space beams otherwise decide the weights).
//!
//! In stages: one unit per 2-D data set (the first one present also measures the filter
//! speed), one for the 3-D drive and one for the corridor; the page ([`page`]) from their
//! results.

mod common;
mod fmp;
mod page;
mod planar;
mod spatial;
mod speed;

use std::path::PathBuf;

use anyhow::{Result, bail};
use raypath_localizer::lidar::{LidarConfig, ModelKind, ModelSpec};
use raypath_sensor_models::GammaPrior;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use super::stages::{self, Staged, UnitResults};
use super::{EvalContext, EvalReport};
use common::Cell;
use speed::SpeedRow;

const NAME: &str = "mcl";
/// Particles of the 2-D accuracy runs (the thesis's count for its 3-D runs).
const PARTICLES_2D: usize = 300;
/// Beam step of the 2-D accuracy runs (every 2nd of 180 beams).
const BEAM_STEP_2D: usize = 2;
/// The 3-D unit.
const URBAN: &str = "urban";
/// The corridor's unit.
const CORRIDOR: &str = "corridor";

struct Settings {
    seeds: Vec<u64>,
    /// Ground-truth scans per 2-D log (`None` = all).
    gt_scans: Option<usize>,
    /// Simulated indoor worlds used.
    indoor_worlds: usize,
    /// Frames of the 3-D drive.
    frames_3d: usize,
    /// Filter updates per speed measurement (tabulated / exact).
    speed_updates: (usize, usize),
    /// The 2-D models.
    models: Vec<ModelSpec>,
}

fn settings(quick: bool) -> Settings {
    if quick {
        Settings {
            seeds: (1..=3).collect(),
            gt_scans: Some(80),
            indoor_worlds: 1,
            frames_3d: 30,
            speed_updates: (30, 3),
            models: models_2d()[..5].to_vec(),
        }
    } else {
        Settings {
            seeds: (1..=10).collect(),
            gt_scans: Some(300),
            indoor_worlds: 3,
            frames_3d: 200,
            speed_updates: (200, 10),
            models: models_2d(),
        }
    }
}

/// The 2-D models; quick mode runs the first five (the decay-rate MLM / FMP pair among them).
fn models_2d() -> Vec<ModelSpec> {
    let fmp = |kind| ModelSpec {
        posterior: true,
        ..ModelSpec::tabulated(kind)
    };
    vec![
        ModelSpec::tabulated(ModelKind::DecayRate),
        fmp(ModelKind::DecayRate),
        ModelSpec::tabulated(ModelKind::Reflection),
        ModelSpec::tabulated(ModelKind::Endpoint),
        ModelSpec::exact(ModelKind::LikelihoodField),
        ModelSpec::tabulated(ModelKind::LogOdds),
        fmp(ModelKind::Reflection),
    ]
}

/// The models of the speed table.
fn speed_models() -> Vec<ModelSpec> {
    vec![
        ModelSpec::exact(ModelKind::LikelihoodField),
        ModelSpec::tabulated(ModelKind::Endpoint),
        ModelSpec::tabulated(ModelKind::DecayRate),
        ModelSpec {
            posterior: true,
            ..ModelSpec::tabulated(ModelKind::DecayRate)
        },
        ModelSpec::tabulated(ModelKind::Reflection),
        ModelSpec::exact(ModelKind::DecayRate),
        ModelSpec::exact(ModelKind::Reflection),
    ]
}

/// The 2-D accuracy runs' sensor configuration.
fn lidar_2d() -> LidarConfig {
    LidarConfig {
        beam_step: BEAM_STEP_2D,
        ..LidarConfig::default()
    }
}

/// The evaluation in stages (`--shard i/n` and `eval merge`).
pub const STAGED: Staged = Staged {
    name: NAME,
    units,
    run_unit,
    report,
};

/// The 2-D data sets in report order: the real logs, then the simulated indoor worlds.
fn planar_units(ctx: &EvalContext) -> Vec<String> {
    let worlds = ["office", "hall", "lab"].into_iter();
    ["intel", "fr079"]
        .into_iter()
        .map(str::to_owned)
        .chain(
            worlds
                .take(settings(ctx.quick).indoor_worlds)
                .map(|w| format!("indoor/{w}")),
        )
        .collect()
}

/// The 2-D data sets, the 3-D drive and the corridor.
fn units(ctx: &EvalContext) -> Result<Vec<String>> {
    let mut units = planar_units(ctx);
    units.extend([URBAN.to_owned(), CORRIDOR.to_owned()]);
    Ok(units)
}

/// A 2-D data set: real or simulated, raw log, corrected log.
struct PlanarData {
    real: bool,
    raw: PathBuf,
    corrected: PathBuf,
}

/// The files of 2-D data set `name`; `None` (with a message for a real log) when absent.
fn planar_data(ctx: &EvalContext, name: &str) -> Result<Option<PlanarData>> {
    let real_log = |raw: &str, corrected: &str| {
        let (raw, corrected) = (ctx.data(raw), ctx.data(corrected));
        if raw.exists() && corrected.exists() {
            return Some(PlanarData {
                real: true,
                raw,
                corrected,
            });
        }
        eprintln!(
            "mcl: skipping {name}: {} or {} absent",
            raw.display(),
            corrected.display()
        );
        None
    };
    let world = match name {
        "intel" => {
            return Ok(real_log(
                "carmen/raw/intel.clf.bz2",
                "carmen/corrected/intel-corrected.log.gz",
            ));
        }
        "fr079" => {
            return Ok(real_log(
                "carmen/raw/fr079.clf.bz2",
                "carmen/corrected/freiburg-079-corrected.log.gz",
            ));
        }
        _ => match name.strip_prefix("indoor/") {
            Some(world) => world,
            None => bail!("mcl: no data set {name:?}"),
        },
    };
    Ok(
        crate::generate::indoor_logs(world, ctx.quick)?.map(|(raw, corrected)| PlanarData {
            real: false,
            raw,
            corrected,
        }),
    )
}

/// What one unit measured.
#[derive(Serialize, Deserialize)]
enum UnitResult {
    /// A 2-D data set (`None`: absent).
    Planar(Option<PlanarResult>),
    /// The 3-D drive (`None`: not generated) and the note on simulated scans.
    Spatial {
        drive: Option<SpatialResult>,
        gap_note: String,
    },
    /// The corridor section: markdown and JSON.
    Corridor { markdown: String, json: Value },
}

/// One 2-D data set's results.
#[derive(Serialize, Deserialize)]
struct PlanarResult {
    name: String,
    real: bool,
    /// The data set's row of `datasets_2d`.
    problem: Value,
    /// The Gamma prior of the decay-rate FMP on this map (Sec. 8.5), as `ModelSpec::build`
    /// estimates it.
    prior: GammaPrior,
    cells: Vec<Cell>,
    /// The speed table (on the first 2-D data set present; empty on the others).
    speed: Vec<SpeedRow>,
}

/// The 3-D drive's results.
#[derive(Serialize, Deserialize)]
struct SpatialResult {
    prior: GammaPrior,
    map_rays: u64,
    frames: usize,
    cells: Vec<Cell>,
}

fn run_unit(ctx: &EvalContext, unit: &str) -> Result<Value> {
    let result = match unit {
        URBAN => UnitResult::Spatial {
            drive: run_spatial(ctx)?,
            gap_note: super::sim::gap_note(ctx).unwrap_or_else(|e| {
                format!("(How far the simulation is from real scans: {e:#})\n")
            }),
        },
        CORRIDOR => {
            let (markdown, json) = super::corridor::section(ctx)?;
            UnitResult::Corridor { markdown, json }
        }
        _ => UnitResult::Planar(run_planar(ctx, unit)?),
    };
    Ok(serde_json::to_value(result)?)
}

/// Whether `name` is the first 2-D data set present (the one the speed table runs on).
fn first_present(ctx: &EvalContext, name: &str) -> Result<bool> {
    for unit in planar_units(ctx) {
        if unit == name {
            return Ok(true);
        }
        if planar_data(ctx, &unit)?.is_some() {
            return Ok(false);
        }
    }
    Ok(false)
}

/// Every 2-D model on data set `name` (and the speed table when it is the first present).
fn run_planar(ctx: &EvalContext, name: &str) -> Result<Option<PlanarResult>> {
    let Some(data) = planar_data(ctx, name)? else {
        return Ok(None);
    };
    let s = settings(ctx.quick);
    eprintln!("mcl: loading {name}");
    let problem = planar::load(name, &data.raw, &data.corrected, s.gt_scans)?;
    let track = planar::track_config(PARTICLES_2D);
    let cells = s
        .models
        .iter()
        .map(|spec| planar::run_model(&problem, spec, lidar_2d(), &track, &s.seeds, || {}))
        .collect::<Result<Vec<_>>>()?;
    let mut speed = Vec::new();
    if first_present(ctx, name)? {
        for spec in &speed_models() {
            let exact = spec.tabulated.is_none() && spec.kind != ModelKind::LikelihoodField;
            let updates = if exact {
                s.speed_updates.1
            } else {
                s.speed_updates.0
            };
            speed.push(speed::measure(&problem, spec, updates)?);
        }
    }
    Ok(Some(PlanarResult {
        name: name.to_owned(),
        real: data.real,
        problem: json!({
            "dataset": name, "kind": page::kind(data.real),
            "raw_steps": problem.steps.len(),
            "ground_truth_scans": problem.ground_truth.len(),
            "corrected_scans": problem.corrected_scans,
            "grid": problem.stats.grid().dims(),
        }),
        prior: GammaPrior::estimate(problem.stats.cells()),
        cells,
        speed,
    }))
}

/// Every 3-D model on the simulated drive and on its campus*-style variant.
fn run_spatial(ctx: &EvalContext) -> Result<Option<SpatialResult>> {
    let root = match crate::generate::ensure("urban-kitti", ctx.quick) {
        Ok(root) => root,
        Err(error) => {
            eprintln!("mcl: skipping the 3-D drive: {error:#}");
            return Ok(None);
        }
    };
    let s = settings(ctx.quick);
    eprintln!("mcl: loading urban-kitti");
    let problem = spatial::load(&root, s.frames_3d)?;
    let failing = spatial::with_failures(&problem);
    let models = spatial::models(&problem)?;
    let mut cells = Vec::new();
    for (set, frames) in [("urban", &problem.frames), ("urban*", &failing)] {
        for (label, model) in &models {
            let cell = spatial::run_model(set, label, model.as_ref(), frames, &s.seeds, || {})?;
            cells.push(cell);
        }
    }
    Ok(Some(SpatialResult {
        prior: GammaPrior::estimate(problem.stats.cells()),
        map_rays: problem.map_rays,
        frames: problem.frames.len(),
        cells,
    }))
}

/// The page from every unit's result.
fn report(ctx: &EvalContext, results: &UnitResults) -> Result<EvalReport> {
    let units: Vec<UnitResult> = stages::decode(results)?;
    let m = page::Measured::of(units);
    let s = settings(ctx.quick);
    let markdown = page::report_markdown(ctx, &s, &m)?;
    Ok(EvalReport {
        name: "mcl",
        title: "Monte-Carlo localization per sensor model".to_owned(),
        markdown,
        json: page::json(&s, &m),
        headline: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use common::RunResult;

    fn cell(dataset: &str, model: &str, position_m: f64) -> Cell {
        Cell {
            dataset: dataset.to_owned(),
            model: model.to_owned(),
            runs: vec![
                RunResult {
                    position_m,
                    heading_rad: 0.01,
                    diverged: false,
                    updates_per_s: 100.0,
                },
                RunResult {
                    position_m: f64::NAN,
                    heading_rad: f64::NAN,
                    diverged: true,
                    updates_per_s: 90.0,
                },
            ],
        }
    }

    fn value(result: UnitResult) -> Value {
        serde_json::to_value(result).unwrap()
    }

    /// The page from known unit results: an absent data set left out, the priors in unit
    /// order, the speed rows on their map, the 3-D rows, the gap note and the corridor.
    #[test]
    fn report_from_known_units() {
        let prior = |alpha| GammaPrior { alpha, beta: 2.0 };
        let intel = PlanarResult {
            name: "intel".to_owned(),
            real: true,
            problem: json!({"dataset": "intel", "kind": "real"}),
            prior: prior(0.5),
            cells: [
                "decay-rate [table]",
                "reflection [table]",
                "endpoint [table]",
            ]
            .into_iter()
            .zip([0.1, 0.2, 0.3])
            .map(|(model, e)| cell("intel", model, e))
            .collect(),
            speed: vec![SpeedRow {
                model: "decay-rate [table]".to_owned(),
                beams: 180,
                updates_per_s: 50.0,
                build_secs: 1.5,
            }],
        };
        let urban = SpatialResult {
            prior: prior(0.25),
            map_rays: 1234,
            frames: 15,
            cells: vec![cell("urban", "decay-rate", 0.4)],
        };
        let results = vec![
            ("intel".to_owned(), value(UnitResult::Planar(Some(intel)))),
            ("fr079".to_owned(), value(UnitResult::Planar(None))),
            (
                URBAN.to_owned(),
                value(UnitResult::Spatial {
                    drive: Some(urban),
                    gap_note: "GAP NOTE\n".to_owned(),
                }),
            ),
            (
                CORRIDOR.to_owned(),
                value(UnitResult::Corridor {
                    markdown: "## Corridor\n\ntext\n".to_owned(),
                    json: json!({"runs": 1}),
                }),
            ),
        ];
        let ctx = EvalContext {
            workspace_root: crate::eval::workspace_root(),
            data_dir: std::env::temp_dir().join("raypath-mcl-test-absent-data"),
            quick: true,
            out_dir: crate::eval::workspace_root(),
        };
        let page = report(&ctx, &results).unwrap();
        let json = &page.json;
        assert_eq!(json["datasets_2d"].as_array().map(Vec::len), Some(1));
        assert_eq!(json["rows_2d"][0]["kind"], "real");
        assert_eq!(json["speed"][0]["map"], "intel");
        assert_eq!(json["settings"]["frames_3d"], 15);
        assert_eq!(json["corridor"]["runs"], 1);
        let priors = &json["decay_rate_fmp_vs_mlm"]["gamma_priors"];
        assert_eq!(priors[0]["dataset"], "intel");
        assert_eq!(priors[1]["dataset"], "urban");
        let md = &page.markdown;
        assert!(md.contains("map from the even frames (1234 rays), localization on 15 odd"));
        assert!(md.contains("GAP NOTE"));
        assert!(md.ends_with("\n## Corridor\n\ntext\n"), "{md}");
        let row = md.lines().find(|l| l.starts_with("| intel ")).unwrap();
        assert!(row.contains("| 1/2 "), "{row}");
        let order = md.lines().find(|l| l.contains("ours (2-D, real)")).unwrap();
        assert!(order.contains("D < R < E"), "{order}");
    }
}
