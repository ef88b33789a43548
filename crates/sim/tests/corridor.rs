//! The 1-D corridor: sample statistics match the distributions of the thesis setup.

#![allow(clippy::unwrap_used)]

use raypath_sim::corridor::{
    self, CORRIDOR_VOXELS, CorridorConfig, CorridorModel, CorridorWorld, REFLECTION_HIT_DEPTH_M,
};
use raypath_sim::no_progress;
use raypath_sim::rng::stream;

fn mean_var(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    (
        mean,
        values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n,
    )
}

#[test]
fn ground_truth_maps_follow_uniform_and_gamma() {
    let mut mu = Vec::new();
    let mut lambda = Vec::new();
    for seed in 0..300 {
        let w = CorridorWorld::sample(seed, CorridorModel::Reflection);
        assert_eq!(w.len(), CORRIDOR_VOXELS);
        assert!(w.values.iter().all(|v| (0.0..1.0).contains(v)));
        mu.extend(w.values);
        let w = CorridorWorld::sample(seed, CorridorModel::DecayRate);
        assert!(w.values.iter().all(|&v| v > 0.0));
        lambda.extend(w.values);
    }
    // 30 000 values each. U(0,1): mean 1/2, variance 1/12. Gamma(1,1): mean 1, variance 1.
    let (m, v) = mean_var(&mu);
    assert!((m - 0.5).abs() < 0.006, "{m}");
    assert!((v * 12.0 - 1.0).abs() < 0.03, "{v}");
    let (m, v) = mean_var(&lambda);
    assert!((m - 1.0).abs() < 0.02, "{m}");
    assert!((v - 1.0).abs() < 0.06, "{v}");
    // Different models of one seed draw from different streams.
    let a = CorridorWorld::sample(1, CorridorModel::Reflection);
    assert_eq!(a, CorridorWorld::sample(1, CorridorModel::Reflection));
    assert_ne!(
        a.values,
        CorridorWorld::sample(2, CorridorModel::Reflection).values
    );
}

#[test]
fn reflection_mapping_counts_are_binomial() {
    let world = CorridorWorld::sample(7, CorridorModel::Reflection);
    let n = 2000u32;
    let stats = world.map_statistics(n, &mut stream(7, 99, 0));
    let mut z2 = 0.0;
    for (i, &mu) in world.values.iter().enumerate() {
        assert_eq!(stats.hits[i] + stats.misses[i], n);
        let expected_r =
            f64::from(stats.misses[i]) + REFLECTION_HIT_DEPTH_M * f64::from(stats.hits[i]);
        assert!((stats.distance_m[i] - expected_r).abs() < 1e-9);
        let sd = (f64::from(n) * mu * (1.0 - mu)).sqrt().max(1e-9);
        let z = (f64::from(stats.hits[i]) - f64::from(n) * mu) / sd;
        assert!(z.abs() < 5.0, "voxel {i}: z = {z}");
        z2 += z * z;
    }
    // Σ z² over 100 voxels ~ χ²(100): mean 100, sd ≈ 14.
    assert!((50.0..160.0).contains(&z2), "{z2}");
}

#[test]
fn decay_rate_mapping_matches_the_truncated_exponential() {
    let world = CorridorWorld::sample(3, CorridorModel::DecayRate);
    let n = 2000u32;
    let stats = world.map_statistics(n, &mut stream(3, 99, 0));
    let (mut zh2, mut zr2) = (0.0, 0.0);
    for (i, &lambda) in world.values.iter().enumerate() {
        assert_eq!(stats.hits[i] + stats.misses[i], n);
        // Per visit: P(hit) = 1 − e^{−λ}; the distance min(t, 1) has mean (1 − e^{−λ})/λ and
        // second moment 2(1 − e^{−λ}(1 + λ))/λ².
        let p = 1.0 - (-lambda).exp();
        let sd = (f64::from(n) * p * (1.0 - p)).sqrt();
        let zh = (f64::from(stats.hits[i]) - f64::from(n) * p) / sd;
        let m1 = p / lambda;
        let m2 = 2.0 * (1.0 - (-lambda).exp() * (1.0 + lambda)) / (lambda * lambda);
        let sd_r = (f64::from(n) * (m2 - m1 * m1)).sqrt();
        let zr = (stats.distance_m[i] - f64::from(n) * m1) / sd_r;
        assert!(zh.abs() < 5.0 && zr.abs() < 5.0, "voxel {i}: {zh} {zr}");
        zh2 += zh * zh;
        zr2 += zr * zr;
    }
    assert!((50.0..160.0).contains(&zh2), "{zh2}");
    assert!((50.0..160.0).contains(&zr2), "{zr2}");
}

