//! The 1-D corridor simulation of Schaefer ch. 8 (Sec. 8.5.1): belief at the
//! true pose for MLM, FMP with uniform prior and FMP with conjugate prior; a section of
//! `eval mcl`.
//!
//! The world, the mapping draws and the localization draws come from
//! [`raypath_sim::corridor`] (its module docs record what one measurement is and how the
//! random streams are split). This section adds the localization:
//!
//! * **Filter**: an exact Bayes filter over the 100 voxels. The belief starts uniform; at
//!   iteration `t = 0 … 99` the robot is in voxel `t`. From `t = 1` on the belief is shifted by
//!   one voxel (known motion; the mass pushed past the last voxel is dropped and the rest
//!   renormalized — the thesis leaves the border open), then multiplied by the likelihood of
//!   the observation under each hypothesis `x`, evaluated with the map of voxel `x`, and
//!   normalized.
//! * **ρ** = mean over the 100 iterations of the belief at the true voxel.
//! * **Likelihoods** (Sec. 8.4.5): REF FMP `l = (H+α)^δ (M+β)^{1−δ} / (H+α+M+β)` (Eq. 8.22),
//!   REF MLM `l = μ^δ (1−μ)^{1−δ}`, DEC FMP `l = ((R+β)/(R+β+r))^{H+α} ((H+α)/(R+β+r))^δ`,
//!   DEC MLM `l = λ^δ e^{−λ r}`.
//! * **MLM zero likelihoods** (the thesis does not say how its MLM survives a zero): MLM clamps the ML values to `μ ∈ [1e-12, 1 − 1e-12]`
//!   and `λ ≥ 1e-12 /m` (a zero likelihood stays practically zero, as in the thesis's MLM,
//!   but the filter stays defined). MLM-clamped, reported beside, uses the clamps of the
//!   crate's models (which floor λ and μ so that an unhit voxel does not give −∞): `μ ∈ [1e-3, 1 − 1e-3]` ([`ReflectionConfig`] default) and
//!   `λ ≥ 1e-3 /m` ([`DecayRateConfig`] default). How often the unclamped ML likelihood at
//!   the true voxel was zero is reported.
//! * **Priors**: FMP-uniform uses Beta(1, 1) (REF) and the flat Gamma(1, 0) (DEC, improper;
//!   every voxel is visited at least once, so `R + β > 0`); FMP-conjugate estimates α, β per
//!   run by the method of moments over the ML map ([`BetaPrior::estimate`],
//!   [`GammaPrior::estimate`]; Sec. 8.5, over the voxels with a finite ML value).
//! * **Test**: one-tailed paired t-test of `ρ_conj − ρ_other` over the runs (H1: mean > 0).

use anyhow::Result;
use rayon::prelude::*;
use raypath_sensor_models::{BetaPrior, CellStats, DecayRateConfig, GammaPrior, ReflectionConfig};
use raypath_sim::corridor::{
    CorridorModel, CorridorWorld, MapStatistics, VoxelObservation, run_seed, streams,
};
use raypath_sim::rng::stream;
use serde_json::json;

use super::{EvalContext, comparable};
use crate::table::{Table, fmt_num};

/// Numbers of mapping visits per voxel (thesis Fig. 8.2).
const N_VISITS: [u32; 10] = [1, 2, 3, 4, 5, 10, 20, 50, 100, 200];
/// Runs per `n` (thesis: 10 000).
const RUNS_FULL: usize = 10_000;
/// Runs per `n` with `--quick`.
const RUNS_QUICK: usize = 500;
/// Seed of the runs (the data-set default).
const SEED: u64 = raypath_sim::datasets::DEFAULT_SEED;
/// Clamp of the ML values of the thesis-like MLM (a zero likelihood stays practically zero but
/// the filter stays defined).
const STRICT_FLOOR: f64 = 1e-12;
/// Significance level of the thesis statement ("with probability > 0.9999").
const ALPHA: f64 = 1e-4;

