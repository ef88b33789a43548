//! The scoring of Tables 7.3 / 8.2 / 8.3 on synthetic worlds where the truth is known:
//! true poses score best, the metrics have their known answers, rows follow the contract,
//! results are deterministic and independent of the thread count.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use nalgebra::{Point3, Vector3};
use raypath_geometry::{Pose2, Pose3, Range, Ray3, Scan2};
use raypath_sensor_models::scoring::{
    MODEL_NAMES, ScoreReport, ScoringConfig, Split, disc_offsets, divergences, log_sum_exp,
    score_log, score_planar, score_spatial,
};

/// Axis-aligned boxes `[x0, x1] × [y0, y1]` inside a closed room `[0, 20] × [0, 12]`.
const OBSTACLES: [[f64; 4]; 5] = [
    [4.0, 5.0, 3.0, 4.0],
    [12.0, 14.0, 7.0, 8.0],
    [8.0, 8.5, 1.0, 4.5],
    [15.0, 16.0, 2.0, 3.0],
    [6.0, 6.4, 8.5, 11.0],
];
const ROOM: [f64; 4] = [0.0, 20.0, 0.0, 12.0];
const MAX_RANGE_M: f64 = 10.0;

/// Slab intersection of the ray `o + t d` with a box: `(t_enter, t_exit)`.
fn slabs(o: [f64; 2], d: [f64; 2], b: [f64; 4]) -> (f64, f64) {
    let mut t0 = f64::NEG_INFINITY;
    let mut t1 = f64::INFINITY;
    for axis in 0..2 {
        let (lo, hi) = (b[2 * axis], b[2 * axis + 1]);
        if d[axis] == 0.0 {
            if o[axis] < lo || o[axis] > hi {
                return (f64::INFINITY, f64::NEG_INFINITY);
            }
            continue;
        }
        let (a, c) = ((lo - o[axis]) / d[axis], (hi - o[axis]) / d[axis]);
        t0 = t0.max(a.min(c));
        t1 = t1.min(a.max(c));
    }
    (t0, t1)
}

/// Range to the first surface along the ray from `o` in direction `d` (unit).
fn cast(o: [f64; 2], d: [f64; 2]) -> f64 {
    let mut t = slabs(o, d, ROOM).1; // leaving the room = hitting its wall
    for b in OBSTACLES {
        let (t0, t1) = slabs(o, d, b);
        if t0 <= t1 && t0 > 0.0 {
            t = t.min(t0);
        }
    }
    t
}

/// A 360° scan of 120 beams from `pose`; ranges beyond `MAX_RANGE_M` are no-returns.
fn scan_at(pose: &Pose2) -> Scan2 {
    let n = 120;
    let increment = std::f64::consts::TAU / n as f64;
    let angle_min = -std::f64::consts::PI;
    let ranges = (0..n)
        .map(|i| {
            let a = pose.theta() + angle_min + i as f64 * increment;
            let r = cast([pose.x(), pose.y()], [a.cos(), a.sin()]);
            if r >= MAX_RANGE_M { 20.0 } else { r }
        })
        .collect();
    Scan2 {
        angle_min_rad: angle_min,
        angle_increment_rad: increment,
        max_range_m: MAX_RANGE_M,
        ranges,
        intensities: None,
    }
}

/// A loop through the free space: out along y = 5.6, back along y = 10.
fn trajectory() -> Vec<Pose2> {
    let mut poses = Vec::new();
    for i in 0..40 {
        let x = 2.0 + 16.0 * i as f64 / 39.0;
        poses.push(Pose2::new(
            x,
            5.6 + 0.2 * (i as f64 * 0.7).sin(),
            0.1 * (i as f64).cos(),
        ));
    }
    for i in 0..40 {
        let x = 18.0 - 16.0 * i as f64 / 39.0;
        poses.push(Pose2::new(
            x,
            10.0,
            std::f64::consts::PI + 0.05 * (i as f64).sin(),
        ));
    }
    poses
}

fn log() -> Vec<(Pose2, Scan2)> {
    trajectory().into_iter().map(|p| (p, scan_at(&p))).collect()
}

