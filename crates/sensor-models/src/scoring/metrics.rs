//! The pose-distribution metrics: samples in a disc, the inverse KL of Eq. 7.29 and the
//! ground-truth KL of Eq. 8.24, from log-likelihoods at the samples.

use rand_xoshiro::SplitMix64;
use rand_xoshiro::rand_core::{RngCore, SeedableRng};
use serde::{Deserialize, Serialize};

/// Uniform in `[0, 1)` with 53 random bits.
fn next_f64(rng: &mut SplitMix64) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// `count` position offsets `[dx, dy]` in metres, uniform in the disc of radius `radius_m`
/// (`r = R √u`, `φ = 2π v`), drawn from a generator seeded with `(seed, scan_index)`.
/// The same arguments give the same offsets.
pub fn disc_offsets(seed: u64, scan_index: u64, count: usize, radius_m: f64) -> Vec<[f64; 2]> {
    // SplitMix64 (Steele, Lea and Flood, OOPSLA 2014) seeded with its state as given.
    let mut mixer = SplitMix64::seed_from_u64(seed ^ 0x5eed_0000_0000_0000);
    let stream = mixer.next_u64() ^ scan_index.wrapping_mul(0xd1b5_4a32_d192_ed03);
    let mut rng = SplitMix64::seed_from_u64(stream);
    (0..count)
        .map(|_| {
            let r = radius_m * next_f64(&mut rng).sqrt();
            let phi = std::f64::consts::TAU * next_f64(&mut rng);
            [r * phi.cos(), r * phi.sin()]
        })
        .collect()
}

/// The two divergences of one test scan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Divergences {
    /// `D(h‖g) = Σ_i p̂_i ln(p̂_i / ĝ_i)` (Eq. 7.29).
    pub inverse_kl: f64,
    /// `D_KL(p_gt‖p) = Σ_i ĝ_i ln(ĝ_i / p̂_i)` (Eq. 8.24, with the estimator of the module docs).
    pub kl_ground_truth: f64,
}

/// `ln Σ_i e^{x_i}`, `−∞` for an empty slice or all `−∞`.
pub fn log_sum_exp(values: &[f64]) -> f64 {
    let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if max == f64::NEG_INFINITY || max.is_nan() {
        return max;
    }
    max + values.iter().map(|v| (v - max).exp()).sum::<f64>().ln()
}

/// The divergences between the model's pose distribution and the Gaussian ground truth over
/// a set of samples, all in log space.
///
/// * `log_likelihoods[i] = ln p(z | s_i, m)` at the sample `s_i = s + offsets[i]`; the
///   model's posterior over the samples is `p̂_i = p(z | s_i, m) / Σ_j p(z | s_j, m)`
///   (Sec. 7.6.2: "normalizing p(z | s_i, m) over the M samples");
/// * the ground truth is `N(s_i; s, σ² I)` normalized over the same samples:
///   `ĝ_i ∝ exp(−|offsets[i]|² / (2σ²))`.
///
/// Terms with a zero weight contribute 0 (`0 ln 0 = 0`). A sample with `ĝ_i > 0` and
/// `p̂_i = 0` makes the ground-truth KL `+∞`; all log-likelihoods `−∞` give `+∞` for both.
pub fn divergences(log_likelihoods: &[f64], offsets: &[[f64; 2]], sigma_m: f64) -> Divergences {
    let n = log_likelihoods.len().min(offsets.len());
    let log_lik = &log_likelihoods[..n];
    let log_gt: Vec<f64> = offsets[..n]
        .iter()
        .map(|[dx, dy]| -(dx * dx + dy * dy) / (2.0 * sigma_m * sigma_m))
        .collect();
    let z_model = log_sum_exp(log_lik);
    let z_gt = log_sum_exp(&log_gt);
    if !z_model.is_finite() || !z_gt.is_finite() {
        return Divergences {
            inverse_kl: f64::INFINITY,
            kl_ground_truth: f64::INFINITY,
        };
    }
    let mut inverse_kl = 0.0;
    let mut kl_ground_truth = 0.0;
    for (l, g) in log_lik.iter().zip(&log_gt) {
        let ln_p = l - z_model; // ln p̂_i
        let ln_g = g - z_gt; // ln ĝ_i
        let p = ln_p.exp();
        let q = ln_g.exp();
        if p > 0.0 {
            inverse_kl += p * (ln_p - ln_g); // Eq. (7.29)
        }
        if q > 0.0 {
            kl_ground_truth += q * (ln_g - ln_p); // Eq. (8.24)
        }
    }
    Divergences {
        inverse_kl,
        kl_ground_truth,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// rand_xoshiro's SplitMix64 seeded with `seed_from_u64(s)` is the generator of Steele
    /// et al. started at state `s` (the pose samples of earlier runs stay the same): the
    /// published first outputs for state 0 and a value of the hand-written generator it
    /// replaced.
    #[test]
    fn splitmix_is_the_published_generator() {
        let mut rng = SplitMix64::seed_from_u64(0);
        assert_eq!(rng.next_u64(), 0xe220_a839_7b1d_cdaf);
        assert_eq!(rng.next_u64(), 0x6e78_9e6a_a1b9_65f4);
        let mut state = 1234u64;
        let mut reference = || {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        };
        let mut rng = SplitMix64::seed_from_u64(1234);
        for _ in 0..100 {
            assert_eq!(rng.next_u64(), reference());
        }
    }

    #[test]
    fn offsets_lie_in_the_disc_and_are_reproducible() {
        let a = disc_offsets(7, 3, 1000, 2.5);
        assert_eq!(a, disc_offsets(7, 3, 1000, 2.5));
        assert_ne!(a, disc_offsets(7, 4, 1000, 2.5));
        assert_ne!(a, disc_offsets(8, 3, 1000, 2.5));
        assert!(a.iter().all(|[x, y]| x * x + y * y <= 2.5 * 2.5));
        // Uniform in area: about a quarter of the samples within half the radius.
        let inner = a
            .iter()
            .filter(|[x, y]| x * x + y * y <= 1.25 * 1.25)
            .count();
        assert!((200..300).contains(&inner), "{inner}");
    }

    #[test]
    fn identical_distributions_have_zero_divergence() {
        let offsets = disc_offsets(1, 0, 50, 2.5);
        let sigma = 0.7;
        let log_lik: Vec<f64> = offsets
            .iter()
            .map(|[x, y]| 3.0 - (x * x + y * y) / (2.0 * sigma * sigma))
            .collect();
        let d = divergences(&log_lik, &offsets, sigma);
        assert!(
            d.inverse_kl.abs() < 1e-12 && d.kl_ground_truth.abs() < 1e-12,
            "{d:?}"
        );
    }

    #[test]
    fn log_sum_exp_is_stable() {
        assert!((log_sum_exp(&[-1000.0, -1000.0]) - (-1000.0 + 2f64.ln())).abs() < 1e-12);
        assert_eq!(log_sum_exp(&[]), f64::NEG_INFINITY);
        assert_eq!(
            log_sum_exp(&[f64::NEG_INFINITY, f64::NEG_INFINITY]),
            f64::NEG_INFINITY
        );
    }
}