/// The three localization algorithms.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Algorithm {
    /// ML map, μ clamped to [1e-12, 1 − 1e-12] / λ ≥ 1e-12: a zero likelihood stays
    /// (practically) zero — the thesis's MLM.
    Mlm,
    /// ML map with the crate's model clamps (1e-3).
    MlmClamped,
    FmpUniform,
    FmpConjugate,
}

const ALGORITHMS: [Algorithm; 4] = [
    Algorithm::Mlm,
    Algorithm::MlmClamped,
    Algorithm::FmpUniform,
    Algorithm::FmpConjugate,
];

impl Algorithm {
    fn name(self) -> &'static str {
        match self {
            Algorithm::Mlm => "MLM",
            Algorithm::MlmClamped => "MLM-clamped",
            Algorithm::FmpUniform => "FMP-uniform",
            Algorithm::FmpConjugate => "FMP-conjugate",
        }
    }
}

/// Per-voxel likelihood parameters of one algorithm on one map.
enum VoxelLikelihood {
    /// Reflection: probability of a hit per voxel.
    Bernoulli(Vec<f64>),
    /// Decay-rate ML: λ per voxel.
    Exponential(Vec<f64>),
    /// Decay-rate posterior: (shape a = H + α, rate b = R + β) per voxel.
    Lomax(Vec<[f64; 2]>),
}

impl VoxelLikelihood {
    fn build(model: CorridorModel, algorithm: Algorithm, cells: &[CellStats]) -> Self {
        match (model, algorithm) {
            (CorridorModel::Reflection, mlm @ (Algorithm::Mlm | Algorithm::MlmClamped)) => {
                let c = ReflectionConfig::default();
                let (lo, hi) = if mlm == Algorithm::Mlm {
                    (STRICT_FLOOR, 1.0 - STRICT_FLOOR)
                } else {
                    (c.min_probability, c.max_probability)
                };
                Self::Bernoulli(
                    cells
                        .iter()
                        .map(|s| {
                            let n = s.h() + s.m();
                            let mu = if n > 0.0 { s.h() / n } else { 0.5 };
                            mu.clamp(lo, hi)
                        })
                        .collect(),
                )
            }
            (CorridorModel::Reflection, fmp) => {
                let prior = if fmp == Algorithm::FmpConjugate {
                    BetaPrior::estimate(cells)
                } else {
                    BetaPrior::default()
                };
                Self::Bernoulli(
                    cells
                        .iter()
                        .map(|s| (s.h() + prior.alpha) / (s.h() + s.m() + prior.alpha + prior.beta)) // Eq. (8.22)
                        .collect(),
                )
            }
            (CorridorModel::DecayRate, mlm @ (Algorithm::Mlm | Algorithm::MlmClamped)) => {
                let floor = if mlm == Algorithm::Mlm {
                    STRICT_FLOOR
                } else {
                    DecayRateConfig::default().min_rate_per_m
                };
                Self::Exponential(
                    cells
                        .iter()
                        .map(|s| {
                            let r = s.path_length_m();
                            let rate = if r > 0.0 { s.h() / r } else { 0.0 }; // Eq. (7.10)
                            rate.max(floor)
                        })
                        .collect(),
                )
            }
            (CorridorModel::DecayRate, fmp) => {
                let (alpha, beta) = if fmp == Algorithm::FmpConjugate {
                    let p = GammaPrior::estimate(cells);
                    (p.alpha, p.beta)
                } else {
                    (1.0, 0.0)
                };
                Self::Lomax(
                    cells
                        .iter()
                        .map(|s| [s.h() + alpha, s.path_length_m() + beta]) // Eq. (8.17)
                        .collect(),
                )
            }
        }
    }

