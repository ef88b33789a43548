//! The random-measurement mixture of `LidarConfig::random_weight`: per beam
//! `ln((1 − ε) p + ε q)` in log space with `q(r) = 1 / (2 r_max)` for a return,
//! `q(sub) = r_min / (2 r_max)`, `q(sup) = 1/2`; ε = 0 is the model's own value; never NaN,
//! never below `ln(ε q)`.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use raypath_geometry::{Aabb2, Grid2, Pose2, Range, Scan2};
use raypath_localizer::MeasurementModel;
use raypath_localizer::lidar::{DEFAULT_RANDOM_WEIGHT, LidarConfig, Scan2Measurement};
use raypath_sensor_models::{
    DecayRateConfig, DecayRateModel2, DenseStats2, MappingConfig, SensorModel, SensorRange,
};

const R_MIN: f64 = 0.5;
const R_MAX: f64 = 30.0;

/// A 10 m × 8 m walled room mapped at 0.1 m from its centre, and the decay-rate model on it.
fn room_model() -> DecayRateModel2 {
    let (w, h) = (10.05, 8.05);
    let grid = Grid2::covering(&Aabb2::new([-1.0, -1.0].into(), [11.0, 9.0].into()), 0.1).unwrap();
    let mut stats = DenseStats2::new(grid);
    let mapping = MappingConfig::default();
    let mut scans = Vec::new();
    for pose in [Pose2::new(3.0, 3.0, 0.3), Pose2::new(6.5, 4.5, 2.0)] {
        let n = 360;
        let inc = std::f64::consts::TAU / n as f64;
        let ranges = (0..n)
            .map(|i| {
                let a = pose.theta() + i as f64 * inc;
                let (c, s) = (a.cos(), a.sin());
                let tx = if c > 1e-9 {
                    (w - pose.x()) / c
                } else if c < -1e-9 {
                    -pose.x() / c
                } else {
                    f64::INFINITY
                };
                let ty = if s > 1e-9 {
                    (h - pose.y()) / s
                } else if s < -1e-9 {
                    -pose.y() / s
                } else {
                    f64::INFINITY
                };
                tx.min(ty)
            })
            .collect();
        let scan = Scan2 {
            angle_min_rad: 0.0,
            angle_increment_rad: inc,
            max_range_m: R_MAX,
            ranges,
            intensities: None,
        };
        scans.push((pose, scan));
    }
    let refs: Vec<(Pose2, &Scan2)> = scans.iter().map(|(p, s)| (*p, s)).collect();
    stats.insert_scans_par(&refs, &mapping);
    DecayRateModel2::new(
        &stats,
        DecayRateConfig {
            range: SensorRange::new(R_MIN, R_MAX).unwrap(),
            ..DecayRateConfig::default()
        },
    )
    .unwrap()
}

/// A scan of single beams straight ahead: a plausible return, returns inside a wall's
/// shadow, a sub reading, a no-return (through a mapped wall) and a return beyond r_max.
fn beams() -> Vec<f64> {
    vec![7.0, 2.0, 6.9, 12.0, 0.2, R_MAX + 1.0, 81.91]
}

fn one_beam_scan(range_m: f64) -> Scan2 {
    Scan2 {
        angle_min_rad: 0.0,
        angle_increment_rad: 0.01,
        max_range_m: R_MAX,
        ranges: vec![range_m],
        intensities: None,
    }
}

fn config(eps: f64) -> LidarConfig {
    LidarConfig {
        beam_step: 1,
        effective_beams: None,
        random_weight: eps,
    }
}

#[test]
fn the_mixture_is_the_log_of_the_mixed_likelihood_per_beam() {
    let model = room_model();
    let pose = Pose2::new(3.0, 4.0, 0.0);
    let range = model.sensor_range();
    for eps in [0.0, 1e-3, DEFAULT_RANDOM_WEIGHT, 0.5, 0.99] {
        let adapter = Scan2Measurement::new(&model, Pose2::identity(), config(eps)).unwrap();
        for r in beams() {
            let scan = one_beam_scan(r);
            let ray = scan.rays(pose).next().unwrap();
            let ln_p = model.ray_log_likelihood(&ray);
            let got = adapter.log_likelihood(&pose, &adapter.prepare(&scan));
            assert!(!got.is_nan());
            if eps == 0.0 {
                assert_eq!(
                    got.to_bits(),
                    ln_p.to_bits(),
                    "ε = 0 must be the model's value"
                );
                continue;
            }
            let q = match range.classify(Range::Hit(r)) {
                raypath_sensor_models::Reading::Hit(_) => 1.0 / (2.0 * R_MAX),
                raypath_sensor_models::Reading::Sub => R_MIN / (2.0 * R_MAX),
                raypath_sensor_models::Reading::Sup => 0.5,
            };
            let expected = ((1.0 - eps) * ln_p.exp() + eps * q).ln();
            assert!(
                (got - expected).abs() <= 1e-12 * expected.abs().max(1.0),
                "r {r}, ε {eps}: {got} vs {expected} (ln p {ln_p})"
            );
            // Never below the random floor, never above the better of the two parts.
            assert!(got >= (eps * q).ln() - 1e-12);
            assert!(got <= ln_p.max(q.ln()) + 1e-12);
        }
    }
}

