//! Sample moments of the motion models against their analytic noise.

#![allow(clippy::unwrap_used)]

use nalgebra::{Matrix3, Vector3};
use raypath_geometry::{Pose2, Pose3, wrap_angle};
use raypath_localizer::motion::{
    Gaussian6DofMotionModel, OdometryControl, OdometryMotionModel, PlanarGaussianMotionModel,
    PlanarIncrement,
};
use raypath_localizer::{MotionModel, ParticleRng, PoseTrack, Stamped};

/// Mean and (population) variance.
fn moments(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    (mean, var)
}

/// Sampling x' from x and decomposing x' − x back into (δ̂rot1, δ̂trans, δ̂rot2) recovers the
/// control as mean and the variances α1 δrot1² + α2 δtrans², … of Table 5.6.
#[test]
fn odometry_model_moments_match_table_5_6() {
    let model = OdometryMotionModel::new(0.05, 0.02, 0.05, 0.02).unwrap();
    let odom_prev = Pose2::new(10.0, 5.0, -0.4);
    let odom_cur = odom_prev * Pose2::new(1.0, 0.3, 0.5);
    let control = OdometryControl::from_poses(&odom_prev, &odom_cur);
    let (r1, t, r2) = (control.rot1_rad, control.trans_m, control.rot2_rad);
    assert!((r1 - 0.3f64.atan2(1.0)).abs() < 1e-12);
    assert!((t - 1.09f64.sqrt()).abs() < 1e-12);
    assert!((r2 - (0.5 - r1)).abs() < 1e-12);

    let start = Pose2::new(2.0, -1.0, 0.7);
    let n = 200_000;
    let mut rot1 = Vec::with_capacity(n);
    let mut trans = Vec::with_capacity(n);
    let mut rot2 = Vec::with_capacity(n);
    for i in 0..n {
        let mut rng = ParticleRng::stream(3, 0, i as u64);
        let end = model.sample(&start, &control, &mut rng);
        let (dx, dy) = (end.x() - start.x(), end.y() - start.y());
        let a = wrap_angle(dy.atan2(dx) - start.theta());
        rot1.push(a);
        trans.push(dx.hypot(dy));
        rot2.push(wrap_angle(end.theta() - start.theta() - a));
    }
    let expected_var = [
        0.05 * r1 * r1 + 0.02 * t * t,
        0.05 * t * t + 0.02 * (r1 * r1 + r2 * r2),
        0.05 * r2 * r2 + 0.02 * t * t,
    ];
    let std = model.noise_std(&control);
    for ((values, mean), (var, s)) in [(&rot1, r1), (&trans, t), (&rot2, r2)]
        .into_iter()
        .zip(expected_var.into_iter().zip(std))
    {
        assert!((s * s - var).abs() < 1e-12);
        let (m, v) = moments(values);
        // Standard errors: σ/√n for the mean, √(2/n) relative for the variance.
        assert!(
            (m - mean).abs() < 4.0 * var.sqrt() / (n as f64).sqrt(),
            "mean {m} vs {mean}"
        );
        assert!(
            (v / var - 1.0).abs() < 4.0 * (2.0 / n as f64).sqrt(),
            "var {v} vs {var}"
        );
    }
}

