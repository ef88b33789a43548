//! Scoring sensor models against ground truth (Schaefer 2020, Sec. 7.6.2 and 8.5.2):
//! Tables 7.3, 8.2 and 8.3.
//!
//! Given mapping scans and disjoint test scans with reference poses, the statistics are
//! built once (exact traversal), every model variant is built from them
//! ([`MODEL_NAMES`]; decay-rate and reflection also as full posteriors), and each test
//! scan is scored:
//!
//! * **`D'(g‖h)`** (Eq. 7.28): `−Σ_j ln p(z_j | s_j, m)` over every scored ray at the true
//!   pose, summed over the data set (lower is better);
//! * **inverse KL `D(h‖g)`** (Eq. 7.29), averaged over the test scans: `M = 50` positions `s_i`
//!   uniform in a disc of radius 2.5 m around the true position (heading, height and attitude at
//!   the truth; the true pose is not a sample), `p̂_i ∝ p(z | s_i, m)` normalized over the samples,
//!   the ground truth `ĝ_i ∝ N(s_i; s, σ²I)` with σ = 0.05 m normalized the same way,
//!   `D = Σ_i p̂_i ln(p̂_i / ĝ_i)`;
//! * **ground-truth KL** (Eq. 8.24; the thesis gives no estimator, ours is):
//!   `Σ_i ĝ_i ln(ĝ_i / p̂_i)` on the same samples, summed over the test scans — its ML/posterior
//!   ratio is Table 8.3, the ratio of the `D'` values is Table 8.2.
//!
//! With σ = 0.05 m and 50 samples in a 19.6 m² disc the nearest sample is typically
//! 0.2–0.4 m from the truth, so `ĝ` is practically one-hot on the nearest sample: the
//! ground-truth KL is about `−ln p̂(nearest sample)`, and the inverse KL punishes
//! probability mass on samples far from the truth by their squared distance / (2σ²).
//!
//! Samples are drawn per test scan from a generator seeded with `(seed, scan index)`
//! ([`disc_offsets`]), the same for every model; work is parallel over test scans and
//! deterministic. The scores use the exact traversal (no optical-depth tables).

mod config;
mod metrics;
mod run;
mod variants;

pub use config::{ScoringConfig, Split};
pub use metrics::{Divergences, disc_offsets, divergences, log_sum_exp};
pub use run::{ScoreReport, ScoreRow, score_log, score_planar, score_spatial};
pub use variants::MODEL_NAMES;