#[test]
fn outlier_beams_are_floored_and_nothing_is_nan() {
    let model = room_model();
    let eps = DEFAULT_RANDOM_WEIGHT;
    let mixed = Scan2Measurement::new(&model, Pose2::identity(), config(eps)).unwrap();
    let plain = Scan2Measurement::new(&model, Pose2::identity(), config(0.0)).unwrap();
    // A no-return from inside the room crosses a mapped wall: a huge penalty for the model,
    // ln(ε / 2) for the mixture.
    let no_return = Scan2 {
        ranges: vec![f64::INFINITY],
        ..one_beam_scan(0.0)
    };
    let pose = Pose2::new(3.0, 4.0, 0.0);
    let p_plain = plain.log_likelihood(&pose, &plain.prepare(&no_return));
    let p_mixed = mixed.log_likelihood(&pose, &mixed.prepare(&no_return));
    assert!(p_plain < -10.0, "{p_plain}");
    assert!((p_mixed - (eps / 2.0).ln()).abs() < 1e-4, "{p_mixed}");
    // Poses far outside the map, a NaN reading: finite (mixture) and never NaN.
    for pose in [Pose2::new(500.0, -300.0, 1.0), Pose2::new(5.0, 4.0, -2.0)] {
        for r in [f64::NAN, 0.0, 3.0, 1e9] {
            let scan = one_beam_scan(r);
            let v = mixed.log_likelihood(&pose, &mixed.prepare(&scan));
            assert!(v.is_finite(), "pose {pose:?}, r {r}: {v}");
            assert!(!plain.log_likelihood(&pose, &plain.prepare(&scan)).is_nan());
        }
    }
    // The true pose still scores best on a full scan with the mixture.
    let n = 180;
    let truth = Pose2::new(4.0, 3.5, 0.4);
    let scan = {
        let inc = std::f64::consts::PI / n as f64;
        let rays: Vec<f64> = (0..n)
            .map(|i| {
                let probe = one_beam_scan(R_MAX);
                let a = -std::f64::consts::FRAC_PI_2 + i as f64 * inc;
                let ray = probe
                    .rays(Pose2::new(truth.x(), truth.y(), truth.theta() + a))
                    .next()
                    .unwrap();
                // Distance to the room's walls along the ray.
                let (c, s) = (ray.direction.x, ray.direction.y);
                let tx = if c > 1e-9 {
                    (10.05 - truth.x()) / c
                } else if c < -1e-9 {
                    -truth.x() / c
                } else {
                    f64::INFINITY
                };
                let ty = if s > 1e-9 {
                    (8.05 - truth.y()) / s
                } else if s < -1e-9 {
                    -truth.y() / s
                } else {
                    f64::INFINITY
                };
                tx.min(ty)
            })
            .collect();
        Scan2 {
            angle_min_rad: -std::f64::consts::FRAC_PI_2,
            angle_increment_rad: inc,
            max_range_m: R_MAX,
            ranges: rays,
            intensities: None,
        }
    };
    let prepared = mixed.prepare(&scan);
    let at_truth = mixed.log_likelihood(&truth, &prepared);
    for off in [
        Pose2::new(0.3, 0.0, 0.0),
        Pose2::new(0.0, -0.2, 0.0),
        Pose2::new(0.0, 0.0, 0.05),
    ] {
        assert!(at_truth > mixed.log_likelihood(&(truth * off), &prepared));
    }
}

#[test]
fn the_weight_is_checked() {
    let model = room_model();
    for eps in [-0.1, 1.0, 1.5, f64::NAN, f64::INFINITY] {
        assert!(
            Scan2Measurement::new(&model, Pose2::identity(), config(eps)).is_err(),
            "{eps}"
        );
    }
    assert_eq!(LidarConfig::default().random_weight, DEFAULT_RANDOM_WEIGHT);
    assert!(Scan2Measurement::new(&model, Pose2::identity(), config(0.0)).is_ok());
}
