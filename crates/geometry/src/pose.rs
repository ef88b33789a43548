//! Rigid-body poses in SE(2) and SE(3).
//!
//! A pose is a transform between two frames and is named after them:
//! `world_from_sensor * point_in_sensor == point_in_world`. Composition reads right to left,
//! like matrices: `world_from_sensor = world_from_base * base_from_sensor`.

use std::ops::Mul;

use nalgebra::{
    Isometry2, Isometry3, Matrix3, Matrix3x4, Point2, Point3, Rotation3, Translation3,
    UnitQuaternion, Vector2, Vector3,
};
use serde::{Deserialize, Serialize};

/// Wraps an angle to `(-π, π]` (radians).
///
/// ```
/// # use raypath_geometry::wrap_angle;
/// use std::f64::consts::PI;
/// assert!((wrap_angle(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-12);
/// assert!((wrap_angle(-PI) - PI).abs() < 1e-12);
/// ```
pub fn wrap_angle(angle_rad: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let wrapped = (angle_rad + PI).rem_euclid(TAU) - PI;
    if wrapped <= -PI {
        wrapped + TAU
    } else {
        wrapped
    }
}

/// A planar pose (x, y, θ): metres and radians, θ counter-clockwise about z (REP-103).
///
/// ```
/// # use raypath_geometry::Pose2;
/// use nalgebra::Point2;
/// use std::f64::consts::FRAC_PI_2;
/// let world_from_robot = Pose2::new(1.0, 2.0, FRAC_PI_2);
/// let point_in_world = world_from_robot * Point2::new(1.0, 0.0);
/// assert!((point_in_world - Point2::new(1.0, 3.0)).norm() < 1e-12);
/// let identity = world_from_robot * world_from_robot.inverse();
/// assert!(identity.translation().norm() < 1e-12 && identity.theta().abs() < 1e-12);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose2 {
    /// The underlying isometry.
    pub isometry: Isometry2<f64>,
}

impl Default for Pose2 {
    fn default() -> Self {
        Self::identity()
    }
}

impl Pose2 {
    /// The pose from position `(x, y)` in metres and heading `theta` in radians.
    pub fn new(x: f64, y: f64, theta: f64) -> Self {
        Self {
            isometry: Isometry2::new(Vector2::new(x, y), theta),
        }
    }

    /// The identity transform.
    pub fn identity() -> Self {
        Self {
            isometry: Isometry2::identity(),
        }
    }

    /// x in metres.
    pub fn x(&self) -> f64 {
        self.isometry.translation.x
    }

    /// y in metres.
    pub fn y(&self) -> f64 {
        self.isometry.translation.y
    }

    /// Heading θ in radians, in `(-π, π]`.
    pub fn theta(&self) -> f64 {
        self.isometry.rotation.angle()
    }

    /// The translation part in metres.
    pub fn translation(&self) -> Vector2<f64> {
        self.isometry.translation.vector
    }

    /// The inverse transform: `(a_from_b).inverse() == b_from_a`.
    pub fn inverse(&self) -> Self {
        Self {
            isometry: self.isometry.inverse(),
        }
    }

    /// Applies the pose to a point.
    pub fn transform_point(&self, point: &Point2<f64>) -> Point2<f64> {
        self.isometry.transform_point(point)
    }

    /// Rotates a vector (no translation).
    pub fn transform_vector(&self, vector: &Vector2<f64>) -> Vector2<f64> {
        self.isometry.transform_vector(vector)
    }

    /// Interpolates between `self` (at `t = 0`) and `other` (at `t = 1`): linear in the
    /// translation, along the shorter arc in the heading.
    pub fn interpolate(&self, other: &Self, t: f64) -> Self {
        let translation = self.translation().lerp(&other.translation(), t);
        let delta = wrap_angle(other.theta() - self.theta());
        Self::new(translation.x, translation.y, self.theta() + t * delta)
    }

    /// The pose lifted into 3-D: z = 0, rotation about the z axis.
    pub fn to_pose3(&self) -> Pose3 {
        Pose3::from_xyz_rpy(self.x(), self.y(), 0.0, 0.0, 0.0, self.theta())
    }

    /// True when all components are finite.
    pub fn is_finite(&self) -> bool {
        self.x().is_finite() && self.y().is_finite() && self.theta().is_finite()
    }
}

impl From<Isometry2<f64>> for Pose2 {
    fn from(isometry: Isometry2<f64>) -> Self {
        Self { isometry }
    }
}

impl Mul for Pose2 {
    type Output = Pose2;
    fn mul(self, rhs: Pose2) -> Pose2 {
        Pose2 {
            isometry: self.isometry * rhs.isometry,
        }
    }
}

impl Mul<Point2<f64>> for Pose2 {
    type Output = Point2<f64>;
    fn mul(self, rhs: Point2<f64>) -> Point2<f64> {
        self.isometry * rhs
    }
}