/// The planar Gaussian increment model reproduces the increment's mean and covariance
/// (times the scale) in the body frame.
#[test]
fn planar_increment_covariance_is_reproduced() {
    let covariance = Matrix3::new(0.04, 0.01, 0.002, 0.01, 0.02, 0.0, 0.002, 0.0, 0.001);
    let delta = Pose2::new(1.5, 0.2, 0.1);
    let control = PlanarIncrement::new(&delta, &covariance).unwrap();
    let model = PlanarGaussianMotionModel {
        covariance_scale: 4.0,
    };
    let start = Pose2::new(-3.0, 4.0, 2.0);
    let n = 100_000;
    let samples: Vec<Vector3<f64>> = (0..n)
        .map(|i| {
            let end = model.sample(&start, &control, &mut ParticleRng::stream(9, 1, i));
            let body = start.inverse() * end;
            Vector3::new(body.x(), body.y(), body.theta())
        })
        .collect();
    let mean = samples.iter().sum::<Vector3<f64>>() / n as f64;
    let cov = samples
        .iter()
        .map(|s| (s - mean) * (s - mean).transpose())
        .sum::<Matrix3<f64>>()
        / n as f64;
    let expected = 4.0 * covariance;
    for i in 0..3 {
        let sd = expected[(i, i)].sqrt();
        assert!((mean[i] - [1.5, 0.2, 0.1][i]).abs() < 4.0 * sd / (n as f64).sqrt());
        for j in 0..3 {
            let tol = 4.0 * (expected[(i, i)] * expected[(j, j)] * 2.0 / n as f64).sqrt();
            assert!(
                (cov[(i, j)] - expected[(i, j)]).abs() < tol,
                "cov[{i}][{j}] {} vs {}",
                cov[(i, j)],
                expected[(i, j)]
            );
        }
    }
    // An indefinite covariance is rejected.
    let bad = Matrix3::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0);
    assert!(PlanarIncrement::new(&delta, &bad).is_err());
}

/// The 6-DOF model's body-frame noise has the documented standard deviations.
#[test]
fn six_dof_noise_has_the_documented_std() {
    let model = Gaussian6DofMotionModel::default();
    let increment = Pose3::from_xyz_rpy(2.0, 0.0, 0.0, 0.0, 0.0, 0.2);
    let (sigma_t, sigma_r) = model.noise_std(&increment);
    // 0.05 · 2 m + 0 + 0.01 m; 0.005 · 2 + 0.05 · 0.2 + c_r.
    assert!((sigma_t[0] - 0.11).abs() < 1e-12);
    assert!((sigma_r[2] - (0.01 + 0.01 + 0.002)).abs() < 1e-12);
    let start = Pose3::from_xyz_rpy(1.0, 2.0, 3.0, 0.1, -0.1, 1.0);
    let n = 50_000;
    let mut dx = Vec::with_capacity(n);
    let mut dyaw = Vec::with_capacity(n);
    for i in 0..n {
        let end = model.sample(&start, &increment, &mut ParticleRng::stream(5, 2, i as u64));
        // The noise in the frame at the end of the increment.
        let noise = (start * increment).inverse() * end;
        dx.push(noise.translation().x);
        dyaw.push(noise.rotation().scaled_axis().z);
    }
    let (mx, vx) = moments(&dx);
    let (my, vy) = moments(&dyaw);
    assert!(mx.abs() < 4.0 * sigma_t[0] / (n as f64).sqrt());
    assert!(my.abs() < 4.0 * sigma_r[2] / (n as f64).sqrt());
    assert!((vx.sqrt() / sigma_t[0] - 1.0).abs() < 0.02);
    assert!((vy.sqrt() / sigma_r[2] - 1.0).abs() < 0.02);
}

/// The odometry increment between two times of an interpolated track.
#[test]
fn odometry_control_from_a_track() {
    let track = PoseTrack::new([
        Stamped::new(0.0, Pose2::new(0.0, 0.0, 0.0)),
        Stamped::new(1.0, Pose2::new(1.0, 0.0, 0.0)),
        Stamped::new(2.0, Pose2::new(1.0, 1.0, std::f64::consts::FRAC_PI_2)),
    ])
    .unwrap();
    let control = track.odometry_control(0.5, 1.5).unwrap();
    // From (0.5, 0, 0) to (1, 0.5, π/4): a 45° bearing, √0.5 m, then no further turn.
    assert!((control.rot1_rad - std::f64::consts::FRAC_PI_4).abs() < 1e-12);
    assert!((control.trans_m - 0.5f64.sqrt()).abs() < 1e-12);
    assert!(control.rot2_rad.abs() < 1e-12);
    assert!(track.odometry_control(-1.0, 1.0).is_err());
}