    /// `l(r, δ)` of `obs` under the map of voxel `x`.
    #[inline]
    fn at(&self, x: usize, obs: &VoxelObservation) -> f64 {
        match self {
            Self::Bernoulli(mu) => {
                let mu = mu.get(x).copied().unwrap_or(0.5);
                if obs.hit { mu } else { 1.0 - mu }
            }
            Self::Exponential(rate) => {
                let rate = rate.get(x).copied().unwrap_or(1.0);
                let survive = (-rate * obs.distance_m).exp();
                if obs.hit { rate * survive } else { survive }
            }
            Self::Lomax(params) => {
                let [a, b] = params.get(x).copied().unwrap_or([1.0, 1.0]);
                if b <= 0.0 {
                    return 0.0;
                }
                let denominator = b + obs.distance_m;
                let survive = (a * (b / denominator).ln()).exp(); // Sec. 8.4.5, l_dec FMP
                if obs.hit {
                    survive * a / denominator
                } else {
                    survive
                }
            }
        }
    }
}

/// ρ of one algorithm: the exact Bayes filter over the voxels (module docs).
fn rho(
    likelihood: &VoxelLikelihood,
    observations: &[VoxelObservation],
    belief: &mut Vec<f64>,
) -> f64 {
    let n = observations.len();
    belief.clear();
    belief.resize(n, 1.0 / n as f64);
    let mut sum_rho = 0.0;
    for (t, obs) in observations.iter().enumerate() {
        if t > 0 {
            // Known motion: shift by one voxel, drop what leaves the corridor.
            belief.rotate_right(1);
            if let Some(first) = belief.first_mut() {
                *first = 0.0;
            }
        }
        let mut total = 0.0;
        for (x, b) in belief.iter_mut().enumerate().skip(t) {
            *b *= likelihood.at(x, obs);
            total += *b;
        }
        if total > 0.0 && total.is_finite() {
            for b in belief.iter_mut().skip(t) {
                *b /= total;
            }
        } else {
            // Every hypothesis impossible: keep the prediction (renormalized).
            let predicted: f64 = belief.iter().skip(t).sum();
            let uniform = 1.0 / (n - t) as f64;
            for b in belief.iter_mut().skip(t) {
                *b = if predicted > 0.0 { uniform } else { 0.0 };
            }
        }
        sum_rho += belief.get(t).copied().unwrap_or(0.0);
    }
    sum_rho / n.max(1) as f64
}

/// The outcome of one run for one model and `n`.
#[derive(Clone, Copy, Debug)]
struct RunOutcome {
    rho: [f64; 4],
    /// Observations whose unclamped ML likelihood at the true voxel was zero.
    mlm_zeros: u32,
    /// The conjugate prior (α, β).
    prior: [f64; 2],
}

fn run_one(model: CorridorModel, n_visits: u32, run: usize, belief: &mut Vec<f64>) -> RunOutcome {
    let world_seed = run_seed(SEED, run);
    let world = CorridorWorld::sample(world_seed, model);
    let stats: MapStatistics = world.map_statistics(
        n_visits,
        &mut stream(world_seed, streams::MAPPING, u64::from(n_visits)),
    );
    let observations =
        world.localization_observations(&mut stream(world_seed, streams::LOCALIZATION, 0));
    let cells: Vec<CellStats> = stats
        .hits
        .iter()
        .zip(&stats.misses)
        .zip(&stats.distance_m)
        .map(|((&h, &m), &r)| CellStats::new(h, m, r))
        .collect();
    let mut rho_of = [0.0; 4];
    for (slot, algorithm) in rho_of.iter_mut().zip(ALGORITHMS) {
        let likelihood = VoxelLikelihood::build(model, algorithm, &cells);
        *slot = rho(&likelihood, &observations, belief);
    }
    let mlm_zeros = observations
        .iter()
        .zip(&cells)
        .filter(|(obs, cell)| {
            (obs.hit && cell.hits() == 0)
                || (!obs.hit && model == CorridorModel::Reflection && cell.misses() == 0)
        })
        .count() as u32;
    let prior = match model {
        CorridorModel::Reflection => {
            let p = BetaPrior::estimate(&cells);
            [p.alpha, p.beta]
        }
        CorridorModel::DecayRate => {
            let p = GammaPrior::estimate(&cells);
            [p.alpha, p.beta]
        }
    };
    RunOutcome {
        rho: rho_of,
        mlm_zeros,
        prior,
    }
}

