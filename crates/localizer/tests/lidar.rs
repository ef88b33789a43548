//! The lidar adapters: equal to `ScanLikelihood` on the composed pose, tempered by the
//! exponent, deterministic for a seed on 1 and 2 threads, and MCL converges on a simulated
//! indoor log.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use nalgebra::{Point2, Point3};
use raypath_geometry::{Aabb2, Grid2, Grid3, Pose2, Pose3, Range, Ray2, Ray3, Scan2};
use raypath_localizer::eval::{EvaluationConfig, evaluate_trajectory};
use raypath_localizer::init::GaussianInit;
use raypath_localizer::lidar::{
    LidarConfig, ModelKind, ModelSpec, PlanarStep, Scan2Measurement, Scan3Measurement, TrackConfig,
    track_planar,
};
use raypath_localizer::{MeasurementModel, PoseTrack, Stamped};
use raypath_sensor_models::{
    CellStats, DecayRateConfig, DecayRateModel2, DecayRateModel3, DecayRatePosteriorModel2,
    DenseStats2, DenseStats3, GammaPosteriorConfig, GammaPrior, MappingConfig, OpticalDepthConfig,
    ScanLikelihood, SensorModel,
};
use raypath_sim::indoor::{FloorPlanConfig, Laser2Config, WorldConfig, simulate_world};

