//! Properties of log-weight normalization, the effective sample size and systematic
//! resampling.

#![allow(clippy::unwrap_used)]

use proptest::prelude::*;
use raypath_localizer::resample::{copy_counts, systematic_resample};
use raypath_localizer::weights::{effective_sample_size, log_sum_exp, normalize_log_weights};

fn log_weights() -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(-50.0..10.0f64, 1..300)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]

    #[test]
    fn normalization_is_invariant_to_adding_a_constant(
        mut l in log_weights(),
        offset in -1e5..1e5f64,
    ) {
        let mut shifted: Vec<f64> = l.iter().map(|x| x + offset).collect();
        let z = normalize_log_weights(&mut l).unwrap();
        let z_shifted = normalize_log_weights(&mut shifted).unwrap();
        prop_assert!((z_shifted - z - offset).abs() < 1e-9 * (1.0 + offset.abs()));
        for (a, b) in l.iter().zip(&shifted) {
            // Normalized log-weights agree (absolute error of ln scaled by the offset's ulp).
            prop_assert!((a - b).abs() < 1e-10 * (1.0 + offset.abs()), "{a} vs {b}");
        }
        let total: f64 = l.iter().map(|x| x.exp()).sum();
        prop_assert!((total - 1.0).abs() < 1e-12);
        prop_assert!((log_sum_exp(&l)).abs() < 1e-12);
    }

    #[test]
    fn ess_lies_between_one_and_n(mut l in log_weights()) {
        normalize_log_weights(&mut l).unwrap();
        let ess = effective_sample_size(&l);
        let n = l.len() as f64;
        prop_assert!(ess >= 1.0 - 1e-9 && ess <= n + 1e-9, "ess {ess}, n {n}");
    }

    #[test]
    fn ess_of_uniform_weights_is_n(n in 1usize..5000, level in -1e4..1e4f64) {
        let mut l = vec![level; n];
        normalize_log_weights(&mut l).unwrap();
        let ess = effective_sample_size(&l);
        prop_assert!((ess - n as f64).abs() < 1e-9 * n as f64, "ess {ess} for n {n}");
    }

    #[test]
    fn systematic_copies_are_within_one_of_expectation(
        weights in prop::collection::vec(prop_oneof![Just(0.0), 0.0..1.0f64], 1..200),
        n_out in 1usize..2000,
        u0 in 0.0..1.0f64,
    ) {
        let total: f64 = weights.iter().sum();
        prop_assume!(total > 0.0);
        let mut indices = Vec::new();
        systematic_resample(&weights, n_out, u0, &mut indices);
        prop_assert_eq!(indices.len(), n_out);
        prop_assert!(indices.windows(2).all(|w| w[0] <= w[1]));
        let counts = copy_counts(&indices, weights.len());
        for (i, (&c, &w)) in counts.iter().zip(&weights).enumerate() {
            let expected = n_out as f64 * w / total;
            // ⌊N wᵢ⌋ or ⌈N wᵢ⌉ copies (a hair of slack for rounding at interval borders).
            prop_assert!(
                (c as f64) > expected - 1.0 - 1e-9 && (c as f64) < expected + 1.0 + 1e-9,
                "particle {i}: {c} copies, expected {expected}"
            );
            if w == 0.0 {
                prop_assert_eq!(c, 0, "zero-weight particle {} copied", i);
            }
        }
    }
}

#[test]
fn systematic_resampling_matches_a_hand_computed_case() {
    // Weights 0.5, 0.3, 0.2 with N = 10 and pointers 0.05, 0.15, …, 0.95.
    let mut indices = Vec::new();
    systematic_resample(&[0.5, 0.3, 0.2], 10, 0.5, &mut indices);
    assert_eq!(copy_counts(&indices, 3), vec![5, 3, 2]);
}
