//! `cargo xtask eval sensor-models`: sensor models scored at the true pose and by inverse KL
//! (Schaefer 2020, Tables 7.3, 8.2, 8.3) on real and simulated data.
//!
//! Each data set is split into disjoint mapping and test scans (alternate scans: even scans
//! build the map with their reference poses, odd scans are scored), and
//! [`raypath_sensor_models::scoring`] scores every model variant: `D'` (Eq. 7.28), the
//! inverse KL over 50 positions in a 2.5 m disc (Eq. 7.29) and the ground-truth KL
//! (Eq. 8.24). Data sets:
//!
//! * **real 2-D**: every corrected Radish log in `$RAYPATH_DATA/carmen/corrected/`
//!   (0.1 m cells, `r_max` = the no-return threshold inferred by `raypath-io`);
//! * **simulated 2-D**: the corrected logs of the generated indoor worlds;
//! * **simulated 3-D**: a section of the generated urban drive (HDL-64E, KITTI layout) at
//!   0.5 m voxels, as the thesis.
//!
//! In stages: one unit per data set ([`measure`]) — `real/<log>` (scored at 0.1 m and again
//! at 0.5 m for section (e), from the same scans), `indoor/<world>` and `urban-kitti` — and
//! the page ([`report()`]) from their results alone. The indoor worlds are listed by name
//! (quick: `office`; full: the worlds of the generated set's configuration), so listing the
//! units generates nothing: the first unit that needs a generated set makes it.

mod data;
mod measure;
mod report;

use anyhow::{Result, bail};
use raypath_sensor_models::scoring::ScoreReport;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use super::stages::{self, Staged, UnitResults};
use super::{EvalContext, EvalReport};

const NAME: &str = "sensor-models";
const TITLE: &str =
    "Sensor models: likelihood at the true pose and inverse KL (Tables 7.3, 8.2, 8.3)";

/// How much work a run does.
#[derive(Clone, Copy, Debug)]
struct Plan {
    /// Real logs scored (`None`: all); quick mode takes these names.
    real_logs: Option<&'static [&'static str]>,
    /// Simulated indoor worlds scored (`None`: all).
    sim_logs: Option<&'static [&'static str]>,
    /// At most this many test scans per 2-D log (evenly spaced).
    max_test_scans_2d: Option<usize>,
    /// Every k-th beam of a 2-D test scan.
    beam_step_2d: usize,
    /// Frames of the urban drive used (the first ones).
    frames_3d: usize,
    /// Every k-th point of a 3-D mapping scan.
    map_ray_step_3d: usize,
    /// Every k-th point of a 3-D test scan.
    test_ray_step_3d: usize,
    /// At most this many 3-D test scans.
    max_test_scans_3d: usize,
}

const QUICK: Plan = Plan {
    real_logs: Some(&["intel", "aces", "freiburg-101"]),
    sim_logs: Some(&["office"]),
    max_test_scans_2d: Some(40),
    beam_step_2d: 2,
    frames_3d: 40,
    map_ray_step_3d: 4,
    test_ray_step_3d: 32,
    max_test_scans_3d: 4,
};

const FULL: Plan = Plan {
    real_logs: None,
    sim_logs: None,
    max_test_scans_2d: Some(300),
    beam_step_2d: 1,
    frames_3d: 200,
    map_ray_step_3d: 1,
    test_ray_step_3d: 8,
    max_test_scans_3d: 20,
};

fn plan(quick: bool) -> Plan {
    if quick { QUICK } else { FULL }
}

/// 3-D cell edge (the thesis's voxels).
const VOXEL_M: f64 = 0.5;
/// The real 2-D logs are scored a second time at the thesis's voxel edge (section (e)).
const COARSE_CELL_M: f64 = 0.5;
/// 3-D range limit: returns beyond count as no-returns (keeps the map box of the drive
/// section small; the HDL-64E's nominal range is about 120 m).
const MAX_RANGE_3D_M: f64 = 50.0;
/// Seed of the pose samples.
const SEED: u64 = 2020;

/// What kind of data a row is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Kind {
    /// A real Radish log.
    Real,
    /// A simulated indoor world (2-D).
    Sim2,
    /// A simulated urban drive (3-D).
    Sim3,
}

impl Kind {
    fn label(self) -> &'static str {
        match self {
            Kind::Real => "real 2-D",
            Kind::Sim2 => "simulated 2-D",
            Kind::Sim3 => "simulated 3-D",
        }
    }
}

