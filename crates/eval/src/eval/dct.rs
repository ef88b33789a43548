//! `cargo xtask eval dct`: continuous DCT decay-rate maps against grid maps with as many
//! parameters on the real CARMEN logs (Schaefer 2020, Tables 9.2–9.4, Fig. 9.1).
//!
//! Per log: a seeded 10 m × 10 m patch among the most densely traversed ones, 10⁴ mapping
//! rays and 500 held-back rays drawn with a seed ([`raypath_dct_map::experiment`]), the
//! 0.05 m ground-truth grid from the mapping rays, and at each of 10², 13², 20², 29², 40²
//! parameters a DCT map and a grid map. Table 9.4 times the fit from 500 rays (the thesis'
//! timing set) and from 10⁴ rays; both solvers are timed side by side.
//!
//! The other two baselines of Sec. 9.5.2 have the same memory: a GPOM with n² training points
//! and a Hilbert map with n² Nyström components ([`raypath_dct_map::baselines`]), trained on
//! points sampled along the same mapping rays and scored on the held-back rays through a
//! 0.05 m raster (Table 9.3's DCT − GPOM and DCT − HM columns; their fit times beside Table
//! 9.4's t_GPOM and t_HM). As a control, the DCT map is also scored through that raster.
//! The headline (real logs) goes to the README's headline table.
//!
//! In stages: one unit per log ([`measure`]), the page ([`report()`]) from their results.

use std::path::PathBuf;

use anyhow::Result;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use super::stages::{self, Staged, UnitResults, float};
use super::{EvalContext, EvalReport, comparable};

mod measure;
mod report;
mod thesis;

use report::{headline, report_markdown};

const NAME: &str = "dct";
const PATCH_M: f64 = 10.0;
const MAPPING_RAYS: usize = 10_000;
const HELD_BACK: usize = 500;
const TIMING_RAYS: usize = 500;
const SEED: u64 = 9;
const HEAVY_FRACTION: f64 = 0.75;
const SIZES: [usize; 5] = [10, 13, 20, 29, 40];
const QUICK_SIZES: [usize; 2] = [13, 40];

/// One (log, size) result.
#[derive(Clone, Serialize, Deserialize)]
struct Cell {
    log: String,
    size: usize,
    #[serde(with = "float")]
    rmse: f64,
    #[serde(with = "float")]
    grid_rmse: f64,
    #[serde(with = "float")]
    ll: f64,
    #[serde(with = "float")]
    grid_ll: f64,
    #[serde(with = "float")]
    time_s: f64,
    #[serde(with = "float")]
    grid_time_s: f64,
    iterations: usize,
    #[serde(with = "float")]
    time500_s: f64,
    #[serde(with = "float")]
    grid_time500_s: f64,
    #[serde(with = "float")]
    lbfgs_time_s: f64,
    #[serde(with = "float")]
    lbfgs_ll: f64,
    #[serde(with = "float")]
    newton_fit_s: f64,
    #[serde(with = "float")]
    newton_train_ll: f64,
    #[serde(with = "float")]
    worst_ray_ll: f64,
    #[serde(with = "float")]
    grid_worst_ray_ll: f64,
    gpom: BaselineCell,
    hm: BaselineCell,
    /// The DCT map scored through the same raster as the baselines (`o = 1 − e^{−λ·0.05}`).
    #[serde(with = "float")]
    dct_raster_ll: f64,
}

/// One occupancy baseline at one (log, size).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct BaselineCell {
    /// Held-back log-likelihood on the 0.05 m raster.
    #[serde(with = "float")]
    ll: f64,
    /// Fit time from the 10⁴ mapping rays (s).
    #[serde(with = "float")]
    fit_s: f64,
    /// Raster prediction time (s).
    #[serde(with = "float")]
    raster_s: f64,
    /// Fit time from the 500 timing rays (s).
    #[serde(with = "float")]
    fit500_s: f64,
    /// What the fit chose (JSON).
    report: Value,
}

/// The evaluation in stages: one unit per log (`--shard i/n` and `eval merge`).
pub const STAGED: Staged = Staged {
    name: NAME,
    units,
    run_unit,
    report,
};