fn quick_config() -> ScoringConfig {
    ScoringConfig {
        poses_per_scan: 20,
        disc_radius_m: 0.5,
        ..ScoringConfig::default()
    }
}

/// Scans with their poses, borrowed.
type Scans<'a> = Vec<(Pose2, &'a Scan2)>;

fn split(scans: &[(Pose2, Scan2)]) -> (Scans<'_>, Scans<'_>) {
    let map = scans.iter().step_by(2).map(|(p, s)| (*p, s)).collect();
    let test = scans
        .iter()
        .skip(1)
        .step_by(2)
        .map(|(p, s)| (*p, s))
        .collect();
    (map, test)
}

fn d_prime(report: &ScoreReport) -> Vec<f64> {
    report.rows.iter().map(|r| r.neg_log_likelihood).collect()
}

#[test]
fn rows_follow_the_contract() {
    let report = score_log(&log(), &quick_config()).unwrap();
    let names: Vec<(&str, bool)> = report
        .rows
        .iter()
        .map(|r| (r.model.as_str(), r.posterior))
        .collect();
    assert_eq!(
        names,
        [
            ("decay-rate", false),
            ("decay-rate", true),
            ("reflection", false),
            ("reflection", true),
            ("endpoint", false),
            ("likelihood-field", false),
            ("log-odds", false),
        ]
    );
    assert!(names.iter().all(|(n, _)| MODEL_NAMES.contains(n)));
    assert_eq!(report.mapping_scans, 40);
    assert_eq!(report.test_scans, 40);
    assert_eq!(report.test_rays, 40 * 120);
    assert_eq!(report.max_range_m, MAX_RANGE_M);
    for row in &report.rows {
        assert!(row.neg_log_likelihood.is_finite(), "{row:?}");
        // Both divergences are KLs between distributions on the samples: ≥ 0.
        assert!(
            row.inverse_kl >= -1e-9 && row.inverse_kl.is_finite(),
            "{row:?}"
        );
        assert!(
            row.kl_ground_truth >= -1e-9 && row.kl_ground_truth.is_finite(),
            "{row:?}"
        );
        assert_eq!(row.evaluations, 40 * 120 * 21);
    }
}

#[test]
fn true_poses_score_best_for_every_model() {
    let scans = log();
    let (map, test) = split(&scans);
    let config = quick_config();
    let truth = d_prime(&score_planar(&map, &test, &config).unwrap());
    for (dx, dy, dtheta) in [
        (0.25, 0.0, 0.0),
        (0.0, -0.25, 0.0),
        (-0.15, 0.15, 0.0),
        (0.0, 0.0, 0.05),
    ] {
        let shifted: Vec<(Pose2, &Scan2)> = test
            .iter()
            .map(|(p, s)| (Pose2::new(p.x() + dx, p.y() + dy, p.theta() + dtheta), *s))
            .collect();
        let report = score_planar(&map, &shifted, &config).unwrap();
        for (row, at_truth) in report.rows.iter().zip(&truth) {
            assert!(
                *at_truth < row.neg_log_likelihood,
                "{} (posterior {}): D' at truth {at_truth} not below {} at ({dx}, {dy}, {dtheta})",
                row.model,
                row.posterior,
                row.neg_log_likelihood
            );
        }
    }
}

#[test]
fn the_same_seed_gives_the_same_figures_on_any_thread_count() {
    let scans = log();
    let config = ScoringConfig {
        seed: 42,
        ..quick_config()
    };
    let strip = |report: ScoreReport| -> Vec<(f64, f64, f64)> {
        report
            .rows
            .iter()
            .map(|r| (r.neg_log_likelihood, r.inverse_kl, r.kl_ground_truth))
            .collect()
    };
    let a = strip(score_log(&scans, &config).unwrap());
    let b = strip(score_log(&scans, &config).unwrap());
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| strip(score_log(&scans, &config).unwrap()));
    assert_eq!(a, b);
    assert_eq!(a, one_thread);
    let other = strip(score_log(&scans, &ScoringConfig { seed: 43, ..config }).unwrap());
    // D' does not depend on the samples; the divergences do.
    for (x, y) in a.iter().zip(&other) {
        assert_eq!(x.0, y.0);
        assert_ne!(x.1, y.1);
    }
}

