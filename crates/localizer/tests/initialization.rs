//! Initial particle distributions: moments, supports and validation.

#![allow(clippy::unwrap_used)]

use raypath_geometry::{Pose2, Pose3, wrap_angle};
use raypath_localizer::init::{GaussianInit, RadialSampling, UniformBox, UniformDisc};
use raypath_localizer::{FilterConfig, FilterState, ParticleFilter};

fn std_of(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let v: Vec<f64> = values.collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    (
        mean,
        (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt(),
    )
}

/// The thesis's ch. 7 Gaussian: σ 1 m horizontal, 0.2 m vertical, 0.1 rad rotations.
#[test]
fn gaussian_se3_has_the_thesis_spreads() {
    let mean = Pose3::from_xyz_rpy(10.0, -5.0, 2.0, 0.0, 0.0, 1.0);
    let init = GaussianInit::new(mean);
    let filter =
        ParticleFilter::from_initializer(&init, 40_000, FilterConfig::default(), 3).unwrap();
    let states = filter.states();
    let (mx, sx) = std_of(states.iter().map(|s| s.translation().x));
    let (mz, sz) = std_of(states.iter().map(|s| s.translation().z));
    // Rotation offsets in the body frame: rotation vector of mean⁻¹ · R.
    let (_, s_roll) = std_of(
        states
            .iter()
            .map(|s| (mean.rotation().inverse() * s.rotation()).scaled_axis().x),
    );
    let (_, s_yaw) = std_of(
        states
            .iter()
            .map(|s| (mean.rotation().inverse() * s.rotation()).scaled_axis().z),
    );
    assert!((mx - 10.0).abs() < 0.03 && (mz - 2.0).abs() < 0.01);
    assert!((sx - 1.0).abs() < 0.02, "{sx}");
    assert!((sz - 0.2).abs() < 0.004, "{sz}");
    assert!((s_roll - 0.1).abs() < 0.002, "{s_roll}");
    assert!((s_yaw - 0.1).abs() < 0.002, "{s_yaw}");
    // The weighted mean of the cloud recovers the mean pose.
    let estimate = Pose3::weighted_mean(states.iter().map(|s| (s, 1.0))).unwrap();
    assert!((estimate.translation() - mean.translation()).norm() < 0.03);
    assert!((estimate.inverse() * mean).rotation_angle() < 0.003);
}

#[test]
fn gaussian_se2_heading_spread() {
    let init = GaussianInit {
        mean: Pose2::new(0.0, 0.0, 3.1),
        sigma_xy_m: 0.5,
        sigma_z_m: 0.0,
        sigma_rotation_rad: 0.2,
    };
    let filter =
        ParticleFilter::from_initializer(&init, 20_000, FilterConfig::default(), 1).unwrap();
    // Offsets from the mean heading, unwrapped across ±π.
    let (m, s) = std_of(filter.states().iter().map(|p| wrap_angle(p.theta() - 3.1)));
    assert!(m.abs() < 0.005 && (s - 0.2).abs() < 0.005, "{m} {s}");
    let (_, sy) = std_of(filter.states().iter().map(|p| p.y()));
    assert!((sy - 0.5).abs() < 0.01);
}

/// Uniform in area: a quarter of the samples fall within half the radius; uniform in the
/// radius (the polex reference implementation): half of them.
#[test]
fn disc_sampling_area_versus_radius() {
    let center = Pose2::new(1.0, 2.0, 0.5);
    for (radial, expected) in [
        (RadialSampling::UniformArea, 0.25),
        (RadialSampling::UniformRadius, 0.5),
    ] {
        let init = UniformDisc {
            radial,
            ..UniformDisc::new(center, 2.5, 5f64.to_radians())
        };
        let filter =
            ParticleFilter::from_initializer(&init, 20_000, FilterConfig::default(), 9).unwrap();
        let inner = filter
            .states()
            .iter()
            .filter(|p| (p.translation() - center.translation()).norm() < 1.25)
            .count() as f64
            / 20_000.0;
        assert!((inner - expected).abs() < 0.015, "{radial:?}: {inner}");
        for p in filter.states() {
            assert!((p.translation() - center.translation()).norm() <= 2.5 + 1e-12);
            assert!(wrap_angle(p.theta() - 0.5).abs() <= 5f64.to_radians() + 1e-12);
        }
    }
    // SE(3): the disc is horizontal and heading offsets turn about the world z axis.
    let center3 = Pose3::from_xyz_rpy(0.0, 0.0, 1.5, 0.0, 0.0, 0.0);
    let init = UniformDisc::new(center3, 1.0, 0.1);
    let filter = ParticleFilter::from_initializer(&init, 1000, FilterConfig::default(), 2).unwrap();
    for p in filter.states() {
        assert!((p.translation().z - 1.5).abs() < 1e-12);
        let (roll, pitch, yaw) = p.rpy();
        assert!(roll.abs() < 1e-12 && pitch.abs() < 1e-12 && yaw.abs() <= 0.1 + 1e-12);
    }
}

#[test]
fn box_sampling_stays_inside_and_bad_parameters_are_rejected() {
    let init = UniformBox {
        heading_range_rad: [-0.5, 0.5],
        ..UniformBox::new([-1.0, 3.0], [2.0, 2.5])
    };
    let filter = ParticleFilter::from_initializer(&init, 5000, FilterConfig::default(), 4).unwrap();
    for p in filter.states() {
        assert!((-1.0..=3.0).contains(&p.x()) && (2.0..=2.5).contains(&p.y()));
        assert!((-0.5..=0.5).contains(&p.theta()));
    }
    let (mx, _) = std_of(filter.states().iter().map(|p| p.x()));
    assert!((mx - 1.0).abs() < 0.05);

    let reversed = UniformBox::new([3.0, -1.0], [0.0, 1.0]);
    assert!(ParticleFilter::from_initializer(&reversed, 10, FilterConfig::default(), 0).is_err());
    let negative = GaussianInit {
        sigma_xy_m: -1.0,
        ..GaussianInit::new(Pose2::identity())
    };
    assert!(ParticleFilter::from_initializer(&negative, 10, FilterConfig::default(), 0).is_err());
    let nan_center = UniformDisc::new(Pose2::new(f64::NAN, 0.0, 0.0), 1.0, 0.0);
    assert!(ParticleFilter::from_initializer(&nan_center, 10, FilterConfig::default(), 0).is_err());
    let ok = UniformDisc::new(Pose2::identity(), 1.0, 0.0);
    assert!(ParticleFilter::from_initializer(&ok, 0, FilterConfig::default(), 0).is_err());
}
