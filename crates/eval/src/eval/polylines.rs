//! `cargo xtask eval polylines`: the polyline benchmark of Schaefer (2020), chapter 10.
//!
//! * Real: seeded-random scans from every corrected CARMEN log (20 per log; the thesis used
//!   13 logs, 10 are available here), `l_max` = 1 m.
//! * Simulated: 260 random-polygon scans from `raypath-sim` (360 rays, σ_angle 0.2°,
//!   σ_radial 0.03 m; the same generator and seed as `datasets/generated/polygons`, simulated
//!   in memory), `l_max` = ∞ like the reference implementation.
//! * For J ∈ {10, 20, 30, 40, 50}: RMSE, f, a (both denominators), IoU and the time per scan
//!   for VVL, IEF, SAM, PLE, PLE+ (Levenberg–Marquardt, the crate default) and PLE+ with
//!   Nelder–Mead (the thesis solver). Scans run in parallel (rayon), each extraction on one
//!   thread, timed alone.
//!
//! In stages: one unit per corrected log and one per block of [`SIM_BLOCK`] simulated scans
//! ([`measure`]); the page ([`page`]) from their results.

mod measure;
mod page;
mod plot;
mod stats;

use std::ops::Range;
use std::path::PathBuf;

use anyhow::{Context, Result};
use raypath_polylines::svg::scan_svg;
use raypath_polylines::{Method, Optimizer, PolylineConfig, extract};
use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::stages::{self, Staged, UnitResults};
use super::{EvalContext, EvalReport};
use measure::Results;

const JS: [usize; 5] = [10, 20, 30, 40, 50];
const NAME: &str = "polylines";
/// Each extraction runs this often; its time is the fastest run.
const TIMING_RUNS: usize = 3;
/// Label of the Nelder–Mead PLE+ variant.
const NM: &str = "PLE+ (NM)";
/// Simulated scans per unit.
const SIM_BLOCK: usize = 20;
/// The corrected logs' file names end so.
const SUFFIX: &str = "-corrected.log.gz";
/// Prefix of the units of simulated scans (`polygons-<first>-<last>`).
const SIM_PREFIX: &str = "polygons-";

/// One extractor as evaluated.
#[derive(Clone, Copy)]
struct Variant {
    label: &'static str,
    method: Method,
    optimizer: Optimizer,
    color: &'static str,
}

const VARIANTS: [Variant; 6] = [
    Variant {
        label: "VVL",
        method: Method::Vvl,
        optimizer: Optimizer::LEVENBERG_MARQUARDT,
        color: "#2ca02c",
    },
    Variant {
        label: "IEF",
        method: Method::Ief,
        optimizer: Optimizer::LEVENBERG_MARQUARDT,
        color: "#ff7f0e",
    },
    Variant {
        label: "SAM",
        method: Method::Sam,
        optimizer: Optimizer::LEVENBERG_MARQUARDT,
        color: "#9467bd",
    },
    Variant {
        label: "PLE",
        method: Method::Ple,
        optimizer: Optimizer::LEVENBERG_MARQUARDT,
        color: "#1f77b4",
    },
    Variant {
        label: "PLE+",
        method: Method::PlePlus,
        optimizer: Optimizer::LEVENBERG_MARQUARDT,
        color: "#d62728",
    },
    Variant {
        label: "PLE+ (NM)",
        method: Method::PlePlus,
        optimizer: Optimizer::NELDER_MEAD,
        color: "#8c564b",
    },
];

/// The evaluation in stages (`--shard i/n` and `eval merge`).
pub const STAGED: Staged = Staged {
    name: NAME,
    units,
    run_unit,
    report,
};

/// Real scans per log and simulated scans in all.
fn counts(ctx: &EvalContext) -> (usize, usize) {
    if ctx.quick { (3, 40) } else { (20, 260) }
}

fn log_dir(ctx: &EvalContext) -> PathBuf {
    ctx.data("carmen/corrected")
}