/// Share of pairs with `a > b` and the p-value of the paired one-tailed t-test of `a − b > 0`.
fn paired_test(a: &[f64], b: &[f64]) -> (f64, f64) {
    if a.len() < 2 {
        return (f64::NAN, f64::NAN);
    }
    let wins = a.iter().zip(b).filter(|(x, y)| x > y).count() as f64 / a.len() as f64;
    (wins, crate::stats::paired_greater(a, b))
}

/// Results for one model and `n`.
struct Cell {
    n: u32,
    mean_rho: [f64; 4],
    /// Fraction of runs where FMP-conjugate beats MLM / FMP-uniform / MLM-clamped, and the
    /// p-values.
    win_vs: [f64; 3],
    p_vs: [f64; 3],
    mlm_zeros_per_run: f64,
    mean_prior: [f64; 2],
}

/// A p-value in scientific notation; "< 1e-300" when it underflows.
fn fmt_p(p: f64) -> String {
    if p == 0.0 {
        "< 1e-300".to_owned()
    } else {
        format!("{p:.1e}")
    }
}

/// FMP-conjugate better than MLM and FMP-uniform (the thesis's three algorithms) with
/// p < 1e-4.
fn significant(cell: &Cell) -> bool {
    cell.p_vs.iter().take(2).all(|&p| p < ALPHA)
}

fn thesis_significant(model: CorridorModel, n: u32) -> bool {
    match model {
        CorridorModel::Reflection => n <= 100,
        CorridorModel::DecayRate => n <= 4,
    }
}

/// The "comparable" cell of a corridor row: the thesis' significance (Sec. 8.5.1) beside
/// ours from `runs` runs per n.
fn comparable_cell(runs: usize) -> String {
    if runs == RUNS_FULL {
        comparable::yes(
            "simulated in both: same corridor, map draws, n and 10 000 runs, same test; the \
             MLM zero clamp and the conjugate prior's moment estimate are ours (thesis unstated)",
        )
    } else {
        comparable::no(&format!(
            "quick run: {runs} runs per n (thesis 10 000), so p-values are weaker"
        ))
    }
}