/// The scores of one data set.
#[derive(Serialize, Deserialize)]
pub struct DataSet {
    /// Short name.
    pub name: String,
    /// Real or simulated.
    pub kind: Kind,
    /// Scans in the data set (or the section used).
    pub scans: usize,
    /// The scores.
    pub report: ScoreReport,
}

/// What one unit measured.
#[derive(Serialize, Deserialize)]
enum UnitResult {
    /// The data set scored.
    Scored(Box<Scored>),
    /// The data set's file is absent (a world the generated set does not have).
    Absent,
    /// The generated data could not be made: the note for the page.
    Unavailable(String),
}

/// The scores of one data set; a real log also at [`COARSE_CELL_M`] (section (e)).
#[derive(Serialize, Deserialize)]
struct Scored {
    set: DataSet,
    coarse: Option<ScoreReport>,
    /// Time of the unit.
    seconds: f64,
}

/// The evaluation in stages: one unit per data set (`--shard i/n` and `eval merge`).
pub const STAGED: Staged = Staged {
    name: NAME,
    units,
    run_unit,
    report,
};

/// The data sets in report order: the real logs (sorted), the indoor worlds (sorted), the
/// urban drive.
fn units(ctx: &EvalContext) -> Result<Vec<String>> {
    let plan = plan(ctx.quick);
    let mut units: Vec<String> = measure::real_logs(ctx, &plan)
        .into_iter()
        .map(|name| format!("real/{name}"))
        .collect();
    units.extend(
        measure::indoor_worlds(&plan)
            .into_iter()
            .map(|w| format!("indoor/{w}")),
    );
    units.push(URBAN.into());
    Ok(units)
}

/// The unit of the simulated urban drive.
const URBAN: &str = "urban-kitti";

/// Scores one data set.
fn run_unit(ctx: &EvalContext, unit: &str) -> Result<Value> {
    let plan = plan(ctx.quick);
    let result = if let Some(name) = unit.strip_prefix("real/") {
        measure::real_log(ctx, &plan, name)?
    } else if let Some(world) = unit.strip_prefix("indoor/") {
        measure::indoor_world(ctx, &plan, world)?
    } else if unit == URBAN {
        measure::urban(ctx, &plan)?
    } else {
        bail!("no unit {unit:?} in {NAME}");
    };
    Ok(serde_json::to_value(result)?)
}

/// The page from every data set's result.
fn report(ctx: &EvalContext, results: &UnitResults) -> Result<EvalReport> {
    let plan = plan(ctx.quick);
    let units: Vec<UnitResult> = stages::decode(results)?;
    let mut notes = Vec::new();
    if !results.iter().any(|(unit, _)| unit.starts_with("real/")) {
        notes.push(format!(
            "No corrected CARMEN logs in `{}` (set RAYPATH_DATA): the real rows are missing.",
            measure::real_dir(ctx).display()
        ));
    }
    let (mut sets, mut coarse, mut seconds) = (Vec::new(), Vec::new(), 0.0);
    for unit in units {
        match unit {
            UnitResult::Scored(scored) => {
                let Scored {
                    set,
                    coarse: at_coarse,
                    seconds: s,
                } = *scored;
                if let Some(report) = at_coarse {
                    coarse.push(DataSet {
                        name: set.name.clone(),
                        kind: set.kind,
                        scans: set.scans,
                        report,
                    });
                }
                sets.push(set);
                seconds += s;
            }
            UnitResult::Absent => {}
            UnitResult::Unavailable(note) if !notes.contains(&note) => notes.push(note),
            UnitResult::Unavailable(_) => {}
        }
    }
    let plan_text = plan_text(&plan, ctx.quick);
    let mut markdown = report::markdown(&sets, &plan_text, &notes)?;
    markdown.push_str(&report::coarse_section(&coarse, COARSE_CELL_M)?);
    let json = json!({
        "quick": ctx.quick,
        "seed": SEED,
        "seconds": seconds,
        "plan": plan_text,
        "notes": notes,
        "data_sets": sets.iter().map(|s| json!({
            "name": s.name,
            "kind": s.kind.label(),
            "scans": s.scans,
            "report": s.report,
        })).collect::<Vec<_>>(),
        "agreement": report::agreement_json(&sets),
        "real_2d_at_0_5_m": {
            "cell_m": COARSE_CELL_M,
            "data_sets": coarse.iter().map(|s| json!({
                "name": s.name,
                "scans": s.scans,
                "report": s.report,
            })).collect::<Vec<_>>(),
            "agreement": report::agreement_json(&coarse),
        },
    });
    Ok(EvalReport {
        name: NAME,
        title: TITLE.to_owned(),
        markdown,
        json,
        headline: None,
    })
}

