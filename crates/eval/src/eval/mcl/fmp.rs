//! The decay-rate model with the ML map (MLM) against its full map posterior (FMP) in the
//! particle filter: the thesis's Measure 3 (Schaefer 2020, Sec. 8.5.2, Fig. 8.3), whose text
//! claims that FMP improves the localization accuracy. A subsection of the orderings.
//!
//! The two filters of a data set share everything but the weighting (same statistics, seeds,
//! initial particles, exponent and outlier mixture): MLM weighs with Eq. (7.13) on
//! `λ_i = H_i / R_i`, FMP with the closed-form `L(z, x)` of Sec. 8.4.5 under
//! `Gamma(H_i + α, R_i + β)`, α and β estimated once per map by the method of moments
//! (Sec. 8.5, [`GammaPrior::estimate`]). Runs are paired by seed; the test is the one-sided
//! paired t-test of [`crate::stats::paired_less`] (H1: FMP error < MLM error).

use anyhow::Result;
use raypath_sensor_models::GammaPrior;
use serde_json::{Value, json};

use super::common::Cell;
use super::{PARTICLES_2D, spatial};
use crate::eval::comparable;
use crate::stats::{mean_std, paired_less};
use crate::table::{Table, fmt_num};

/// The MLM and FMP cells of one data set.
struct Pair<'a> {
    dataset: &'a str,
    /// `ours (2-D, real)` and the like.
    source: String,
    comparable: String,
    ml: &'a Cell,
    fmp: &'a Cell,
}

impl Pair<'_> {
    fn errors(cell: &Cell) -> Vec<f64> {
        cell.runs.iter().map(|r| r.position_m).collect()
    }

    /// Mean paired difference FMP − MLM and the one-sided p-value (H1: FMP < MLM).
    fn test(&self) -> (f64, f64) {
        let (ml, fmp) = (Self::errors(self.ml), Self::errors(self.fmp));
        let diff: Vec<f64> = fmp.iter().zip(&ml).map(|(f, m)| f - m).collect();
        (mean_std(&diff).0, paired_less(&fmp, &ml))
    }

    fn diverged(cell: &Cell) -> usize {
        cell.runs.iter().filter(|r| r.diverged).count()
    }

    /// "yes — …" / "no — …": does FMP have the lower mean error?
    fn verdict(&self) -> String {
        let (diff, p) = self.test();
        let significance = if p < 0.05 {
            format!("p = {} < 0.05", fmt_num(p, 3))
        } else {
            format!("p = {}, not significant", fmt_num(p, 3))
        };
        if diff < 0.0 {
            format!("yes — FMP better ({significance})")
        } else {
            format!("no — FMP worse or equal ({significance})")
        }
    }
}

/// The MLM cell of a group (`decay-rate` or `decay-rate [table]`) and its FMP partner.
fn find_pair<'a>(group: &[&'a Cell]) -> Option<(&'a Cell, &'a Cell)> {
    let ml = group
        .iter()
        .find(|c| c.model == "decay-rate" || c.model == "decay-rate [table]")?;
    let fmp = group
        .iter()
        .find(|c| c.model.starts_with("decay-rate (FMP)"))?;
    (ml.runs.len() == fmp.runs.len()).then_some((*ml, *fmp))
}

/// The "comparable" cell of one of our rows; `kind` is real / simulated (2-D) or `urban`,
/// `urban*` (3-D).
fn ours_comparable(kind: &str, three_d: bool) -> String {
    let thesis = "the thesis' real VIONA park drive (Velodyne HDL-64E, Applanix ground truth, \
                  3000 particles), not available here; the direction of the effect only";
    if three_d {
        let failures = if kind == "urban*" {
            ", 10 % of the rays at r_min"
        } else {
            ""
        };
        comparable::no(&format!(
            "simulated HDL-64E urban drive{failures}, 6-DOF like the thesis but {} particles \
             (this page's count, not the thesis' 3000) and exact ray casting, vs {thesis}",
            spatial::PARTICLES
        ))
    } else if kind == "real" {
        comparable::no(&format!(
            "real 2-D CARMEN laser log (3-DOF, {PARTICLES_2D} particles, tabulated likelihoods, \
             map and test scans not disjoint) vs {thesis}"
        ))
    } else {
        comparable::no(&format!(
            "{kind} 2-D indoor world (3-DOF, {PARTICLES_2D} particles, tabulated likelihoods) \
             vs {thesis}"
        ))
    }
}