/// A pose in 3-D: translation in metres and a unit-quaternion rotation.
///
/// ```
/// # use raypath_geometry::Pose3;
/// use nalgebra::Point3;
/// use std::f64::consts::FRAC_PI_2;
/// let world_from_sensor = Pose3::from_xyz_rpy(1.0, 0.0, 2.0, 0.0, 0.0, FRAC_PI_2);
/// let point_in_world = world_from_sensor * Point3::new(1.0, 0.0, 0.0);
/// assert!((point_in_world - Point3::new(1.0, 1.0, 2.0)).norm() < 1e-12);
/// let planar = world_from_sensor.to_planar();
/// assert!((planar.theta() - FRAC_PI_2).abs() < 1e-12);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose3 {
    /// The underlying isometry.
    pub isometry: Isometry3<f64>,
}

impl Default for Pose3 {
    fn default() -> Self {
        Self::identity()
    }
}

impl Pose3 {
    /// The identity transform.
    pub fn identity() -> Self {
        Self {
            isometry: Isometry3::identity(),
        }
    }

    /// The pose from a translation (metres) and a rotation.
    pub fn from_parts(translation: Vector3<f64>, rotation: UnitQuaternion<f64>) -> Self {
        Self {
            isometry: Isometry3::from_parts(Translation3::from(translation), rotation),
        }
    }

    /// The pose from a translation and roll, pitch, yaw in radians (rotation
    /// `R = Rz(yaw) · Ry(pitch) · Rx(roll)`, fixed axes x-y-z as in ROS and NCLT).
    pub fn from_xyz_rpy(x: f64, y: f64, z: f64, roll: f64, pitch: f64, yaw: f64) -> Self {
        Self::from_parts(
            Vector3::new(x, y, z),
            UnitQuaternion::from_euler_angles(roll, pitch, yaw),
        )
    }

    /// The pose from a row-major 3×4 matrix `[R | t]` (the KITTI pose layout). The rotation
    /// block is re-orthonormalized, so rounding in text files does not leak into the quaternion.
    ///
    /// The block must be a rotation up to rounding; for matrices read from files use
    /// [`Pose3::try_from_matrix3x4`]. A block far from a rotation (`|RᵀR − I| > 0.5`
    /// entrywise, `det R ≤ 0`, non-finite entries) gives a pose with NaN rotation components
    /// (never a hang in the orthonormalization).
    pub fn from_matrix3x4(matrix: &Matrix3x4<f64>) -> Self {
        let rotation_block: Matrix3<f64> = matrix.fixed_view::<3, 3>(0, 0).into_owned();
        // nalgebra's iteration loops forever when the norms it compares are inf or NaN, or
        // when all rotations are equally far (a zero block): only near-rotations go in.
        let near_rotation = rotation_block
            .iter()
            .all(|v| v.is_finite() && v.abs() < 1e6)
            && (rotation_block.transpose() * rotation_block - Matrix3::identity())
                .abs()
                .max()
                <= 0.5
            && rotation_block.determinant() > 0.0;
        if !near_rotation {
            let nan = nalgebra::Quaternion::new(f64::NAN, f64::NAN, f64::NAN, f64::NAN);
            return Self::from_parts(
                matrix.column(3).into_owned(),
                UnitQuaternion::new_unchecked(nan),
            );
        }
        let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_eps(
            &rotation_block,
            1e-12,
            100,
            Rotation3::identity(),
        ));
        Self::from_parts(matrix.column(3).into_owned(), rotation)
    }

    /// Like [`Pose3::from_matrix3x4`], for untrusted input: `None` unless all twelve entries
    /// are finite and the 3×3 block is a proper rotation up to `1e-2` (`|RᵀR − I| ≤ 1e-2`
    /// entrywise, `det R > 0`).
    pub fn try_from_matrix3x4(matrix: &Matrix3x4<f64>) -> Option<Self> {
        if !matrix.iter().all(|v| v.is_finite()) {
            return None;
        }
        let block: Matrix3<f64> = matrix.fixed_view::<3, 3>(0, 0).into_owned();
        let error = (block.transpose() * block - Matrix3::identity())
            .abs()
            .max();
        (error <= 1e-2 && block.determinant() > 0.0).then(|| Self::from_matrix3x4(matrix))
    }

    /// The row-major 3×4 matrix `[R | t]`.
    pub fn to_matrix3x4(&self) -> Matrix3x4<f64> {
        let mut matrix = Matrix3x4::zeros();
        matrix
            .fixed_view_mut::<3, 3>(0, 0)
            .copy_from(self.isometry.rotation.to_rotation_matrix().matrix());
        matrix
            .column_mut(3)
            .copy_from(&self.isometry.translation.vector);
        matrix
    }

    /// The translation part in metres.
    pub fn translation(&self) -> Vector3<f64> {
        self.isometry.translation.vector
    }

    /// The rotation part.
    pub fn rotation(&self) -> UnitQuaternion<f64> {
        self.isometry.rotation
    }

    /// Roll, pitch and yaw in radians (inverse of [`Pose3::from_xyz_rpy`]).
    pub fn rpy(&self) -> (f64, f64, f64) {
        self.isometry.rotation.euler_angles()
    }

    /// The inverse transform: `(a_from_b).inverse() == b_from_a`.
    pub fn inverse(&self) -> Self {
        Self {
            isometry: self.isometry.inverse(),
        }
    }

    /// Applies the pose to a point.
    pub fn transform_point(&self, point: &Point3<f64>) -> Point3<f64> {
        self.isometry.transform_point(point)
    }

    /// Rotates a vector (no translation).
    pub fn transform_vector(&self, vector: &Vector3<f64>) -> Vector3<f64> {
        self.isometry.transform_vector(vector)
    }

    /// Interpolates between `self` (at `t = 0`) and `other` (at `t = 1`): linear in the
    /// translation, spherical-linear (slerp, shorter arc) in the rotation.
    pub fn interpolate(&self, other: &Self, t: f64) -> Self {
        let translation = self.translation().lerp(&other.translation(), t);
        let rotation = self
            .rotation()
            .try_slerp(&other.rotation(), t, 1e-12)
            // Opposite rotations (angle π apart): any great circle is shortest; nlerp picks one.
            .unwrap_or_else(|| self.rotation().nlerp(&other.rotation(), t));
        Self::from_parts(translation, rotation)
    }

    /// Projects the pose onto the ground plane: (x, y) of the translation and the heading of
    /// the rotated x axis about z. Robust near ±90° pitch, where yaw of the Euler angles is
    /// ill-defined, because it uses the projected x axis; falls back to the Euler yaw when the
    /// x axis points straight up or down.
    pub fn to_planar(&self) -> Pose2 {
        let x_axis = self.isometry.rotation * Vector3::x();
        let heading = if x_axis.x.hypot(x_axis.y) > 1e-9 {
            x_axis.y.atan2(x_axis.x)
        } else {
            self.rpy().2
        };
        let t = self.translation();
        Pose2::new(t.x, t.y, heading)
    }

    /// True when all components are finite.
    pub fn is_finite(&self) -> bool {
        self.translation().iter().all(|v| v.is_finite())
            && self.rotation().coords.iter().all(|v| v.is_finite())
    }
}