/// A 10 m × 8 m box room scanned from a few poses, mapped at 0.1 m.
fn room() -> (DenseStats2, Vec<(Pose2, Scan2)>) {
    let (w, h) = (10.05, 8.05);
    let scan_at = |pose: Pose2| {
        let n = 181;
        let inc = std::f64::consts::PI / 180.0;
        let min = -std::f64::consts::FRAC_PI_2;
        let ranges = (0..n)
            .map(|i| {
                let a = pose.theta() + min + i as f64 * inc;
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
        Scan2 {
            angle_min_rad: min,
            angle_increment_rad: inc,
            max_range_m: 30.0,
            ranges,
            intensities: None,
        }
    };
    let poses = [
        Pose2::new(3.0, 3.0, 0.3),
        Pose2::new(6.0, 4.0, 2.0),
        Pose2::new(5.0, 2.5, -1.0),
        Pose2::new(7.5, 6.0, 3.5),
    ];
    let scans: Vec<(Pose2, Scan2)> = poses.iter().map(|p| (*p, scan_at(*p))).collect();
    let grid = Grid2::covering(
        &Aabb2::new(Point2::new(-1.0, -1.0), Point2::new(w + 1.0, h + 1.0)),
        0.1,
    )
    .unwrap();
    let mut stats = DenseStats2::new(grid);
    let refs: Vec<(Pose2, &Scan2)> = scans.iter().map(|(p, s)| (*p, s)).collect();
    stats.insert_scans_par(&refs, &MappingConfig::default());
    (stats, scans)
}

#[test]
fn planar_adapter_equals_scan_likelihood_on_the_laser_pose() {
    let (stats, scans) = room();
    let model = DecayRateModel2::new(&stats, DecayRateConfig::default()).unwrap();
    let robot_from_laser = Pose2::new(0.2, -0.05, 0.1);
    for step in [1, 3] {
        let plain = LidarConfig {
            beam_step: step,
            effective_beams: None,
            random_weight: 0.0,
        };
        let adapter = Scan2Measurement::new(&model, robot_from_laser, plain).unwrap();
        let reference = ScanLikelihood::new(&model).with_beam_step(step);
        for (pose, scan) in &scans {
            let prepared = adapter.prepare(scan);
            assert_eq!(prepared.len(), scan.len().div_ceil(step));
            let reference_prepared = reference.prepare(scan);
            for offset in [
                Pose2::identity(),
                Pose2::new(0.3, -0.2, 0.05),
                Pose2::new(-0.17, 0.23, -0.04),
            ] {
                // A robot pose whose laser lands at `pose * offset`.
                let world_from_robot = *pose * offset * robot_from_laser.inverse();
                let world_from_laser = world_from_robot * robot_from_laser;
                let got = adapter.log_likelihood(&world_from_robot, &prepared);
                // Bit-identical to the scan adapter's prepared path on the composed pose.
                let expected =
                    reference.log_likelihood_prepared(&world_from_laser, &reference_prepared);
                assert!(expected.is_finite());
                assert_eq!(got, expected, "step {step}");
                // And to the per-ray sum away from the mapping poses (at them, rays end on
                // the very cell faces the map was built from, where one ulp of pose
                // round-off moves an endpoint into the neighbouring cell).
                if offset != Pose2::identity() {
                    let direct = reference.log_likelihood(&world_from_laser, scan);
                    assert!(
                        (got - direct).abs() <= 1e-9 * direct.abs().max(1.0),
                        "step {step}: {got} vs {direct}"
                    );
                }
            }
        }
        // The exponent scales the sum: γ = 8 / kept beams.
        let tempered = Scan2Measurement::new(
            &model,
            robot_from_laser,
            LidarConfig {
                beam_step: step,
                effective_beams: Some(8.0),
                ..LidarConfig::default()
            },
        )
        .unwrap();
        let (pose, scan) = &scans[0];
        let prepared = tempered.prepare(scan);
        let gamma = 8.0 / prepared.len() as f64;
        assert!((prepared.exponent() - gamma).abs() < 1e-15);
        let robot = *pose * robot_from_laser.inverse();
        let raw = tempered.raw_log_likelihood(&robot, &prepared);
        let got = tempered.log_likelihood(&robot, &prepared);
        assert!((got - gamma * raw).abs() <= 1e-12 * raw.abs());
    }
}

#[test]
fn the_true_pose_scores_best() {
    let (stats, scans) = room();
    for kind in [
        ModelKind::DecayRate,
        ModelKind::Reflection,
        ModelKind::Endpoint,
    ] {
        let model = ModelSpec::exact(kind)
            .build(&stats, MappingConfig::default().range)
            .unwrap();
        let adapter =
            Scan2Measurement::new(model.as_ref(), Pose2::identity(), LidarConfig::default())
                .unwrap();
        for (pose, scan) in &scans {
            let prepared = adapter.prepare(scan);
            let at_truth = adapter.log_likelihood(pose, &prepared);
            for d in [
                Pose2::new(0.3, 0.0, 0.0),
                Pose2::new(0.0, 0.3, 0.0),
                Pose2::new(0.0, 0.0, 0.1),
            ] {
                let off = adapter.log_likelihood(&(*pose * d), &prepared);
                assert!(at_truth > off, "{kind}: {at_truth} ≤ {off} at offset {d:?}");
            }
        }
    }
}

#[test]
fn model_spec_parses_names_and_rejects_bad_configs() {
    for kind in ModelKind::ALL {
        assert_eq!(kind.name().parse::<ModelKind>().unwrap(), kind);
    }
    assert!("laser".parse::<ModelKind>().is_err());
    let (stats, _) = room();
    let bad = LidarConfig {
        beam_step: 0,
        effective_beams: None,
        ..LidarConfig::default()
    };
    let model = DecayRateModel2::new(&stats, DecayRateConfig::default()).unwrap();
    assert!(Scan2Measurement::new(&model, Pose2::identity(), bad).is_err());
    let bad = LidarConfig {
        beam_step: 1,
        effective_beams: Some(f64::NAN),
        ..LidarConfig::default()
    };
    assert!(Scan2Measurement::new(&model, Pose2::identity(), bad).is_err());
}

#[test]
fn spatial_adapter_equals_rays_log_likelihood_on_the_sensor_pose() {
    // A 3-D box: floor at z = 0, a wall at x = 8.
    let grid = Grid3::covering(
        &raypath_geometry::Aabb3::new(Point3::new(-2.0, -6.0, -1.0), Point3::new(10.0, 6.0, 4.0)),
        0.5,
    )
    .unwrap();
    let mut stats = DenseStats3::new(grid);
    let origin = Point3::new(1.0, 0.0, 1.5);
    let mut rays = Vec::new();
    for i in 0..40 {
        for j in 0..6 {
            let yaw = -0.8 + 1.6 * i as f64 / 39.0;
            let pitch = -0.05 - 0.04 * j as f64;
            let d = nalgebra::Vector3::new(
                yaw.cos() * pitch.cos(),
                yaw.sin() * pitch.cos(),
                pitch.sin(),
            );
            let t_wall = (8.0 - origin.x) / d.x;
            let t_floor = -origin.z / d.z;
            let t = t_wall.min(t_floor);
            rays.push(Ray3::new(origin, d, Range::Hit(t)).unwrap());
        }
    }
    stats.insert_rays_par(&rays, &MappingConfig::default());
    let model = DecayRateModel3::new(&stats, DecayRateConfig::default()).unwrap();
    let robot_from_sensor = Pose3::from_xyz_rpy(0.0, 0.0, 1.5, 0.0, 0.0, 0.0);
    let adapter = Scan3Measurement::new(
        &model,
        robot_from_sensor,
        LidarConfig {
            beam_step: 2,
            effective_beams: None,
            random_weight: 0.0,
        },
    )
    .unwrap();
    let rays_in_sensor: Vec<Ray3> = rays
        .iter()
        .map(|r| Ray3 {
            origin: Point3::origin(),
            ..*r
        })
        .collect();
    let scan = adapter.prepare_rays(&rays_in_sensor);
    assert_eq!(scan.len(), rays.len().div_ceil(2));
    let reference = ScanLikelihood::new(&model).with_beam_step(2);
    let world_from_robot = Pose3::from_xyz_rpy(1.1, 0.1, 0.0, 0.0, 0.01, 0.05);
    let expected =
        reference.rays_log_likelihood(&(world_from_robot * robot_from_sensor), &rays_in_sensor);
    let got = adapter.log_likelihood(&world_from_robot, &scan);
    assert!(expected.is_finite());
    assert!((got - expected).abs() <= 1e-9 * expected.abs());
    let truth = Pose3::from_xyz_rpy(1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    assert!(adapter.log_likelihood(&truth, &scan) > got);
}

/// A small simulated office: map from the even scans at the true laser poses, the filter on
/// the odd scans with the simulated (drifting) odometry.
fn simulated_office() -> (DenseStats2, Vec<PlanarStep>, PoseTrack<Pose2>, Pose2) {
    let config = WorldConfig::new(
        "office",
        FloorPlanConfig {
            width_m: 14.0,
            height_m: 10.0,
            ..FloorPlanConfig::default()
        },
        Laser2Config::sick_180(),
        240,
    );
    let run = simulate_world(&config, 11, raypath_sim::no_progress()).unwrap();
    let robot_from_laser = config.laser.robot_from_laser();
    let l = &config.laser;
    let scans: Vec<Scan2> = run
        .scans
        .iter()
        .map(|s| Scan2 {
            angle_min_rad: l.angle_min_rad,
            angle_increment_rad: l.angle_increment_rad,
            max_range_m: l.max_range_m,
            ranges: s.ranges.clone(),
            intensities: None,
        })
        .collect();
    let grid = Grid2::covering(
        &Aabb2::new(Point2::new(-1.0, -1.0), Point2::new(15.0, 11.0)),
        0.1,
    )
    .unwrap();
    let mut stats = DenseStats2::new(grid);
    let refs: Vec<(Pose2, &Scan2)> = run
        .laser_poses
        .iter()
        .zip(&scans)
        .step_by(2)
        .map(|(p, s)| (*p, s))
        .collect();
    stats.insert_scans_par(&refs, &MappingConfig::default());
    let mut steps = Vec::new();
    let mut truth = Vec::new();
    for k in (1..scans.len()).step_by(2) {
        steps.push(PlanarStep {
            stamp_secs: run.scan_times[k],
            odom_from_robot: run.scan_odometry[k],
            scan: scans[k].clone(),
            force_update: true,
        });
        truth.push(Stamped::new(
            run.scan_times[k],
            run.laser_poses[k] * robot_from_laser.inverse(),
        ));
    }
    (
        stats,
        steps,
        PoseTrack::new(truth).unwrap(),
        robot_from_laser,
    )
}

#[test]
fn mcl_converges_on_a_simulated_office_and_is_deterministic_on_1_and_2_threads() {
    let (stats, steps, truth, robot_from_laser) = simulated_office();
    let model = ModelSpec::exact(ModelKind::Endpoint)
        .build(&stats, MappingConfig::default().range)
        .unwrap();
    let lidar = LidarConfig {
        beam_step: 4,
        ..LidarConfig::default()
    };
    let measurement = Scan2Measurement::new(model.as_ref(), robot_from_laser, lidar).unwrap();
    let start = truth.poses()[0];
    // A poor start: the mean 0.7 m and 0.1 rad off, σ 1 m / 0.1 rad (thesis ch. 7).
    let init = GaussianInit::new(start * Pose2::new(0.5, -0.5, 0.1));
    let config = TrackConfig {
        particles: 400,
        ..TrackConfig::default()
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| track_planar(&steps, &measurement, &init, &config, 5).unwrap())
    };
    let one = run(1);
    let two = run(2);
    assert_eq!(one.estimates.len(), two.estimates.len());
    for (a, b) in one.estimates.iter().zip(&two.estimates) {
        assert_eq!(a.1.pose, b.1.pose, "thread count changed the estimate");
    }
    assert_eq!(one.updates, steps.len());
    let evaluation =
        evaluate_trajectory(&truth, &one.track().unwrap(), &EvaluationConfig::default()).unwrap();
    // After convergence (second half of the path) the error is small.
    let late: Vec<f64> = evaluation
        .points
        .iter()
        .skip(evaluation.points.len() / 2)
        .map(|p| p.position_error_m)
        .collect();
    let late_mean = late.iter().sum::<f64>() / late.len() as f64;
    eprintln!(
        "path {:.1} m, mean error {:.3} m, late mean {late_mean:.3} m",
        evaluation.length_m, evaluation.position_m.mean_abs
    );
    assert!(evaluation.length_m > 10.0);
    assert!(late_mean < 0.25, "late mean error {late_mean}");
    assert!(evaluation.heading_rad.mean_abs < 0.1);
}

/// The no-mixture, untempered adapter settings: the scan weight is the plain sum of the ray
/// log-likelihoods (Eq. 7.15).
const PLAIN: LidarConfig = LidarConfig {
    beam_step: 1,
    effective_beams: None,
    random_weight: 0.0,
};

/// The decay-rate full map posterior as the filter builds it (`ModelSpec` with `posterior`)
/// is the sensor-models model with the method-of-moments prior (Sec. 8.5), and on known rays
/// both equal the closed form of Sec. 8.4.5 written out here as the reference:
/// `ln L = −Σ_i (H_i + α) ln(1 + r_i / (R_i + β)) + ln(H_k + α) − ln(R_k + β + r_k)`.
/// The filter's adapter weighs a one-beam scan with exactly that value; the tabulated
/// variant stays close.
#[test]
fn decay_rate_fmp_in_the_filter_is_the_closed_form_posterior() {
    let (stats, scans) = room();
    let range = MappingConfig::default().range;
    let exact = ModelSpec {
        kind: ModelKind::DecayRate,
        posterior: true,
        tabulated: None,
    };
    let tabulated = ModelSpec {
        tabulated: Some(OpticalDepthConfig::default()),
        ..exact
    };
    assert_eq!(exact.label(), "decay-rate (FMP)");
    assert_eq!(tabulated.label(), "decay-rate (FMP) [table]");
    let built = exact.build(&stats, range).unwrap();
    let built_table = tabulated.build(&stats, range).unwrap();
    let library =
        DecayRatePosteriorModel2::new(&stats, GammaPosteriorConfig { range, prior: None }).unwrap();
    let prior = GammaPrior::estimate(stats.cells());
    assert_eq!(library.prior(), prior);
    let reference = |ray: &Ray2| {
        let crossings: Vec<_> = stats.grid().traverse_ray(ray, range.max_range_m).collect();
        let mut value = 0.0;
        for c in &crossings {
            let cell = stats.cell(c.index);
            let (a, b) = (cell.h() + prior.alpha, cell.path_length_m() + prior.beta);
            value -= a * (c.length() / b).ln_1p();
        }
        let k = crossings.last().unwrap();
        let cell = stats.cell(k.index);
        let (a, b) = (cell.h() + prior.alpha, cell.path_length_m() + prior.beta);
        value + a.ln() - (b + k.length()).ln()
    };
    // Beams of the mapping scans seen from 0.13 m / 0.05 rad off the mapping pose (so that
    // no endpoint lies on a cell face).
    let (pose, scan) = &scans[1];
    let off = *pose * Pose2::new(0.13, -0.07, 0.05);
    let (mut sum_exact, mut sum_table) = (0.0, 0.0);
    for (j, ray) in scan.rays(off).enumerate().step_by(15) {
        let expected = reference(&ray);
        let got = built.ray_log_likelihood(&ray);
        assert!(expected.is_finite(), "{expected}");
        assert!((got - expected).abs() < 1e-9 * (1.0 + expected.abs()));
        assert_eq!(got, library.ray_log_likelihood(&ray));
        sum_exact += got;
        sum_table += built_table.ray_log_likelihood(&ray);
        // A one-beam scan through the filter's adapter.
        let one_beam = Scan2 {
            angle_min_rad: scan.angle(j),
            angle_increment_rad: 0.0,
            max_range_m: scan.max_range_m,
            ranges: vec![scan.ranges[j]],
            intensities: None,
        };
        let adapter = Scan2Measurement::new(built.as_ref(), Pose2::identity(), PLAIN).unwrap();
        let weight = adapter.log_likelihood(&off, &adapter.prepare(&one_beam));
        assert!((weight - expected).abs() < 1e-9 * (1.0 + expected.abs()));
    }
    assert!(
        (sum_table / sum_exact - 1.0).abs() < 0.05,
        "{sum_table} vs {sum_exact}"
    );
}

/// Sec. 8.4.3: with `n` times the observations of every cell (each hit at least once, so
/// the MLM floor of 1e-3 /m plays no part) the Gamma posterior concentrates on the ML rate
/// and the filter's FMP weights tend to the MLM weights: the ratio of the scan
/// log-likelihoods MLM / FMP tends to 1, exact and tabulated. (A never-hit cell does not
/// converge: its ML rate 0 is floored, its posterior mean α / (nR + β) → 0.)
#[test]
fn decay_rate_fmp_weights_tend_to_mlm_with_many_observations() {
    let grid = Grid2::new(Point2::new(0.0, 0.0), 0.5, [24, 24]).unwrap();
    let base: Vec<(u32, u32, f64)> = (0..grid.num_cells())
        .map(|i| {
            let f = i as f64;
            (
                1 + (i % 5) as u32,
                (i * 7 % 23) as u32,
                0.5 + 11.0 * (0.5 + 0.5 * (f * 0.37).sin()),
            )
        })
        .collect();
    let scan = Scan2 {
        angle_min_rad: -3.0,
        angle_increment_rad: 0.1,
        max_range_m: 30.0,
        ranges: (0..60)
            .map(|j| 0.3 + 4.0 * (0.5 + 0.5 * (j as f64 * 1.7).sin()))
            .collect(),
        intensities: None,
    };
    let range = MappingConfig::default().range;
    let pose = Pose2::new(6.1, 5.9, 0.3);
    for table in [None, Some(OpticalDepthConfig::default())] {
        let mut previous = f64::INFINITY;
        for n in [1u32, 10, 100, 1000] {
            let cells = base
                .iter()
                .map(|&(h, m, r)| CellStats::new(h * n, m * n, r * f64::from(n)))
                .collect();
            let stats = DenseStats2::from_parts(grid, cells, Default::default()).unwrap();
            let spec = ModelSpec {
                kind: ModelKind::DecayRate,
                posterior: false,
                tabulated: table,
            };
            let weight = |spec: ModelSpec| {
                let model = spec.build(&stats, range).unwrap();
                let adapter =
                    Scan2Measurement::new(model.as_ref(), Pose2::identity(), PLAIN).unwrap();
                adapter.log_likelihood(&pose, &adapter.prepare(&scan))
            };
            let (ml, fmp) = (
                weight(spec),
                weight(ModelSpec {
                    posterior: true,
                    ..spec
                }),
            );
            let gap = (ml / fmp - 1.0).abs();
            eprintln!(
                "table {}: n = {n}: MLM {ml:.2}, FMP {fmp:.2}, |ratio − 1| {gap:.2e}",
                table.is_some()
            );
            assert!(
                ml < -10.0 && gap < 0.5 * previous,
                "n = {n}: {gap} vs {previous}"
            );
            previous = gap;
        }
        assert!(previous < 1e-3, "{previous}");
    }
}
