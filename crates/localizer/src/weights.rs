//! Log-weights: log-sum-exp normalization and the effective sample size.
//!
//! The filter keeps one log-weight lᵢ = ln wᵢ per particle. A measurement update adds the
//! log-likelihood, lᵢ ← lᵢ + ln p(z | xᵢ), and then normalizes by log-sum-exp (Thrun et al.
//! 2005, §4.3):
//!
//! ```text
//!   m = maxᵢ lᵢ,   ln Σᵢ e^{lᵢ} = m + ln Σᵢ e^{lᵢ − m},   lᵢ ← lᵢ − ln Σⱼ e^{lⱼ}
//! ```
//!
//! so the largest term is e⁰ = 1: no overflow or underflow whatever the scale of the
//! log-likelihoods (a 3-D scan easily sums to −10⁵), and the result is invariant to adding a
//! constant to every lᵢ. The effective sample size (Kong et al. 1994; Thrun et al. §4.3.4)
//! of normalized weights is `ESS = 1 / Σᵢ wᵢ²`, between 1 and N.
//!
//! Large sets are processed in parallel; sums run over fixed chunks, so the result is
//! bit-identical on any number of threads.

use rayon::prelude::*;

use crate::error::LocalizerError;

/// Sums run over fixed chunks of this many entries (in parallel), then over the chunk sums in
/// order: the rounding depends on the length only, never on the number of threads.
const CHUNK: usize = 2048;

/// Σᵢ f(vᵢ), deterministic for a given length whatever the thread count (see [`CHUNK`]).
fn chunked_sum(values: &[f64], f: impl Fn(f64) -> f64 + Sync) -> f64 {
    let chunk_sum = |chunk: &[f64]| chunk.iter().map(|&v| f(v)).sum::<f64>();
    if values.len() <= CHUNK {
        return 0.0 + chunk_sum(values);
    }
    let partials: Vec<f64> = values.par_chunks(CHUNK).map(chunk_sum).collect();
    partials.iter().sum()
}

/// ln Σᵢ e^{lᵢ}, computed stably. `−∞` when every entry is `−∞` or the slice is empty.
/// NaN entries propagate (check before calling).
pub fn log_sum_exp(log_weights: &[f64]) -> f64 {
    let (max, ln_sum) = log_sum_exp_parts(log_weights);
    max + ln_sum
}

/// `(m, ln Σᵢ e^{lᵢ − m})` with m = maxᵢ lᵢ; `(±∞, 0)` when m is infinite.
fn log_sum_exp_parts(log_weights: &[f64]) -> (f64, f64) {
    let max = log_weights
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    if max.is_infinite() {
        return (max, 0.0);
    }
    let sum: f64 = log_weights.iter().map(|&l| (l - max).exp()).sum();
    (max, sum.ln())
}

/// Normalizes log-weights in place so that Σᵢ e^{lᵢ} = 1 and returns the subtracted
/// normalizer ln Σ e^{lᵢ}.
///
/// Errors: [`LocalizerError::Empty`] for an empty slice, [`LocalizerError::NonFinite`] for
/// NaN or +∞ entries, [`LocalizerError::AllParticlesImpossible`] when every entry is −∞.
/// On error the slice is unchanged.
pub fn normalize_log_weights(log_weights: &mut [f64]) -> Result<f64, LocalizerError> {
    if log_weights.is_empty() {
        return Err(LocalizerError::Empty {
            what: "log-weights",
        });
    }
    if let Some(index) = log_weights
        .iter()
        .position(|l| l.is_nan() || *l == f64::INFINITY)
    {
        return Err(LocalizerError::NonFinite {
            what: "log-weight",
            index,
        });
    }
    let (max, ln_sum) = log_sum_exp_parts(log_weights);
    if max == f64::NEG_INFINITY {
        return Err(LocalizerError::AllParticlesImpossible {
            particles: log_weights.len(),
        });
    }
    // (lᵢ − m) first: exact for nearby values however large m is, so the weights of a
    // −10⁵ scan likelihood keep full relative precision.
    let subtract = |l: &mut f64| *l = (*l - max) - ln_sum;
    if log_weights.len() <= CHUNK {
        log_weights.iter_mut().for_each(subtract);
    } else {
        log_weights
            .par_iter_mut()
            .with_min_len(CHUNK)
            .for_each(subtract);
    }
    Ok(max + ln_sum)
}

/// The effective sample size `1 / Σᵢ wᵢ²` of **normalized** log-weights
/// (see [`normalize_log_weights`]).
pub fn effective_sample_size(normalized_log_weights: &[f64]) -> f64 {
    let sum_sq = chunked_sum(normalized_log_weights, |l| (2.0 * l).exp());
    if sum_sq > 0.0 { 1.0 / sum_sq } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huge_log_likelihoods_do_not_underflow() {
        let mut l = vec![-1e5, -1e5 - 1.0, -1e5 - 2.0];
        normalize_log_weights(&mut l).unwrap();
        let w: Vec<f64> = l.iter().map(|x| x.exp()).collect();
        let total = 1.0 + (-1f64).exp() + (-2f64).exp();
        assert!((w[0] - 1.0 / total).abs() < 1e-12);
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn degenerate_inputs_are_errors_and_leave_weights() {
        let mut l = vec![f64::NEG_INFINITY; 3];
        assert!(matches!(
            normalize_log_weights(&mut l),
            Err(LocalizerError::AllParticlesImpossible { particles: 3 })
        ));
        assert!(l.iter().all(|x| *x == f64::NEG_INFINITY));
        let mut l = vec![0.0, f64::NAN];
        assert!(matches!(
            normalize_log_weights(&mut l),
            Err(LocalizerError::NonFinite { index: 1, .. })
        ));
        assert!(normalize_log_weights(&mut []).is_err());
    }

    #[test]
    fn ess_of_a_single_surviving_particle_is_one() {
        let mut l = vec![0.0, f64::NEG_INFINITY, f64::NEG_INFINITY];
        normalize_log_weights(&mut l).unwrap();
        assert!((effective_sample_size(&l) - 1.0).abs() < 1e-12);
    }
}
