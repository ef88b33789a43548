//! The thesis' figures (Schaefer 2020, Tables 9.1–9.4) and the "comparable" cells that say
//! how our rows differ from them.

use raypath_dct_map::experiment::BASELINE_PIXEL_M;

use super::{HELD_BACK, MAPPING_RAYS, comparable};

/// Thesis Table 9.2 (μ_DCT, σ_DCT, μ_GM, σ_GM, p %, Δ_μ %), Table 9.3 (DCT − GM μ, σ) and
/// Table 9.4 (t_DCT, t_GM in s), per size. Δ_μ of 13² is 5.21 = 1 − 0.3146 / 0.3319 from
/// the thesis' own μ; the thesis prints 0.52 there (see [`THESIS_PRINTED_DELTA_13`]).
/// `(size, μ_DCT, σ_DCT, μ_GM, σ_GM, p, Δ_μ, ΔLL μ, ΔLL σ, t_DCT, t_GM)`.
pub(super) type ThesisRow = (usize, f64, f64, f64, f64, f64, f64, f64, f64, f64, f64);

pub(super) const THESIS: [ThesisRow; 5] = [
    (
        10, 0.3314, 0.0679, 0.3330, 0.0708, 39.36, 0.48, 88.5, 74.1, 3.52, 0.0917,
    ),
    (
        13, 0.3146, 0.0675, 0.3319, 0.0752, 1.01, 5.21, 150.6, 146.5, 4.69, 0.0915,
    ),
    (
        20, 0.2932, 0.0645, 0.3093, 0.0690, 0.03, 5.21, 135.7, 63.9, 3.70, 0.0923,
    ),
    (
        29, 0.2571, 0.0611, 0.2822, 0.0672, 0.05, 8.89, 196.1, 101.5, 18.25, 0.0926,
    ),
    (
        40, 0.2370, 0.0563, 0.2543, 0.0583, 0.07, 6.80, 96.8, 132.0, 39.84, 0.0942,
    ),
];

/// Δ_μ [%] of the 13² row as printed in thesis Table 9.2 (0.52; its μ give 5.21).
pub(super) const THESIS_PRINTED_DELTA_13: f64 = 0.52;

/// Thesis Table 9.3 (DCT − GPOM μ, σ and DCT − HM μ, σ, in nats; printed in units of 10⁴)
/// and Table 9.4 (t_GPOM, t_HM in s), per size:
/// `(size, GPOM μ, GPOM σ, HM μ, HM σ, t_GPOM, t_HM)`.
pub(super) type ThesisBaselineRow = (usize, f64, f64, f64, f64, f64, f64);

pub(super) const THESIS_BASELINES: [ThesisBaselineRow; 5] = [
    (10, 4.21e4, 3.00e4, 4.30e4, 3.42e4, 1.12, 22.8),
    (13, 3.89e4, 2.81e4, 4.19e4, 3.46e4, 1.98, 40.6),
    (20, 3.53e4, 2.60e4, 4.06e4, 3.42e4, 3.25, 108.4),
    (29, 2.97e4, 2.15e4, 4.12e4, 3.32e4, 6.45, 328.3),
    (40, 2.68e4, 1.90e4, 4.12e4, 3.31e4, 14.04, 949.3),
];

/// The 12 Radish logs of thesis Table 9.1, named as our corrected logs are.
pub(super) const THESIS_LOGS: [&str; 12] = [
    "acapulco",
    "aces",
    "belgioioso",
    "csail",
    "edmonton",
    "fhw",
    "seattle",
    "freiburg-079",
    "freiburg-101",
    "infinite-corridor",
    "intel",
    "orebro",
];

/// Our logs beside the thesis' 12 (for the "comparable" cells): how many of its logs, which
/// are absent, which of ours it did not use.
pub(super) fn logs_text(logs: &[&str]) -> String {
    let (ours, absent, extra) = comparable::log_overlap(logs, &THESIS_LOGS);
    let mut text = format!("real Radish logs in both, {ours} of the thesis' 12");
    if !absent.is_empty() {
        text.push_str(&format!(" (absent: {})", absent.join(", ")));
    }
    if !extra.is_empty() {
        text.push_str(&format!(" plus {} (not in the thesis)", extra.join(", ")));
    }
    text
}

/// The "comparable" cell of a Table 9.2 row of `n`² parameters.
pub(super) fn rmse_comparable(logs: &str, n: usize) -> String {
    let printed = if n == 13 {
        format!("; thesis Δ_μ printed as {THESIS_PRINTED_DELTA_13}, bracket recomputed from its μ")
    } else {
        String::new()
    };
    comparable::no(&format!(
        "{logs}; our seeded patch per log; same sizes, 10⁴ rays, 0.05 m truth and p_ref \
         RMSE{printed}"
    ))
}

/// The "comparable" cell of a Table 9.3 row.
pub(super) fn likelihood_comparable(logs: &str) -> String {
    comparable::no(&format!(
        "other protocol: ours = {HELD_BACK} held-back rays under maps from {MAPPING_RAYS} rays, \
         thesis = the 500 rays that built the maps; {logs}"
    ))
}

/// The "comparable" cell of a GPOM / Hilbert-map row of Table 9.3.
pub(super) fn baseline_likelihood_comparable(logs: &str) -> String {
    comparable::no(&format!(
        "our re-implementations with our hyperparameters (GPOM: Matérn 3/2, (ℓ, σ_n) by marginal \
         likelihood on a grid; HM: Nyström RBF γ = 1 /m², L2 logistic regression by L-BFGS), not \
         Jadidi's GPML code and Ott's Python with the thesis' unlisted settings; other protocol: \
         ours = {HELD_BACK} held-back rays under maps from {MAPPING_RAYS} rays, thesis = the 500 \
         rays that built the maps; same {BASELINE_PIXEL_M} m raster; {logs}"
    ))
}

/// The "comparable" cell of a GPOM / Hilbert-map row of Table 9.4.
pub(super) const BASELINE_TIME_COMPARABLE: &str = "no — other language, hardware and implementation: thesis \
     GPOM in MATLAB/GPML and Hilbert maps in Python (SGD; the thesis blames finite differences) \
     on an i7-2600K, medians of 10-run means; ours our own Rust re-implementations (HM by \
     L-BFGS with an analytic gradient), one run, on 2 shared, loaded cores";

/// The "comparable" cell of a Table 9.4 row.
pub(super) const TIME_COMPARABLE: &str = "no — other language and hardware: thesis MATLAB R2017b on an \
     Intel i7-2600K (3.4 GHz), medians of 10-run means; ours Rust, one run, on 2 shared, loaded \
     cores";