/// The corrected logs by name, sorted, then the blocks of simulated scans.
fn units(ctx: &EvalContext) -> Result<Vec<String>> {
    let mut units: Vec<String> = std::fs::read_dir(log_dir(ctx))
        .map(|entries| {
            entries
                .flatten()
                .filter_map(|e| {
                    let name = e.file_name().to_string_lossy().into_owned();
                    name.strip_suffix(SUFFIX).map(str::to_owned)
                })
                .collect()
        })
        .unwrap_or_default();
    units.sort();
    let sims = counts(ctx).1;
    for first in (0..sims).step_by(SIM_BLOCK) {
        let last = (first + SIM_BLOCK).min(sims) - 1;
        units.push(format!("{SIM_PREFIX}{first}-{last}"));
    }
    Ok(units)
}

/// The simulated scans of a unit `polygons-<first>-<last>`; `None` for a log.
fn sim_range(unit: &str) -> Option<Range<usize>> {
    let (first, last) = unit.strip_prefix(SIM_PREFIX)?.split_once('-')?;
    Some(first.parse().ok()?..last.parse::<usize>().ok()? + 1)
}

/// One unit's result.
#[derive(Serialize, Deserialize)]
struct UnitResult {
    /// The log: name, scans sampled, beams per scan (`None`: simulated scans).
    log: Option<(String, usize, usize)>,
    /// Rays of all scans.
    rays: usize,
    /// Where each scan comes from (`intel scan 12`, `polygon 3 (n = 12)`).
    sources: Vec<String>,
    /// The source of the real example picture, when this unit drew it.
    example: Option<String>,
    results: Results,
}

/// Extracts with every method at every J from one log's seeded-random scans (`l_max` =
/// 1 m) or one block of simulated scans (`l_max` = ∞).
fn run_unit(ctx: &EvalContext, unit: &str) -> Result<Value> {
    let (per_log, _) = counts(ctx);
    let (samples, log, max_edge_m) = match sim_range(unit) {
        Some(range) => (measure::simulated_samples(range)?, None, f64::INFINITY),
        None => {
            let path = log_dir(ctx).join(format!("{unit}{SUFFIX}"));
            let (samples, beams) = measure::real_samples(&path, unit, per_log)?;
            let log = (unit.to_owned(), samples.len(), beams);
            (samples, Some(log), 1.0)
        }
    };
    eprintln!("{NAME}: {unit}: {} scans", samples.len());
    let results = measure::evaluate(&samples, max_edge_m)?;
    // The first log's first scan is the real example.
    let first = units(ctx)?.first().is_some_and(|u| u == unit);
    let example = match samples.first() {
        Some(sample) if log.is_some() && first => Some(real_example(ctx, sample)?),
        _ => None,
    };
    Ok(serde_json::to_value(UnitResult {
        log,
        rays: samples.iter().map(|s| s.scan.len()).sum(),
        sources: samples.into_iter().map(|s| s.source).collect(),
        example,
        results,
    })?)
}

/// PLE+ with J = 20 on `sample`, drawn as `example-real.svg`; returns its source.
fn real_example(ctx: &EvalContext, sample: &measure::Sample) -> Result<String> {
    let map = extract(&sample.scan, &PolylineConfig::new(Method::PlePlus, 20))?;
    page::write_figure(
        &ctx.figure_dir(NAME)?,
        "example-real.svg",
        &scan_svg(&sample.scan, &map, 600.0),
    )?;
    Ok(sample.source.clone())
}

/// The real and the simulated scans' results, joined over the units.
struct Joined {
    /// Logs used: name, scans sampled, beams per scan.
    logs: Vec<(String, usize, usize)>,
    /// Real scans and their rays.
    real_scans: usize,
    real_rays: usize,
    /// `None` without real scans.
    real: Option<Results>,
    /// The source of the real example picture.
    real_example: Option<String>,
    sim: Results,
    /// Where each simulated scan comes from, in order (index = polygon number).
    sim_sources: Vec<String>,
}