#[test]
fn observations_follow_the_model() {
    let world = CorridorWorld {
        model: CorridorModel::DecayRate,
        values: vec![0.7],
    };
    let mut rng = stream(1, 2, 3);
    let obs: Vec<_> = (0..40_000)
        .map(|_| world.observation(0, &mut rng).unwrap())
        .collect();
    assert!(world.observation(1, &mut rng).is_none());
    let hits: Vec<f64> = obs.iter().filter(|o| o.hit).map(|o| o.distance_m).collect();
    assert!(obs.iter().filter(|o| !o.hit).all(|o| o.distance_m == 1.0));
    let lambda = 0.7f64;
    let p = 1.0 - (-lambda).exp();
    let frac = hits.len() as f64 / obs.len() as f64;
    assert!((frac - p).abs() < 0.01, "{frac} vs {p}");
    // Hit depths: Exp(λ) truncated to [0, 1): mean 1/λ − e^{−λ}/(1 − e^{−λ}).
    let (m, _) = mean_var(&hits);
    let want = 1.0 / lambda - (-lambda).exp() / p;
    assert!((m - want).abs() < 0.01, "{m} vs {want}");
    assert!(hits.iter().all(|&d| (0.0..1.0).contains(&d)));

    // Reflection: hits with probability μ.
    let world = CorridorWorld {
        model: CorridorModel::Reflection,
        values: vec![0.25; CORRIDOR_VOXELS],
    };
    let loc = world.localization_observations(&mut rng);
    assert_eq!(loc.len(), CORRIDOR_VOXELS);
    let hits = (0..200)
        .flat_map(|_| world.localization_observations(&mut rng))
        .filter(|o| o.hit)
        .count();
    let frac = hits as f64 / 20_000.0;
    assert!((frac - 0.25).abs() < 0.01, "{frac}");
}

#[test]
fn generated_set_is_deterministic_and_readable() {
    let config = CorridorConfig::default();
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let set = corridor::generate(&config, 5, a.path(), no_progress()).unwrap();
    corridor::generate(&config, 5, b.path(), no_progress()).unwrap();
    assert_eq!(set.files.len(), 2 * (config.runs + 1));
    for f in &set.files {
        assert_eq!(
            std::fs::read(a.path().join(f)).unwrap(),
            std::fs::read(b.path().join(f)).unwrap()
        );
        if f.extension().unwrap() == "csv" {
            let s = raypath_io::summarize(&a.path().join(f)).unwrap();
            assert_eq!(s.points, Some(100));
        }
    }
    // The JSON runs are the API's runs.
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.path().join("corridor-decay-rate.json")).unwrap())
            .unwrap();
    let run = &json["runs"][1];
    let world_seed = run["world_seed"].as_u64().unwrap();
    assert_eq!(world_seed, corridor::run_seed(5, 1));
    let world = CorridorWorld::sample(world_seed, CorridorModel::DecayRate);
    let truth: Vec<f64> = serde_json::from_value(run["truth"].clone()).unwrap();
    // serde_json's default float parser may be off by an ulp (the file holds exact values).
    assert_eq!(truth.len(), world.values.len());
    assert!(
        truth
            .iter()
            .zip(&world.values)
            .all(|(a, b)| (a - b).abs() <= 1e-15 * b.abs())
    );
    let stats = world.map_statistics(10, &mut stream(world_seed, corridor::streams::MAPPING, 10));
    let hits: Vec<u32> = serde_json::from_value(run["mapping"][1]["hits"].clone()).unwrap();
    assert_eq!(hits, stats.hits);
    assert!(set.stats["decay-rate"]["truth_mean"].as_f64().unwrap() > 0.5);
}