impl From<Isometry3<f64>> for Pose3 {
    fn from(isometry: Isometry3<f64>) -> Self {
        Self { isometry }
    }
}

impl From<Pose2> for Pose3 {
    fn from(pose: Pose2) -> Self {
        pose.to_pose3()
    }
}

impl Mul for Pose3 {
    type Output = Pose3;
    fn mul(self, rhs: Pose3) -> Pose3 {
        Pose3 {
            isometry: self.isometry * rhs.isometry,
        }
    }
}

impl Mul<Point3<f64>> for Pose3 {
    type Output = Point3<f64>;
    fn mul(self, rhs: Point3<f64>) -> Point3<f64> {
        self.isometry * rhs
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn wrap_angle_range() {
        for k in -20..=20 {
            let a = 0.3 + f64::from(k) * 0.7;
            let w = wrap_angle(a);
            assert!(w > -PI && w <= PI);
            assert!(
                ((a - w) / (2.0 * PI)).fract().abs() < 1e-9
                    || ((a - w) / (2.0 * PI)).fract().abs() > 1.0 - 1e-9
            );
        }
    }

    #[test]
    fn pose2_interpolation_takes_short_arc() {
        let a = Pose2::new(0.0, 0.0, 3.0);
        let b = Pose2::new(2.0, 0.0, -3.0);
        let mid = a.interpolate(&b, 0.5);
        assert!((mid.x() - 1.0).abs() < 1e-12);
        assert!((mid.theta().abs() - PI).abs() < 1e-9);
    }

    #[test]
    fn pose3_matrix_round_trip() {
        let pose = Pose3::from_xyz_rpy(1.0, -2.0, 3.0, 0.1, -0.2, 0.3);
        let back = Pose3::from_matrix3x4(&pose.to_matrix3x4());
        assert!((back.translation() - pose.translation()).norm() < 1e-12);
        // `angle_to` goes through acos (~1e-8 resolution near zero), so compare matrices;
        // `from_matrix3x4` re-orthonormalizes to its convergence threshold of 1e-12.
        let rotation_error = back.rotation().to_rotation_matrix().matrix()
            - pose.rotation().to_rotation_matrix().matrix();
        assert!(rotation_error.norm() < 1e-10);
        let (r, p, y) = back.rpy();
        assert!((r - 0.1).abs() < 1e-12 && (p + 0.2).abs() < 1e-12 && (y - 0.3).abs() < 1e-12);
    }

    #[test]
    fn pose3_slerp_midpoint() {
        let a = Pose3::identity();
        let b = Pose3::from_xyz_rpy(2.0, 0.0, 0.0, 0.0, 0.0, 1.0);
        let mid = a.interpolate(&b, 0.5);
        assert!((mid.to_planar().theta() - 0.5).abs() < 1e-12);
        assert!((mid.translation().x - 1.0).abs() < 1e-12);
    }

    #[test]
    fn planar_projection_of_lifted_pose_is_identity() {
        let p = Pose2::new(3.0, -1.0, -2.5);
        let q = p.to_pose3().to_planar();
        assert!((q.x() - 3.0).abs() < 1e-12 && (q.y() + 1.0).abs() < 1e-12);
        assert!((q.theta() + 2.5).abs() < 1e-12);
    }
}