/// The corridor section of the `mcl` report: markdown and JSON.
pub fn section(ctx: &EvalContext) -> Result<(String, serde_json::Value)> {
    let runs = if ctx.quick { RUNS_QUICK } else { RUNS_FULL };
    let started = std::time::Instant::now();
    let bar = ctx.progress(
        (CorridorModel::ALL.len() * N_VISITS.len()) as u64,
        "corridor",
    );
    let mut markdown = format!(
        "Simulated (Schaefer 2020 Sec. 8.5.1): a corridor of 100 voxels, ground truth \
         re-drawn per run (REF μ ~ U(0, 1), DEC λ ~ Gamma(1, 1)), {runs} seeded runs per n \
         (thesis: 10 000), seed {SEED}. ρ = belief at the true voxel averaged over the 100 \
         iterations of an exact Bayes filter with known motion and a uniform initial belief. \
         \"wins\" = fraction of runs where FMP-conjugate has the higher ρ; p = one-tailed paired \
         t-test (H1: FMP-conjugate better). Thesis (Fig. 8.2): FMP-conjugate better than both \
         with p < 1e-4 for n ≤ 100 (REF) and n ≤ 4 (DEC). MLM (the thesis's) uses the ML map with \
         μ clamped to [1e-12, 1 − 1e-12] and λ ≥ 1e-12 /m, so a zero likelihood stays practically \
         zero but the filter stays defined; MLM-clamped uses the clamps of the \
         crate's models instead (μ ∈ [1e-3, 1 − 1e-3], λ ≥ 1e-3 /m) and is shown beside. \
         \"ML zeros\" = observations per run whose unclamped ML likelihood at the true voxel is 0; \
         each one nearly removes the true pose from the MLM belief.\n\n"
    );
    let mut json_models = serde_json::Map::new();
    for model in CorridorModel::ALL {
        let mut cells = Vec::new();
        for n in N_VISITS {
            let outcomes: Vec<RunOutcome> = (0..runs)
                .into_par_iter()
                .map_init(Vec::new, |belief, run| run_one(model, n, run, belief))
                .collect();
            let column = |i: usize| outcomes.iter().map(|o| o.rho[i]).collect::<Vec<f64>>();
            let (mlm, clamped, uniform, conjugate) = (column(0), column(1), column(2), column(3));
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
            let (win_mlm, p_mlm) = paired_test(&conjugate, &mlm);
            let (win_uni, p_uni) = paired_test(&conjugate, &uniform);
            let (win_clamped, p_clamped) = paired_test(&conjugate, &clamped);
            let k = outcomes.len().max(1) as f64;
            cells.push(Cell {
                n,
                mean_rho: [mean(&mlm), mean(&uniform), mean(&conjugate), mean(&clamped)],
                win_vs: [win_mlm, win_uni, win_clamped],
                p_vs: [p_mlm, p_uni, p_clamped],
                mlm_zeros_per_run: outcomes.iter().map(|o| f64::from(o.mlm_zeros)).sum::<f64>() / k,
                mean_prior: [
                    outcomes.iter().map(|o| o.prior[0]).sum::<f64>() / k,
                    outcomes.iter().map(|o| o.prior[1]).sum::<f64>() / k,
                ],
            });
            bar.inc(1);
        }
        let (label, prior_name) = match model {
            CorridorModel::Reflection => ("REF (reflection model)", "Beta"),
            CorridorModel::DecayRate => ("DEC (decay-rate model)", "Gamma"),
        };
        let mut table = Table::new([
            "n".to_owned(),
            "ρ MLM".to_owned(),
            "ρ FMP-uniform".to_owned(),
            "ρ FMP-conjugate".to_owned(),
            "wins vs MLM".to_owned(),
            "p vs MLM".to_owned(),
            "wins vs uniform".to_owned(),
            "p vs uniform".to_owned(),
            "ours: p < 1e-4 vs both".to_owned(),
            "thesis".to_owned(),
            "ML zeros".to_owned(),
            "ρ MLM-clamped".to_owned(),
            "wins / p vs clamped".to_owned(),
            format!("mean {prior_name} α, β"),
            comparable::HEADER.to_owned(),
        ]);
        let mut agree = 0;
        for c in &cells {
            let ours = significant(c);
            let thesis = thesis_significant(model, c.n);
            agree += usize::from(ours == thesis);
            table.row([
                c.n.to_string(),
                fmt_num(c.mean_rho[0], 4),
                fmt_num(c.mean_rho[1], 4),
                fmt_num(c.mean_rho[2], 4),
                fmt_num(c.win_vs[0], 3),
                fmt_p(c.p_vs[0]),
                fmt_num(c.win_vs[1], 3),
                fmt_p(c.p_vs[1]),
                if ours { "yes" } else { "no" }.to_owned(),
                if thesis { "yes" } else { "no" }.to_owned(),
                fmt_num(c.mlm_zeros_per_run, 2),
                fmt_num(c.mean_rho[3], 4),
                format!("{} / {}", fmt_num(c.win_vs[2], 3), fmt_p(c.p_vs[2])),
                format!("{:.2}, {:.2}", c.mean_prior[0], c.mean_prior[1]),
                comparable_cell(runs),
            ]);
        }
        markdown.push_str(&format!(
            "### {label}\n\n{}\nOurs and the thesis agree on the significance for {agree} of {} \
             values of n.\n\n",
            table.to_markdown()?,
            cells.len()
        ));
        json_models.insert(
            model.name().to_owned(),
            json!(
                cells
                    .iter()
                    .map(|c| json!({
                        "n": c.n,
                        "mean_rho": {
                            "mlm": c.mean_rho[0],
                            "fmp_uniform": c.mean_rho[1],
                            "fmp_conjugate": c.mean_rho[2],
                        },
                        "conjugate_wins_vs_mlm": c.win_vs[0],
                        "conjugate_wins_vs_uniform": c.win_vs[1],
                        "p_vs_mlm": c.p_vs[0],
                        "p_vs_uniform": c.p_vs[1],
                        "significant_vs_both": significant(c),
                        "mlm_clamped": {
                            "mean_rho": c.mean_rho[3],
                            "conjugate_wins": c.win_vs[2],
                            "p": c.p_vs[2],
                        },
                        "thesis_significant": thesis_significant(model, c.n),
                        "mlm_zero_likelihoods_per_run": c.mlm_zeros_per_run,
                        "mean_prior": c.mean_prior,
                    }))
                    .collect::<Vec<_>>()
            ),
        );
    }
    bar.finish_and_clear();
    let seconds = started.elapsed().as_secs_f64();
    markdown.push_str(&format!(
        "Algorithms: {}. Run time of this section: {seconds:.1} s.\n",
        ALGORITHMS.map(Algorithm::name).join(", ")
    ));
    Ok((
        markdown,
        json!({
            "simulated": true,
            "runs_per_n": runs,
            "seed": SEED,
            "n_visits": N_VISITS,
            "alpha": ALPHA,
            "seconds": seconds,
            "models": json_models,
        }),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perfect_information_tracks_the_true_voxel() {
        // Nearly deterministic voxels with a pseudo-random hit pattern, observations that
        // follow it: a few steps identify the start, after that the belief is sharp.
        let mut state = 0x9E37_79B9_7F4A_7C15_u64;
        let pattern: Vec<bool> = (0..100)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                state & 1 == 1
            })
            .collect();
        let mu: Vec<f64> = pattern
            .iter()
            .map(|&h| if h { 0.999 } else { 0.001 })
            .collect();
        let obs: Vec<VoxelObservation> = pattern
            .iter()
            .map(|&hit| VoxelObservation {
                hit,
                distance_m: 1.0,
            })
            .collect();
        let r = rho(&VoxelLikelihood::Bernoulli(mu), &obs, &mut Vec::new());
        assert!(r > 0.9, "ρ = {r}");
        // Uninformative map: the belief is uniform over the remaining voxels.
        let flat = VoxelLikelihood::Bernoulli(vec![0.5; 100]);
        let r = rho(&flat, &obs, &mut Vec::new());
        let expected = (0..100).map(|t| 1.0 / (100 - t) as f64).sum::<f64>() / 100.0;
        assert!((r - expected).abs() < 1e-12);
    }

    #[test]
    fn comparable_cell_names_the_run_count() {
        assert!(comparable_cell(RUNS_FULL).starts_with("yes — simulated in both"));
        let quick = comparable_cell(RUNS_QUICK);
        assert!(
            quick.starts_with("no — quick run: 500 runs per n"),
            "{quick}"
        );
    }

    #[test]
    fn runs_are_deterministic() {
        let a = run_one(CorridorModel::DecayRate, 3, 7, &mut Vec::new());
        let b = run_one(CorridorModel::DecayRate, 3, 7, &mut Vec::new());
        assert_eq!(a.rho, b.rho);
    }

    /// Prints the quick section (`cargo test -p raypath-eval corridor -- --ignored --nocapture`; the
    /// full one with `CORRIDOR_FULL=1`).
    #[test]
    #[ignore = "prints the quick corridor table (a few seconds)"]
    fn print_quick_section() {
        let ctx = EvalContext {
            workspace_root: crate::eval::workspace_root(),
            data_dir: std::path::PathBuf::from("datasets"),
            quick: std::env::var_os("CORRIDOR_FULL").is_none(),
            out_dir: crate::eval::workspace_root(),
        };
        let (markdown, _) = section(&ctx).expect("section");
        println!("{markdown}");
    }
}