fn pairs<'a>(cells: &'a [(String, &'static str, Cell)], cells_3d: &'a [Cell]) -> Vec<Pair<'a>> {
    let mut names: Vec<(&str, &str)> = Vec::new();
    for (name, kind, _) in cells {
        if !names.iter().any(|(n, _)| n == name) {
            names.push((name, kind));
        }
    }
    let mut out = Vec::new();
    for (name, kind) in names {
        let group: Vec<&Cell> = cells
            .iter()
            .filter(|(n, _, _)| n == name)
            .map(|(_, _, c)| c)
            .collect();
        if let Some((ml, fmp)) = find_pair(&group) {
            out.push(Pair {
                dataset: name,
                source: format!("ours (2-D, {kind})"),
                comparable: ours_comparable(kind, false),
                ml,
                fmp,
            });
        }
    }
    for set in ["urban", "urban*"] {
        let group: Vec<&Cell> = cells_3d.iter().filter(|c| c.dataset == set).collect();
        if let Some((ml, fmp)) = find_pair(&group) {
            out.push(Pair {
                dataset: set,
                source: "ours (3-D, simulated)".to_owned(),
                comparable: ours_comparable(set, true),
                ml,
                fmp,
            });
        }
    }
    out
}

/// The markdown subsection: the thesis's claim and our rows, with the priors in use.
pub fn section(
    cells: &[(String, &'static str, Cell)],
    cells_3d: &[Cell],
    priors: &[(String, GammaPrior)],
) -> Result<String> {
    let mut md = String::from(
        "\n### Decay-rate: full map posterior (FMP) vs ML map (MLM) in the filter (thesis Fig. 8.3)\n\n\
         Thesis claim (Sec. 8.5.2, Measure 3): \"FMP improves localization accuracy over MLM for the \
         decay-rate model\" — two 6-DOF filters with 3000 particles on the park drive, ten runs, errors \
         shown in Fig. 8.3 only (no numbers). Ours: mean position error over all runs (mean ± std), \
         runs paired by seed (same initial particles); Δ = mean of FMP − MLM; p = one-sided paired \
         t-test, H1: FMP error < MLM error.\n\n",
    );
    let mut table = Table::new([
        "data set",
        "source",
        "MLM [m]",
        "FMP [m]",
        "Δ FMP − MLM [m]",
        "p",
        "diverged MLM / FMP",
        "FMP better?",
        comparable::HEADER,
    ]);
    table.row([
        "park".to_owned(),
        "thesis Fig. 8.3 (3-D, real)".to_owned(),
        "–".to_owned(),
        "–".to_owned(),
        "–".to_owned(),
        "–".to_owned(),
        "–".to_owned(),
        "yes — claimed in the text (figure only)".to_owned(),
        comparable::no(
            "thesis: real VIONA park drive (Velodyne HDL-64E, Applanix ground truth, 3000 \
             particles), not available here; none of our rows uses it",
        ),
    ]);
    let pairs = pairs(cells, cells_3d);
    for pair in &pairs {
        let (diff, p) = pair.test();
        table.row([
            pair.dataset.to_owned(),
            pair.source.clone(),
            pair.ml.position_text(),
            pair.fmp.position_text(),
            fmt_num(diff, 3),
            fmt_num(p, 3),
            format!("{} / {}", Pair::diverged(pair.ml), Pair::diverged(pair.fmp)),
            pair.verdict(),
            pair.comparable.clone(),
        ]);
    }
    md.push_str(&table.to_markdown()?);
    let better = pairs.iter().filter(|p| p.test().0 < 0.0).count();
    let significant = pairs
        .iter()
        .filter(|p| p.test().0 < 0.0 && p.test().1 < 0.05)
        .count();
    md.push_str(&format!(
        "\nFMP has the lower mean error on {better} of {} of our data sets ({significant} with p < 0.05). \
         Gamma prior (method of moments over the observed cells' ML rates, Sec. 8.5): {}.\n",
        pairs.len(),
        priors_text(priors)
    ));
    Ok(md)
}

/// `intel α = …, β = … m; …`.
fn priors_text(priors: &[(String, GammaPrior)]) -> String {
    if priors.is_empty() {
        return "none computed".to_owned();
    }
    priors
        .iter()
        .map(|(name, prior)| {
            format!(
                "{name} α = {}, β = {} m (mean {} /m)",
                fmt_small(prior.alpha),
                fmt_small(prior.beta),
                fmt_num(prior.mean(), 3)
            )
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// Three decimals, or three significant digits in scientific notation below 0.01.
fn fmt_small(value: f64) -> String {
    if value != 0.0 && value.abs() < 0.01 {
        format!("{value:.2e}")
    } else {
        fmt_num(value, 3)
    }
}

/// The rows as JSON.
pub fn json(
    cells: &[(String, &'static str, Cell)],
    cells_3d: &[Cell],
    priors: &[(String, GammaPrior)],
) -> Value {
    let rows: Vec<Value> = pairs(cells, cells_3d)
        .iter()
        .map(|pair| {
            let (diff, p) = pair.test();
            json!({
                "dataset": pair.dataset, "source": pair.source,
                "mlm_model": pair.ml.model, "fmp_model": pair.fmp.model,
                "mlm_position_m": mean_std(&Pair::errors(pair.ml)).0,
                "fmp_position_m": mean_std(&Pair::errors(pair.fmp)).0,
                "mean_difference_m": diff, "p_fmp_less": p,
                "diverged": [Pair::diverged(pair.ml), Pair::diverged(pair.fmp)],
                "comparable": pair.comparable,
            })
        })
        .collect();
    let priors: Vec<Value> = priors
        .iter()
        .map(|(name, prior)| json!({"dataset": name, "alpha": prior.alpha, "beta_m": prior.beta}))
        .collect();
    json!({ "rows": rows, "gamma_priors": priors })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::mcl::common::RunResult;

    fn cell(dataset: &str, model: &str, errors: &[f64]) -> Cell {
        Cell {
            dataset: dataset.to_owned(),
            model: model.to_owned(),
            runs: errors
                .iter()
                .map(|&position_m| RunResult {
                    position_m,
                    heading_rad: 0.01,
                    diverged: position_m > 5.0,
                    updates_per_s: 100.0,
                })
                .collect(),
        }
    }

    /// FMP better on intel (paired, significant), worse on urban; every row says it is not
    /// like for like and why.
    #[test]
    fn rows_give_the_verdict_the_test_and_why_not_comparable() {
        let cells = vec![
            (
                "intel".to_owned(),
                "real",
                cell("intel", "decay-rate [table]", &[0.10, 0.12, 0.11, 0.14]),
            ),
            (
                "intel".to_owned(),
                "real",
                cell(
                    "intel",
                    "decay-rate (FMP) [table]",
                    &[0.08, 0.10, 0.10, 0.11],
                ),
            ),
        ];
        let cells_3d = vec![
            cell("urban", "decay-rate", &[0.2, 0.3, 0.25, 0.2]),
            cell("urban", "decay-rate (FMP)", &[0.3, 0.35, 0.3, 0.3]),
        ];
        let priors = vec![(
            "intel".to_owned(),
            GammaPrior::new(0.05, 0.009_999_9).expect("prior"),
        )];
        let md = section(&cells, &cells_3d, &priors).expect("section");
        let row = |start: &str| {
            md.lines()
                .find(|l| l.starts_with(start))
                .unwrap_or_default()
                .to_owned()
        };
        assert!(row("| park ").contains("no — thesis: real VIONA park drive"));
        let intel = row("| intel ");
        assert!(intel.contains("yes — FMP better (p = "), "{intel}");
        assert!(intel.contains("< 0.05"), "{intel}");
        assert!(intel.contains("| -0.020 "), "{intel}");
        assert!(intel.contains("no — real 2-D CARMEN laser log"), "{intel}");
        let urban = row("| urban ");
        assert!(urban.contains("no — FMP worse"), "{urban}");
        assert!(urban.contains("not the thesis' 3000"), "{urban}");
        assert!(md.contains("on 1 of 2 of our data sets (1 with p < 0.05)"));
        assert!(md.contains("intel α = 0.050, β = 1.00e-2 m"), "{md}");
        let header = md
            .lines()
            .find(|l| l.starts_with("| data set"))
            .expect("table");
        assert_eq!(comparable::last_cell(header), "comparable");
        let json = json(&cells, &cells_3d, &priors);
        assert_eq!(json["rows"].as_array().map(Vec::len), Some(2));
    }
}