const TITLE: &str = "Continuous DCT decay-rate maps against grid maps (Tables 9.2-9.4)";
/// The corrected logs' file names end so.
const SUFFIX: &str = "-corrected.log.gz";

fn log_dir(ctx: &EvalContext) -> PathBuf {
    ctx.data("carmen/corrected")
}

fn sizes(ctx: &EvalContext) -> &'static [usize] {
    if ctx.quick { &QUICK_SIZES } else { &SIZES }
}

/// The corrected logs by name, sorted (quick: `aces` and `intel`, the two smallest, keep CI
/// fast).
fn units(ctx: &EvalContext) -> Result<Vec<String>> {
    let mut logs: Vec<String> = std::fs::read_dir(log_dir(ctx))
        .map(|d| {
            d.flatten()
                .filter_map(|e| {
                    let name = e.file_name().to_string_lossy().into_owned();
                    name.strip_suffix(SUFFIX).map(str::to_owned)
                })
                .collect()
        })
        .unwrap_or_default();
    logs.sort();
    if ctx.quick {
        logs.retain(|n| n == "aces" || n == "intel");
    }
    Ok(logs)
}

/// One log's result: its data, its cells and the machine's load around the run.
#[derive(Serialize, Deserialize)]
struct LogResult {
    info: Value,
    cells: Vec<Cell>,
    /// Load average (1 min) at the start and at the end of the unit.
    load: (String, String),
}

/// Every size on one log (the Fig. 9.1 pictures on `intel`).
fn run_unit(ctx: &EvalContext, log: &str) -> Result<Value> {
    let load_before = load_average();
    let path = log_dir(ctx).join(format!("{log}{SUFFIX}"));
    let fig_dir = match log {
        "intel" => Some(ctx.figure_dir(NAME)?),
        _ => None,
    };
    let (cells, info) = measure::run_log(&path, log, sizes(ctx), fig_dir.as_deref())?;
    Ok(serde_json::to_value(LogResult {
        info,
        cells,
        load: (load_before, load_average()),
    })?)
}

/// The page from every log's result.
fn report(ctx: &EvalContext, results: &UnitResults) -> Result<EvalReport> {
    let logs: Vec<LogResult> = stages::decode(results)?;
    let (Some(first), Some(last)) = (logs.first(), logs.last()) else {
        return Ok(skipped(ctx));
    };
    let mut md = format!(
        "Load average (1 min) of the machine: {} at the start, {} at the end — other \
         evaluations ran at the same time, so absolute times are inflated; ratios within one row \
         were measured side by side.\n\n",
        first.load.0, last.load.1
    );
    let cells: Vec<Cell> = logs.iter().flat_map(|l| l.cells.clone()).collect();
    let infos: Vec<Value> = logs.iter().map(|l| l.info.clone()).collect();
    let sizes = sizes(ctx);
    md.push_str(&report_markdown(ctx, &cells, &infos, sizes)?);
    let json_cells: Vec<Value> = cells.iter().map(cell_json).collect();
    Ok(EvalReport {
        name: NAME,
        title: TITLE.into(),
        markdown: md,
        json: json!({ "logs": infos, "results": json_cells, "quick": ctx.quick, "threads": rayon::current_num_threads() }),
        headline: headline(&cells, sizes),
    })
}

/// The page without logs.
fn skipped(ctx: &EvalContext) -> EvalReport {
    EvalReport {
        name: NAME,
        title: TITLE.into(),
        markdown: format!(
            "No corrected CARMEN logs under `{}` — skipped.\n",
            log_dir(ctx).display()
        ),
        json: json!({ "status": "skipped: no data" }),
        headline: None,
    }
}

