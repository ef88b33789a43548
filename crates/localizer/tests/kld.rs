//! KLD-sampling follows Fox's bound.

#![allow(clippy::unwrap_used)]

use raypath_geometry::Pose2;
use raypath_localizer::kld::{KldBins, KldConfig, kld_bound, normal_quantile};
use raypath_localizer::{FilterConfig, ParticleFilter};

/// Fox's bound by hand for k = 11, ε = 0.05, z = 2.326347874 (δ = 0.01).
#[test]
fn bound_matches_a_hand_computed_value() {
    let z = normal_quantile(0.99);
    let km1: f64 = 10.0;
    let a = 2.0 / (9.0 * km1);
    let expected = km1 / (2.0 * 0.05) * (1.0 - a + a.sqrt() * z).powi(3);
    assert!((kld_bound(11, 0.05, z) - expected).abs() < 1e-9);
    // 100 · (1 − 0.022222 + 0.149071 · 2.326348)³ = 100 · 1.324570³ = 232.39
    assert!((expected - 232.39).abs() < 0.01, "{expected}");
    assert_eq!(kld_bound(1, 0.05, z), 0.0);
    assert_eq!(kld_bound(0, 0.05, z), 0.0);
}

/// For many bins the bound approaches the χ² quantile / 2ε, whose normal approximation is
/// (k − 1) + z √(2(k − 1)).
#[test]
fn bound_approaches_the_chi_square_quantile() {
    let z = normal_quantile(0.99);
    for k in [1000usize, 10_000, 100_000] {
        let km1 = (k - 1) as f64;
        let chi2 = km1 + z * (2.0 * km1).sqrt();
        let bound = kld_bound(k, 0.01, z);
        let relative = (bound * 2.0 * 0.01 - chi2).abs() / chi2;
        assert!(relative < 0.005, "k {k}: {relative}");
    }
}

/// Particles spread over a grid of distinct bins with equal weights: after KLD resampling
/// the count n is the first at which n ≥ n(k) for the k bins drawn so far.
#[test]
fn resampled_count_follows_the_bound() {
    for (cells, epsilon) in [(5usize, 0.05), (20, 0.05), (60, 0.02), (200, 0.01)] {
        // One particle per 1 m × 1 m cell, bins of 1 m.
        let states: Vec<Pose2> = (0..cells)
            .map(|i| Pose2::new(i as f64 + 0.5, 0.5, 0.1))
            .collect();
        let kld = KldConfig {
            epsilon,
            delta: 0.01,
            bins: KldBins {
                xy_m: 1.0,
                z_m: 1.0,
                angle_rad: 1.0,
            },
            min_particles: 10,
            max_particles: 100_000,
        };
        let config = FilterConfig {
            kld: Some(kld),
            ..FilterConfig::default()
        };
        let mut filter = ParticleFilter::new(states, config, 7).unwrap();
        let report = filter.resample();
        let info = report.kld.unwrap();
        let n = report.particles_after;
        assert_eq!(n, filter.len());
        let bound = kld.bound(info.bins);
        assert!(info.bins <= cells);
        assert!(
            n as f64 >= bound && n >= kld.min_particles,
            "cells {cells}: n {n}, bound {bound}"
        );
        // It stopped at the first n that satisfied the rule: one fewer particle would not
        // have met the bound for the same (or fewer) bins, unless the minimum held it.
        assert!(
            (n - 1) as f64 <= bound || n == kld.min_particles,
            "cells {cells}: n {n} overshoots bound {bound}"
        );
        // With many samples every cell is drawn: k equals the number of cells.
        if n > 20 * cells {
            assert_eq!(info.bins, cells);
        }
    }
}

#[test]
fn a_collapsed_cloud_shrinks_to_the_minimum_and_max_is_respected() {
    let states = vec![Pose2::new(0.1, 0.1, 0.0); 1000];
    let kld = KldConfig {
        min_particles: 50,
        ..KldConfig::default()
    };
    let config = FilterConfig {
        kld: Some(kld),
        ..FilterConfig::default()
    };
    let mut filter = ParticleFilter::new(states, config, 1).unwrap();
    assert_eq!(filter.resample().particles_after, 50);

    let spread: Vec<Pose2> = (0..5000)
        .map(|i| Pose2::new(f64::from(i), 0.0, 0.0))
        .collect();
    let kld = KldConfig {
        max_particles: 300,
        ..KldConfig::default()
    };
    let mut filter = ParticleFilter::new(
        spread,
        FilterConfig {
            kld: Some(kld),
            ..FilterConfig::default()
        },
        1,
    )
    .unwrap();
    assert_eq!(filter.resample().particles_after, 300);
}