#[test]
fn a_flat_pose_distribution_has_the_known_inverse_kl() {
    // A model that gives every sample the same likelihood: p̂_i = 1/M, so
    // D(h‖g) = Σ (1/M) ln((1/M) / ĝ_i) = −ln M − (1/M) Σ ln ĝ_i.
    let m = 50;
    let sigma = 0.05;
    let offsets = disc_offsets(3, 17, m, 2.5);
    let log_g: Vec<f64> = offsets
        .iter()
        .map(|[x, y]| -(x * x + y * y) / (2.0 * sigma * sigma))
        .collect();
    let z = log_sum_exp(&log_g);
    let expected = -(m as f64).ln() - log_g.iter().map(|g| g - z).sum::<f64>() / m as f64;
    let d = divergences(&vec![-123.0; m], &offsets, sigma);
    assert!(
        (d.inverse_kl - expected).abs() < 1e-9 * expected.abs(),
        "{d:?} vs {expected}"
    );
    // The ground-truth KL of a flat model: Σ ĝ ln(ĝ · M).
    let kl: f64 = log_g
        .iter()
        .map(|g| (g - z).exp() * ((g - z) + (m as f64).ln()))
        .sum();
    assert!((d.kl_ground_truth - kl).abs() < 1e-9, "{d:?} vs {kl}");
    // A model that puts all mass on the sample nearest to the truth, where ĝ is largest:
    // inverse KL = −ln ĝ_nearest, ground-truth KL → ∞ as the other samples vanish.
    let nearest = (0..m)
        .max_by(|&a, &b| log_g[a].total_cmp(&log_g[b]))
        .unwrap();
    let mut peaked = vec![-1e6; m];
    peaked[nearest] = 0.0;
    let d = divergences(&peaked, &offsets, sigma);
    assert!((d.inverse_kl + (log_g[nearest] - z)).abs() < 1e-9, "{d:?}");
}

#[test]
fn a_model_closer_to_the_truth_has_the_smaller_divergences() {
    let offsets = disc_offsets(0, 0, 50, 2.5);
    let sigma = 0.05;
    // Gaussian pose likelihoods of growing width around the truth: the narrowest is the
    // closest to the ground truth in both directions.
    let model = |width: f64| -> Vec<f64> {
        offsets
            .iter()
            .map(|[x, y]| -(x * x + y * y) / (2.0 * width * width))
            .collect()
    };
    let d: Vec<_> = [0.1, 0.3, 1.0, 3.0]
        .iter()
        .map(|&w| divergences(&model(w), &offsets, sigma))
        .collect();
    for pair in d.windows(2) {
        assert!(pair[0].inverse_kl < pair[1].inverse_kl, "{d:?}");
        assert!(pair[0].kl_ground_truth < pair[1].kl_ground_truth, "{d:?}");
    }
}

#[test]
fn halves_split_and_thinning() {
    let scans = log();
    let config = ScoringConfig {
        split: Split::Halves,
        max_test_scans: Some(7),
        ..quick_config()
    };
    let report = score_log(&scans, &config).unwrap();
    assert_eq!(report.mapping_scans, 40);
    // 40 test scans thinned with step ceil(40 / 7) = 6: indices 0, 6, …, 36.
    assert_eq!(report.test_scans, 7);
    assert!(Split::Alternate.is_test(3, 10) && !Split::Alternate.is_test(4, 10));
    assert!(Split::Halves.is_test(5, 10) && !Split::Halves.is_test(4, 10));
    assert_eq!(Split::from_name("halves"), Some(Split::Halves));
    assert_eq!(Split::from_name("nope"), None);
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let scans = log();
    let (map, test) = split(&scans);
    assert!(score_planar(&map, &[], &quick_config()).is_err());
    assert!(score_planar(&[], &test, &quick_config()).is_err());
    for config in [
        ScoringConfig {
            resolution_m: 0.0,
            ..quick_config()
        },
        ScoringConfig {
            poses_per_scan: 1,
            ..quick_config()
        },
        ScoringConfig {
            beam_step: 0,
            ..quick_config()
        },
        ScoringConfig {
            max_range_m: Some(f64::NAN),
            ..quick_config()
        },
        ScoringConfig {
            max_cells: 1000,
            ..quick_config()
        },
    ] {
        assert!(score_planar(&map, &test, &config).is_err(), "{config:?}");
    }
    let mut bad = test.clone();
    bad[0].0 = Pose2::new(f64::NAN, 0.0, 0.0);
    assert!(score_planar(&map, &bad, &quick_config()).is_err());
}

