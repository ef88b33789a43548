//! Registration and odometry on a synthetic street with known motion, invariants, and bad
//! input.

// Test helpers (outside #[test] functions) panic on setup failures too.
#![allow(clippy::unwrap_used)]

mod common;

use common::{pose_error, scan};
use nalgebra::Point3;
use proptest::prelude::*;
use raypath_geometry::{PointCloud, Pose3};
use raypath_registration::{
    Kernel, Odometry, OdometryConfig, RegistrationConfig, RegistrationError, register,
};

const N: usize = 60_000;
const NOISE_M: f64 = 0.02;

#[test]
fn known_rigid_transform_is_recovered() {
    let config = RegistrationConfig::default();
    let truth = Pose3::from_xyz_rpy(
        1.2,
        0.3,
        0.05,
        0.5f64.to_radians(),
        -0.5f64.to_radians(),
        4f64.to_radians(),
    );
    // Independent samples with 2 cm noise: no point of one scan is in the other.
    let target = scan(1, N, NOISE_M, &Pose3::identity());
    let source = scan(2, N, NOISE_M, &truth);
    let mut errors = Vec::new();
    for kernel in [Kernel::GemanMcClure, Kernel::Huber, Kernel::None] {
        let config = RegistrationConfig {
            kernel,
            ..config.clone()
        };
        let found = register(&source, &target, &Pose3::identity(), &config).unwrap();
        let (dt, dr) = pose_error(&truth, &found.target_from_source);
        assert!(found.converged, "{kernel:?}: {found:?}");
        assert!(found.fitness > 0.9, "{kernel:?}: fitness {}", found.fitness);
        // Both points carry 2 cm of noise per axis (residuals of about √2 · 2 cm); foliage
        // points within 0.3 m of a surface count as inliers too.
        assert!(
            found.rmse_m > NOISE_M && found.rmse_m < 3.0 * NOISE_M,
            "{kernel:?}: rmse {}",
            found.rmse_m
        );
        errors.push((kernel, dt, dr));
    }
    // Geman–McClure with the graduated scale: millimetres; plain least squares is pulled by
    // the foliage and poles (centimetres).
    let (_, gm_t, gm_r) = errors[0];
    let (_, ls_t, _) = errors[2];
    assert!(
        gm_t < 0.01 && gm_r < 0.02f64.to_radians(),
        "Geman–McClure: {errors:?}"
    );
    assert!(gm_t < ls_t, "{errors:?}");
    for (kernel, dt, dr) in errors {
        assert!(
            dt < 0.06 && dr < 0.1f64.to_radians(),
            "{kernel:?}: {dt} m, {dr} rad"
        );
    }
}

#[test]
fn identical_clouds_register_to_the_identity() {
    let cloud = scan(3, N, NOISE_M, &Pose3::identity());
    // With the default scales the source and target are different thinnings of the cloud:
    // the identity up to the noise of ~2000 correspondences.
    let config = RegistrationConfig::default();
    let found = register(&cloud, &cloud, &Pose3::identity(), &config).unwrap();
    let (dt, dr) = pose_error(&Pose3::identity(), &found.target_from_source);
    assert!(dt < 5e-3 && dr < 5e-4, "{dt} m, {dr} rad");
    // Each of the four kernel stages converges in a step or two.
    assert!(found.converged && found.iterations <= 12, "{found:?}");
    // With one scale, every source point that has a normal is its own target point
    // (residual 0): the identity up to the pull of the few points without normals.
    let same = RegistrationConfig {
        source_voxel_scale: config.target_voxel_scale,
        kernel: Kernel::GemanMcClure,
        kernel_scale_m: 0.05,
        ..config
    };
    let found = register(&cloud, &cloud, &Pose3::identity(), &same).unwrap();
    let (dt, dr) = pose_error(&Pose3::identity(), &found.target_from_source);
    assert!(dt < 2e-4 && dr < 5e-5, "{dt} m, {dr} rad");
}