fn plan_text(plan: &Plan, quick: bool) -> String {
    let real = plan
        .real_logs
        .map_or("every corrected log".to_owned(), |n| n.join(", "));
    let sim = plan
        .sim_logs
        .map_or("every indoor world".to_owned(), |n| n.join(", "));
    format!(
        "{} run. 2-D ({real}; simulated: {sim}): 0.1 m cells, alternate split (even scans map, \
         odd scans are scored), at most {} evenly spaced test scans per log, {}. \
         3-D (urban-kitti, frames 0–{}): {VOXEL_M} m voxels, r_max {MAX_RANGE_3D_M} m, even \
         frames map ({}), at most {} odd frames scored ({}). 50 poses \
         in a 2.5 m disc per test scan, σ = 0.05 m, seed {SEED}.",
        if quick { "Quick" } else { "Full" },
        plan.max_test_scans_2d
            .map_or("all".to_owned(), |n| n.to_string()),
        every(plan.beam_step_2d, "beam"),
        plan.frames_3d.saturating_sub(1),
        every(plan.map_ray_step_3d, "point"),
        plan.max_test_scans_3d,
        every(plan.test_ray_step_3d, "point"),
    )
}

/// "every beam", "every 2nd beam", "every 8th point", …
fn every(k: usize, noun: &str) -> String {
    match k {
        0 | 1 => format!("every {noun}"),
        2 => format!("every 2nd {noun}"),
        3 => format!("every 3rd {noun}"),
        k => format!("every {k}th {noun}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scored(name: &str, kind: Kind, coarse: bool) -> (String, Value) {
        let set = report::tests::data_set(name, kind);
        let coarse = coarse.then(|| set.report.clone());
        let unit = match kind {
            Kind::Real => format!("real/{name}"),
            Kind::Sim2 => format!("indoor/{name}"),
            Kind::Sim3 => URBAN.to_owned(),
        };
        let result = UnitResult::Scored(Box::new(Scored {
            set,
            coarse,
            seconds: 2.5,
        }));
        (unit, serde_json::to_value(result).unwrap())
    }

    /// The page from known units: data sets in unit order, the real log also at 0.5 m, an
    /// absent world left out, the note of an unavailable set once, the JSON keys of a whole
    /// run.
    #[test]
    fn report_from_known_units() {
        let dir = tempfile::tempdir().unwrap();
        let ctx = EvalContext::scratch(dir.path());
        let unavailable = UnitResult::Unavailable("Simulated indoor worlds unavailable: x.".into());
        let results = vec![
            scored("intel", Kind::Real, true),
            (
                "indoor/hall".to_owned(),
                serde_json::to_value(UnitResult::Absent).unwrap(),
            ),
            (
                "indoor/lab".to_owned(),
                serde_json::to_value(&unavailable).unwrap(),
            ),
            (
                "indoor/office".to_owned(),
                serde_json::to_value(&unavailable).unwrap(),
            ),
            scored("urban-kitti", Kind::Sim3, false),
        ];
        let page = report(&ctx, &results).unwrap();
        let md = &page.markdown;
        assert!(md.contains("**Workload.** Quick run."), "{md}");
        assert_eq!(
            md.matches("*Note:* Simulated indoor worlds unavailable: x.")
                .count(),
            1,
            "{md}"
        );
        assert!(!md.contains("No corrected CARMEN logs"));
        assert!(md.lines().any(|l| l.starts_with("| intel ")));
        assert!(md.lines().any(|l| l.starts_with("| urban-kitti ")));
        let mut keys: Vec<&String> = page.json.as_object().unwrap().keys().collect();
        keys.sort();
        assert_eq!(
            keys,
            [
                "agreement",
                "data_sets",
                "notes",
                "plan",
                "quick",
                "real_2d_at_0_5_m",
                "seconds",
                "seed"
            ]
        );
        let sets = page.json["data_sets"].as_array().unwrap();
        assert_eq!(sets.len(), 2);
        assert_eq!(sets[0]["name"], "intel");
        assert_eq!(sets[1]["kind"], "simulated 3-D");
        assert_eq!(page.json["seconds"], 5.0);
        let coarse = &page.json["real_2d_at_0_5_m"];
        assert_eq!(coarse["data_sets"].as_array().unwrap().len(), 1);
        assert_eq!(coarse["cell_m"], COARSE_CELL_M);

        let without_real = report(&ctx, &results[1..]).unwrap();
        assert!(
            without_real.json["notes"][0]
                .as_str()
                .unwrap()
                .starts_with("No corrected CARMEN logs in")
        );
    }
}
