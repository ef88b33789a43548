//! Algebraic laws of `Pose2` and `Pose3`: inverse, composition, interpolation, conversions.

use std::f64::consts::PI;

use nalgebra::{Point2, Point3};
use proptest::prelude::*;
use raypath_geometry::testing::{pose2, pose3};
use raypath_geometry::{Pose2, Pose3, wrap_angle};

/// Distance between two planar poses: translation difference plus wrapped heading difference.
fn distance2(a: &Pose2, b: &Pose2) -> f64 {
    (a.translation() - b.translation()).norm() + wrap_angle(a.theta() - b.theta()).abs()
}

/// Distance between two 3-D poses: translation difference plus rotation-matrix difference.
fn distance3(a: &Pose3, b: &Pose3) -> f64 {
    let ra = a.rotation().to_rotation_matrix();
    let rb = b.rotation().to_rotation_matrix();
    (a.translation() - b.translation()).norm() + (ra.matrix() - rb.matrix()).norm()
}

fn point2() -> impl Strategy<Value = Point2<f64>> {
    (-100.0..100.0f64, -100.0..100.0f64).prop_map(|(x, y)| Point2::new(x, y))
}

fn point3() -> impl Strategy<Value = Point3<f64>> {
    (-100.0..100.0f64, -100.0..100.0f64, -100.0..100.0f64)
        .prop_map(|(x, y, z)| Point3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(500))]

    #[test]
    fn pose2_inverse_and_composition(a in pose2(), b in pose2(), c in pose2(), p in point2()) {
        prop_assert!(distance2(&(a * a.inverse()), &Pose2::identity()) < 1e-9);
        prop_assert!(distance2(&(a.inverse() * a), &Pose2::identity()) < 1e-9);
        prop_assert!((a.inverse() * (a * p) - p).norm() < 1e-9);
        // Composition acts like successive application, and is associative.
        prop_assert!(((a * b) * p - a * (b * p)).norm() < 1e-9);
        prop_assert!(distance2(&((a * b) * c), &(a * (b * c))) < 1e-9);
        // (a b)^-1 = b^-1 a^-1.
        prop_assert!(distance2(&(a * b).inverse(), &(b.inverse() * a.inverse())) < 1e-9);
        prop_assert!(a.theta() > -PI && a.theta() <= PI);
    }

    #[test]
    fn pose2_interpolation(a in pose2(), b in pose2(), t in 0.0..=1.0f64) {
        prop_assert!(distance2(&a.interpolate(&b, 0.0), &a) < 1e-9);
        prop_assert!(distance2(&a.interpolate(&b, 1.0), &b) < 1e-9);
        prop_assert!(distance2(&a.interpolate(&a, t), &a) < 1e-9);
        let mid = a.interpolate(&b, t);
        let expected = a.translation() + t * (b.translation() - a.translation());
        prop_assert!((mid.translation() - expected).norm() < 1e-9);
        // Along the shorter arc, at constant rate.
        let total = wrap_angle(b.theta() - a.theta());
        prop_assert!((wrap_angle(mid.theta() - a.theta()) - t * total).abs() < 1e-9);
    }

    #[test]
    fn pose2_lifts_to_pose3(a in pose2(), b in pose2(), p in point2()) {
        let lifted = a.to_pose3();
        let q = lifted * Point3::new(p.x, p.y, 0.0);
        let r = a * p;
        prop_assert!((q - Point3::new(r.x, r.y, 0.0)).norm() < 1e-9);
        prop_assert!(distance2(&lifted.to_planar(), &a) < 1e-9);
        // Lifting is a homomorphism.
        prop_assert!(distance3(&(a * b).to_pose3(), &(a.to_pose3() * b.to_pose3())) < 1e-9);
    }

    #[test]
    fn pose3_inverse_and_composition(a in pose3(), b in pose3(), c in pose3(), p in point3()) {
        prop_assert!(distance3(&(a * a.inverse()), &Pose3::identity()) < 1e-9);
        prop_assert!((a.inverse() * (a * p) - p).norm() < 1e-9);
        prop_assert!(((a * b) * p - a * (b * p)).norm() < 1e-9);
        prop_assert!(distance3(&((a * b) * c), &(a * (b * c))) < 1e-9);
        prop_assert!(distance3(&(a * b).inverse(), &(b.inverse() * a.inverse())) < 1e-9);
        prop_assert!(a.is_finite());
    }

    #[test]
    fn pose3_interpolation(a in pose3(), b in pose3(), t in 0.0..=1.0f64) {
        prop_assert!(distance3(&a.interpolate(&b, 0.0), &a) < 1e-9);
        prop_assert!(distance3(&a.interpolate(&b, 1.0), &b) < 1e-9);
        prop_assert!(distance3(&a.interpolate(&a, t), &a) < 1e-9);
        let mid = a.interpolate(&b, t);
        let expected = a.translation() + t * (b.translation() - a.translation());
        prop_assert!((mid.translation() - expected).norm() < 1e-9);
        // Slerp: constant angular rate along the shorter arc (angles via acos: ~1e-7).
        let total = a.rotation().angle_to(&b.rotation());
        prop_assume!(total < PI - 1e-3);
        prop_assert!((a.rotation().angle_to(&mid.rotation()) - t * total).abs() < 1e-6);
        prop_assert!((mid.rotation().angle_to(&b.rotation()) - (1.0 - t) * total).abs() < 1e-6);
    }

    #[test]
    fn pose3_from_any_matrix_terminates(
        entries in prop::collection::vec(
            prop_oneof![
                -2.0..2.0f64,
                Just(0.0),
                Just(f64::INFINITY),
                Just(f64::NAN),
                Just(1e300),
                Just(-1e300),
            ],
            12,
        ),
    ) {
        let m = nalgebra::Matrix3x4::from_row_slice(&entries);
        let pose = Pose3::from_matrix3x4(&m);
        if let Some(checked) = Pose3::try_from_matrix3x4(&m) {
            prop_assert!(checked.rotation().coords.iter().all(|v| v.is_finite()));
            prop_assert!(pose.rotation().coords.iter().all(|v| v.is_finite()));
        }
    }

    #[test]
    fn pose3_conversions_round_trip(a in pose3()) {
        prop_assert!(distance3(&Pose3::from_matrix3x4(&a.to_matrix3x4()), &a) < 1e-9);
        let (roll, pitch, yaw) = a.rpy();
        let t = a.translation();
        let back = Pose3::from_xyz_rpy(t.x, t.y, t.z, roll, pitch, yaw);
        prop_assert!(distance3(&back, &a) < 1e-9);
    }

    #[test]
    fn wrap_angle_is_congruent_and_in_range(angle in -1e4..1e4f64) {
        let w = wrap_angle(angle);
        prop_assert!(w > -PI && w <= PI);
        let turns = (angle - w) / (2.0 * PI);
        prop_assert!((turns - turns.round()).abs() < 1e-9);
    }
}

/// Blocks on which nalgebra's orthonormalization never ends (a zero block: every rotation is
/// equally far; infinite entries) give NaN rotations instead of hanging, and are refused by
/// the checked constructor.
#[test]
fn pose3_from_degenerate_blocks_terminates() {
    for fill in [0.0, f64::INFINITY, f64::NAN, 1e300] {
        let m = nalgebra::Matrix3x4::from_element(fill);
        assert!(Pose3::try_from_matrix3x4(&m).is_none());
        let pose = Pose3::from_matrix3x4(&m);
        assert!(pose.rotation().coords.iter().any(|v| v.is_nan()));
    }
    let identity =
        nalgebra::Matrix3x4::new(1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 2.0, 0.0, 0.0, 1.0, 3.0);
    let pose = Pose3::try_from_matrix3x4(&identity).expect("a rigid transform");
    assert!((pose.translation() - nalgebra::Vector3::new(1.0, 2.0, 3.0)).norm() < 1e-12);
}