#[test]
fn registration_is_symmetric_and_guess_independent() {
    let config = RegistrationConfig::default();
    let truth = Pose3::from_xyz_rpy(0.9, -0.2, 0.0, 0.0, 0.0, -2f64.to_radians());
    let a = scan(4, N, NOISE_M, &Pose3::identity());
    let b = scan(5, N, NOISE_M, &truth);
    let forward = register(&b, &a, &Pose3::identity(), &config).unwrap();
    let backward = register(&a, &b, &Pose3::identity(), &config).unwrap();
    // a_from_b · b_from_a ≈ identity.
    let (dt, dr) = pose_error(
        &Pose3::identity(),
        &(forward.target_from_source * backward.target_from_source),
    );
    assert!(dt < 0.02 && dr < 1e-3, "{dt} m, {dr} rad");
    // A guess 0.5 m and 2° off the truth converges to the same pose.
    let guess = truth * Pose3::from_xyz_rpy(0.5, 0.3, 0.0, 0.0, 0.0, 2f64.to_radians());
    let from_guess = register(&b, &a, &guess, &config).unwrap();
    let (dt, dr) = pose_error(&forward.target_from_source, &from_guess.target_from_source);
    assert!(dt < 5e-3 && dr < 2e-4, "{dt} m, {dr} rad");
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let truth = Pose3::from_xyz_rpy(1.0, 0.2, 0.0, 0.0, 0.0, 0.03);
    let target = scan(6, N, NOISE_M, &Pose3::identity());
    let source = scan(7, N, NOISE_M, &truth);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                register(
                    &source,
                    &target,
                    &Pose3::identity(),
                    &RegistrationConfig::default(),
                )
                .unwrap()
            })
    };
    assert_eq!(run(1), run(3));
}

#[test]
fn odometry_follows_a_synthetic_drive() {
    // 12 scans 1 m apart along a gentle curve (yaw rate 1° per scan).
    let truth: Vec<Pose3> = (0..12)
        .map(|k| {
            let k = k as f64;
            let yaw = k * 1f64.to_radians();
            Pose3::from_xyz_rpy(k * 1.0 - 6.0, 0.02 * k * k, 0.0, 0.0, 0.0, yaw)
        })
        .collect();
    let mut odometry = Odometry::new(OdometryConfig::default()).unwrap();
    for (k, pose) in truth.iter().enumerate() {
        let step = odometry
            .register_frame(&scan(100 + k as u64, 40_000, NOISE_M, pose))
            .unwrap();
        assert_eq!(step.registration.is_none(), k == 0);
        assert!(step.map_points > 0);
    }
    let found = odometry.poses();
    for k in 1..truth.len() {
        let expected = truth[k - 1].inverse() * truth[k];
        let got = found[k - 1].inverse() * found[k];
        let (dt, dr) = pose_error(&expected, &got);
        assert!(
            dt < 0.02 && dr < 0.05f64.to_radians(),
            "step {k}: {dt} m, {} deg",
            dr.to_degrees()
        );
    }
    // End-to-end drift over 11 m.
    let end = truth[0].inverse() * truth[truth.len() - 1];
    let (dt, _) = pose_error(&end, &found[found.len() - 1]);
    assert!(dt < 0.05, "drift {dt} m");
}