/// 3-D: the same room extruded to 4 m height with floor and ceiling, scanned by a fan of
/// rays at several elevations; the true poses beat shifted ones for every model.
#[test]
fn spatial_true_poses_score_best() {
    let rays_in_sensor = |pose: &Pose3| -> Vec<Ray3> {
        let origin = pose.translation();
        let mut rays = Vec::new();
        for e in [-0.3f64, -0.15, 0.0, 0.15, 0.3] {
            for i in 0..90 {
                let a = std::f64::consts::TAU * i as f64 / 90.0;
                let d_sensor = Vector3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin());
                let d = pose.transform_vector(&d_sensor);
                let horizontal = d.xy().norm();
                let r_wall = if horizontal > 1e-9 {
                    cast([origin.x, origin.y], [d.x / horizontal, d.y / horizontal]) / horizontal
                } else {
                    f64::INFINITY
                };
                let r_floor = if d.z < 0.0 {
                    -origin.z / d.z
                } else {
                    (4.0 - origin.z) / d.z.max(1e-12)
                };
                let r = r_wall.min(r_floor);
                let range = if r < MAX_RANGE_M {
                    Range::Hit(r)
                } else {
                    Range::NoReturn
                };
                rays.push(Ray3::new(Point3::origin(), d_sensor, range).unwrap());
            }
        }
        rays
    };
    let poses: Vec<Pose3> = trajectory()
        .iter()
        .map(|p| Pose3::from_xyz_rpy(p.x(), p.y(), 1.5, 0.0, 0.0, p.theta()))
        .collect();
    let rays: Vec<Vec<Ray3>> = poses.iter().map(rays_in_sensor).collect();
    let scans: Vec<(Pose3, &[Ray3])> = poses
        .iter()
        .zip(&rays)
        .map(|(p, r)| (*p, r.as_slice()))
        .collect();
    let map: Vec<_> = scans.iter().step_by(2).copied().collect();
    let test: Vec<_> = scans.iter().skip(1).step_by(2).copied().collect();
    let config = ScoringConfig {
        resolution_m: 0.25,
        max_range_m: Some(MAX_RANGE_M),
        max_test_scans: Some(10),
        ..quick_config()
    };
    assert!(
        score_spatial(
            &map,
            &test,
            &ScoringConfig {
                max_range_m: None,
                ..config
            }
        )
        .is_err()
    );
    let truth = score_spatial(&map, &test, &config).unwrap();
    assert_eq!(truth.test_rays, 10 * 450);
    assert_eq!(truth.rows.len(), 7);
    let shifted: Vec<(Pose3, &[Ray3])> = test
        .iter()
        .map(|(p, r)| {
            (
                Pose3::from_parts(p.translation() + Vector3::new(0.2, -0.2, 0.0), p.rotation()),
                *r,
            )
        })
        .collect();
    let off = score_spatial(&map, &shifted, &config).unwrap();
    for (t, o) in truth.rows.iter().zip(&off.rows) {
        assert!(
            t.neg_log_likelihood < o.neg_log_likelihood,
            "{} (posterior {}): {} vs {}",
            t.model,
            t.posterior,
            t.neg_log_likelihood,
            o.neg_log_likelihood
        );
        assert!(t.inverse_kl.is_finite() && t.kl_ground_truth.is_finite());
    }
}