fn cell_json(c: &Cell) -> Value {
    json!({
        "log": c.log, "size": c.size, "rmse_p_ref": c.rmse, "grid_rmse_p_ref": c.grid_rmse,
        "log_likelihood": c.ll, "grid_log_likelihood": c.grid_ll, "time_s": c.time_s,
        "grid_time_s": c.grid_time_s, "iterations": c.iterations, "time_500_s": c.time500_s,
        "grid_time_500_s": c.grid_time500_s, "lbfgs_fit_s": c.lbfgs_time_s,
        "lbfgs_train_log_likelihood": c.lbfgs_ll, "newton_fit_s": c.newton_fit_s,
        "newton_train_log_likelihood": c.newton_train_ll,
        "worst_held_back_ray_log_likelihood": c.worst_ray_ll,
        "grid_worst_held_back_ray_log_likelihood": c.grid_worst_ray_ll,
        "gpom": baseline_json(&c.gpom), "hilbert_map": baseline_json(&c.hm),
        "dct_on_baseline_raster_log_likelihood": c.dct_raster_ll,
    })
}

fn baseline_json(b: &BaselineCell) -> Value {
    json!({
        "held_back_log_likelihood": b.ll, "fit_s": b.fit_s, "raster_s": b.raster_s,
        "fit_500_s": b.fit500_s, "fit": b.report,
    })
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_owned))
        .unwrap_or_else(|| "n/a".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn baseline(ll: f64) -> BaselineCell {
        BaselineCell {
            ll,
            fit_s: 0.5,
            raster_s: 0.1,
            fit500_s: 0.05,
            report: json!({"length_scale_m": 0.5, "noise_std": 0.3, "iterations": 20}),
        }
    }

    /// A cell whose worst held-back ray is impossible under the grid map (−∞).
    fn cell(log: &str, size: usize) -> Cell {
        Cell {
            log: log.to_owned(),
            size,
            rmse: 0.2,
            grid_rmse: 0.25,
            ll: -100.0,
            grid_ll: -150.0,
            time_s: 0.1,
            grid_time_s: 0.001,
            iterations: 4,
            time500_s: 0.01,
            grid_time500_s: 0.0001,
            lbfgs_time_s: 0.2,
            lbfgs_ll: -101.0,
            newton_fit_s: 0.05,
            newton_train_ll: -100.0,
            worst_ray_ll: -5.0,
            grid_worst_ray_ll: f64::NEG_INFINITY,
            gpom: baseline(-20_000.0),
            hm: baseline(f64::NAN),
            dct_raster_ll: -110.0,
        }
    }

    fn unit(log: &str, load: (&str, &str)) -> (String, Value) {
        let result = LogResult {
            info: json!({"log": log, "patch": [1.0, 2.0, 10.0, 10.0], "mapping_rays": 10000,
                         "mapping_hits": 9000, "held_back_rays": 500, "truth_observed_cells": 7}),
            cells: vec![cell(log, 13), cell(log, 40)],
            load: (load.0.to_owned(), load.1.to_owned()),
        };
        (log.to_owned(), serde_json::to_value(result).unwrap())
    }

    /// The page from two logs' results: the load line from the first and the last unit,
    /// non-finite figures through the unit results, every cell in the JSON.
    #[test]
    fn report_from_known_logs() {
        let ctx = EvalContext {
            workspace_root: crate::eval::workspace_root(),
            data_dir: std::env::temp_dir().join("raypath-dct-test-absent-data"),
            quick: true,
            out_dir: crate::eval::workspace_root(),
        };
        let results = vec![unit("aces", ("0.5", "0.7")), unit("intel", ("0.8", "0.9"))];
        let page = report(&ctx, &results).unwrap();
        assert!(
            page.markdown.starts_with(
                "Load average (1 min) of the machine: 0.5 at the start, 0.9 at the end"
            )
        );
        let row = page
            .markdown
            .lines()
            .find(|l| l.starts_with("| aces "))
            .unwrap();
        assert!(row.contains("| 1.0, 2.0 "), "{row}");
        assert!(page.markdown.contains("## Fig. 9.1"));
        let cells = page.json["results"].as_array().unwrap();
        assert_eq!(cells.len(), 4);
        assert_eq!(cells[3]["log"], "intel");
        assert!(cells[0]["grid_worst_held_back_ray_log_likelihood"].is_null());
        assert!(page.headline.unwrap().starts_with("Real CARMEN logs (2,"));
        let skipped = report(&ctx, &[]).unwrap();
        assert!(
            skipped
                .markdown
                .starts_with("No corrected CARMEN logs under")
        );
        assert_eq!(skipped.json["status"], "skipped: no data");
    }
}