#[test]
fn bad_input_gives_errors() {
    let config = RegistrationConfig::default();
    let good = scan(8, 20_000, NOISE_M, &Pose3::identity());
    let id = Pose3::identity();
    // Empty clouds.
    let empty = PointCloud::default();
    assert!(matches!(
        register(&empty, &good, &id, &config),
        Err(RegistrationError::EmptyCloud { what: "source", .. })
    ));
    assert!(matches!(
        register(&good, &empty, &id, &config),
        Err(RegistrationError::EmptyCloud { what: "target", .. })
    ));
    // NaN in an unorganized cloud names the point.
    let mut nan = good.clone();
    nan.points[17].y = f32::NAN;
    let err = register(&nan, &good, &id, &config).unwrap_err();
    assert!(
        matches!(
            err,
            RegistrationError::NonFinitePoint {
                what: "source",
                index: 17,
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("point 17"), "{err}");
    let mut inf = good.clone();
    inf.points[3].z = f32::INFINITY;
    assert!(matches!(
        register(&good, &inf, &id, &config),
        Err(RegistrationError::NonFinitePoint {
            what: "target",
            index: 3,
            ..
        })
    ));
    // In an organized cloud NaN marks a missing pixel: skipped.
    let mut organized = good.clone();
    organized.width = 100;
    organized.height = 200;
    organized.points[17] = Point3::new(f32::NAN, f32::NAN, f32::NAN);
    assert!(register(&organized, &good, &id, &config).is_ok());
    // Inconsistent attributes.
    let mut bad_width = good.clone();
    bad_width.width = 7;
    assert!(matches!(
        register(&bad_width, &good, &id, &config),
        Err(RegistrationError::InvalidCloud { .. })
    ));
    // Nothing within range.
    let far = PointCloud::from_points(vec![Point3::new(500.0, 0.0, 0.0); 10]);
    assert!(matches!(
        register(&far, &good, &id, &config),
        Err(RegistrationError::EmptyCloud { .. })
    ));
    // A non-finite guess, an invalid config.
    let guess = Pose3::from_xyz_rpy(f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0);
    assert!(matches!(
        register(&good, &good, &guess, &config),
        Err(RegistrationError::NonFinitePose { .. })
    ));
    for broken in [
        RegistrationConfig {
            voxel_size_m: 0.0,
            ..config.clone()
        },
        RegistrationConfig {
            max_range_m: f64::NAN,
            ..config.clone()
        },
        RegistrationConfig {
            normal_neighbours: 2,
            ..config.clone()
        },
        RegistrationConfig {
            max_iterations: 0,
            ..config.clone()
        },
    ] {
        assert!(matches!(
            register(&good, &good, &id, &broken),
            Err(RegistrationError::InvalidParameter { .. })
        ));
    }
    // No overlap at the guess: 1 km away.
    let away = Pose3::from_xyz_rpy(1000.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    assert!(matches!(
        register(&good, &good, &away, &config),
        Err(RegistrationError::TooFewCorrespondences { .. })
    ));
    // Odometry keeps its state after a bad frame.
    let mut odometry = Odometry::new(OdometryConfig::default()).unwrap();
    odometry.register_frame(&good).unwrap();
    assert!(odometry.register_frame(&nan).is_err());
    assert_eq!(odometry.poses().len(), 1);
}

/// A cloud of up to 40 coordinates, some replaced by NaN, ±inf or huge values.
fn mutated_cloud() -> impl Strategy<Value = PointCloud> {
    let coordinate = prop_oneof![
        8 => -60.0f32..60.0,
        1 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(-1e30f32),
    ];
    prop::collection::vec([coordinate.clone(), coordinate.clone(), coordinate], 0..40).prop_map(
        |xyz| {
            PointCloud::from_points(
                xyz.into_iter()
                    .map(|[x, y, z]| Point3::new(x, y, z))
                    .collect(),
            )
        },
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    /// Any cloud, however broken, gives a registration or an error, never a panic.
    #[test]
    fn mutated_clouds_never_panic(source in mutated_cloud(), target in mutated_cloud()) {
        let config = RegistrationConfig { min_correspondences: 6, ..RegistrationConfig::default() };
        if let Ok(found) = register(&source, &target, &Pose3::identity(), &config) {
            prop_assert!(found.target_from_source.is_finite());
        }
        let mut odometry = Odometry::new(OdometryConfig::default()).unwrap();
        let _ = odometry.register_frame(&source);
        let _ = odometry.register_frame(&target);
    }
}