impl Joined {
    fn of(units: &[UnitResult]) -> Self {
        let (real, sim): (Vec<&UnitResult>, Vec<&UnitResult>) =
            units.iter().partition(|u| u.log.is_some());
        let real_scans = real.iter().map(|u| u.sources.len()).sum();
        Self {
            logs: real.iter().filter_map(|u| u.log.clone()).collect(),
            real_scans,
            real_rays: real.iter().map(|u| u.rays).sum(),
            real: (real_scans > 0)
                .then(|| stats::join(&real.iter().map(|u| &u.results).collect::<Vec<_>>())),
            real_example: real.iter().find_map(|u| u.example.clone()),
            sim: stats::join(&sim.iter().map(|u| &u.results).collect::<Vec<_>>()),
            sim_sources: sim.iter().flat_map(|u| u.sources.clone()).collect(),
        }
    }
}

/// The page from every unit's results.
fn report(ctx: &EvalContext, results: &UnitResults) -> Result<EvalReport> {
    let units: Vec<UnitResult> = stages::decode(results)?;
    let joined = Joined::of(&units);
    let (per_log, _) = counts(ctx);
    let fig_dir = ctx.figure_dir(NAME)?;
    page::page(ctx, &joined, per_log, &fig_dir).context("writing the polylines page")
}

#[cfg(test)]
mod tests {
    use super::*;
    use measure::{Outcome, simulated_sample};

    /// `scans` outcomes per variant and J: RMSE `rmse[k]` on scan k, time 1 ms per variant
    /// index, areas on simulated scans only.
    fn results(rmse: &[f64], simulated: bool) -> Results {
        let area = if simulated { 0.1 } else { f64::NAN };
        (0..VARIANTS.len())
            .map(|v| {
                (0..JS.len())
                    .map(|_| {
                        rmse.iter()
                            .map(|&r| Outcome {
                                rmse_m: r,
                                f: 0.9,
                                a_gt: area,
                                a_printed: area,
                                iou: area,
                                secs: (v + 1) as f64 * 1e-3,
                                vertices: 10,
                            })
                            .collect()
                    })
                    .collect()
            })
            .collect()
    }

    /// The page from one log's and one block of simulated scans' results.
    #[test]
    fn report_from_known_results() {
        let dir = tempfile::tempdir().unwrap();
        let ctx = EvalContext::scratch(dir.path());
        let log = UnitResult {
            log: Some(("intel".to_owned(), 2, 180)),
            rays: 2 * 180,
            sources: vec!["intel scan 3".to_owned(), "intel scan 9".to_owned()],
            example: Some("intel scan 3".to_owned()),
            results: results(&[0.01, 0.03], false),
        };
        let sources: Vec<String> = (0..2)
            .map(|i| simulated_sample(i).unwrap().source)
            .collect();
        let sim = UnitResult {
            log: None,
            rays: 2 * 360,
            sources: sources.clone(),
            example: None,
            results: results(&[0.02, 0.04], true),
        };
        let units = vec![
            ("intel".to_owned(), serde_json::to_value(log).unwrap()),
            (
                "polygons-0-1".to_owned(),
                serde_json::to_value(sim).unwrap(),
            ),
        ];
        let page = report(&ctx, &units).unwrap();
        let md = &page.markdown;
        assert!(
            md.contains("- Real: 2 scans, 3 seeded-random scans"),
            "{md}"
        );
        assert!(
            md.contains("intel (2 × 180 beams); 180 rays per scan"),
            "{md}"
        );
        assert!(md.contains("- Simulated: 2 random polygons"), "{md}");
        assert!(
            md.contains("Example: PLE+ with J = 20 on intel scan 3"),
            "{md}"
        );
        assert!(
            md.contains(&format!("on simulated {}.", sources[0]))
                || md.contains(&format!("on simulated {}.", sources[1]))
        );
        assert!(
            md.contains("- real, J = 10: VVL (20.0 mm) < IEF (20.0 mm)"),
            "{md}"
        );
        assert!(
            dir.path()
                .join("docs/results/polylines/example-sim.svg")
                .is_file()
        );
        let json = &page.json;
        assert_eq!(json["simulated"]["scans"], 2);
        assert_eq!(json["real"]["logs"][0]["beams"], 180);
        // PLE is the fourth variant: 4 ms per scan on the real scans.
        assert_eq!(json["speed_j20"]["ple_mean_s"], 4e-3);
        assert_eq!(sim_range("polygons-20-39"), Some(20..40));
        assert_eq!(sim_range("intel"), None);
    }
}
