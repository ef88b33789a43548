//! The states a particle can hold: [`Pose2`] (SE(2)) and [`Pose3`] (SE(3)).
//!
//! [`FilterState`] collects what the filter, the estimators and the evaluation need from a
//! pose type: composition, interpolation, a weighted mean, the KLD-sampling bin and the
//! planar projection.
//!
//! ## Weighted means
//!
//! * **SE(2)**: x and y are weighted arithmetic means; the heading is the weighted circular
//!   mean θ̄ = atan2(Σ wᵢ sin θᵢ, Σ wᵢ cos θᵢ) (θ̄ = 0 when both sums vanish).
//! * **SE(3)**: the translation is the weighted arithmetic mean; the rotation is the
//!   weighted quaternion average of Markley et al. ("Averaging quaternions", J. Guidance,
//!   Control, and Dynamics 30(4), 2007): the unit eigenvector of the largest eigenvalue of
//!   M = Σ wᵢ qᵢ qᵢᵀ (4 × 4). It minimizes the weighted sum of squared chordal distances
//!   of the rotation matrices, is insensitive to the sign ambiguity q ≡ −q and needs no
//!   iteration or starting point.

use std::fmt::Debug;

use nalgebra::{Matrix4, Quaternion, SymmetricEigen, UnitQuaternion, Vector3, Vector4};
use raypath_geometry::{Pose2, Pose3, wrap_angle};

use crate::kld::KldBins;

/// A pose type the particle filter can estimate.
pub trait FilterState: Copy + Send + Sync + Debug + 'static {
    /// The identity transform.
    fn identity() -> Self;

    /// The weighted mean of `(state, weight)` pairs (see the module docs for the rotation
    /// part). Weights must be non-negative; `None` when their sum is not positive and finite.
    fn weighted_mean<'a, I>(pairs: I) -> Option<Self>
    where
        I: IntoIterator<Item = (&'a Self, f64)>;

    /// The KLD-sampling histogram bin of the state (unused axes are 0).
    fn kld_bin(&self, bins: &KldBins) -> [i64; 6];

    /// True when every component is finite.
    fn is_finite(&self) -> bool;

    /// Interpolation from `self` (t = 0) to `other` (t = 1): linear in the translation,
    /// shorter arc (slerp) in the rotation.
    fn interpolate(&self, other: &Self, t: f64) -> Self;

    /// Composition `self * other` (apply `other` first, then `self`).
    fn compose(&self, other: &Self) -> Self;

    /// The inverse transform.
    fn inverse(&self) -> Self;

    /// The projection onto the ground plane (x, y, heading).
    fn to_planar(&self) -> Pose2;

    /// The length of the translation in metres.
    fn translation_norm(&self) -> f64;

    /// The rotation angle in radians, in `[0, π]`.
    fn rotation_angle(&self) -> f64;
}

/// The bin index of `value` for bins of `size` (floor division).
fn bin_of(value: f64, size: f64) -> i64 {
    // `as` saturates for huge values and maps NaN to 0: no panic on any input.
    (value / size).floor() as i64
}

impl FilterState for Pose2 {
    fn identity() -> Self {
        Pose2::identity()
    }

    fn weighted_mean<'a, I>(pairs: I) -> Option<Self>
    where
        I: IntoIterator<Item = (&'a Self, f64)>,
    {
        let (mut w_sum, mut x, mut y, mut s, mut c) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (pose, w) in pairs {
            w_sum += w;
            x += w * pose.x();
            y += w * pose.y();
            let (sin, cos) = pose.theta().sin_cos();
            s += w * sin;
            c += w * cos;
        }
        if !(w_sum.is_finite() && w_sum > 0.0) {
            return None;
        }
        let theta = if s == 0.0 && c == 0.0 {
            0.0
        } else {
            s.atan2(c)
        };
        Some(Pose2::new(x / w_sum, y / w_sum, theta))
    }

    fn kld_bin(&self, bins: &KldBins) -> [i64; 6] {
        [
            bin_of(self.x(), bins.xy_m),
            bin_of(self.y(), bins.xy_m),
            bin_of(self.theta(), bins.angle_rad),
            0,
            0,
            0,
        ]
    }

    fn is_finite(&self) -> bool {
        Pose2::is_finite(self)
    }

    fn interpolate(&self, other: &Self, t: f64) -> Self {
        Pose2::interpolate(self, other, t)
    }

    fn compose(&self, other: &Self) -> Self {
        *self * *other
    }

    fn inverse(&self) -> Self {
        Pose2::inverse(self)
    }

    fn to_planar(&self) -> Pose2 {
        *self
    }

    fn translation_norm(&self) -> f64 {
        self.translation().norm()
    }

    fn rotation_angle(&self) -> f64 {
        wrap_angle(self.theta()).abs()
    }
}

impl FilterState for Pose3 {
    fn identity() -> Self {
        Pose3::identity()
    }

    fn weighted_mean<'a, I>(pairs: I) -> Option<Self>
    where
        I: IntoIterator<Item = (&'a Self, f64)>,
    {
        let mut w_sum = 0.0;
        let mut translation = Vector3::zeros();
        let mut scatter = Matrix4::zeros();
        for (pose, w) in pairs {
            w_sum += w;
            translation += w * pose.translation();
            let q: Vector4<f64> = pose.rotation().into_inner().coords;
            scatter += w * q * q.transpose();
        }
        if !(w_sum.is_finite() && w_sum > 0.0) {
            return None;
        }
        let eigen = SymmetricEigen::new(scatter / w_sum);
        let best = eigen.eigenvalues.imax();
        let q = eigen.eigenvectors.column(best).into_owned();
        let rotation = UnitQuaternion::from_quaternion(Quaternion::from(q));
        Some(Pose3::from_parts(translation / w_sum, rotation))
    }

    fn kld_bin(&self, bins: &KldBins) -> [i64; 6] {
        let t = self.translation();
        let (roll, pitch, yaw) = self.rpy();
        [
            bin_of(t.x, bins.xy_m),
            bin_of(t.y, bins.xy_m),
            bin_of(t.z, bins.z_m),
            bin_of(roll, bins.angle_rad),
            bin_of(pitch, bins.angle_rad),
            bin_of(yaw, bins.angle_rad),
        ]
    }

    fn is_finite(&self) -> bool {
        Pose3::is_finite(self)
    }

    fn interpolate(&self, other: &Self, t: f64) -> Self {
        Pose3::interpolate(self, other, t)
    }

    fn compose(&self, other: &Self) -> Self {
        *self * *other
    }

    fn inverse(&self) -> Self {
        Pose3::inverse(self)
    }

    fn to_planar(&self) -> Pose2 {
        Pose3::to_planar(self)
    }

    fn translation_norm(&self) -> f64 {
        self.translation().norm()
    }

    fn rotation_angle(&self) -> f64 {
        // `angle()` goes through acos of w (poor near 0); 2·atan2(|v|, |w|) is exact.
        let q = self.rotation().into_inner();
        2.0 * q.imag().norm().atan2(q.w.abs())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn circular_mean_across_the_seam() {
        let poses = [
            Pose2::new(0.0, 0.0, PI - 0.1),
            Pose2::new(2.0, 4.0, -PI + 0.1),
        ];
        let mean = Pose2::weighted_mean(poses.iter().map(|p| (p, 1.0))).unwrap();
        assert!((mean.x() - 1.0).abs() < 1e-12 && (mean.y() - 2.0).abs() < 1e-12);
        assert!((mean.theta().abs() - PI).abs() < 1e-12);
    }

    #[test]
    fn quaternion_mean_of_symmetric_rotations_and_sign_flip() {
        let a = Pose3::from_xyz_rpy(0.0, 0.0, 0.0, 0.0, 0.0, 0.3);
        let b = Pose3::from_xyz_rpy(2.0, 0.0, 0.0, 0.0, 0.0, -0.3);
        // The same rotation as `b` with the opposite quaternion sign.
        let b_flipped = Pose3::from_parts(
            b.translation(),
            UnitQuaternion::new_unchecked(-b.rotation().into_inner()),
        );
        let mean = Pose3::weighted_mean([(&a, 1.0), (&b_flipped, 1.0)]).unwrap();
        assert!(mean.rotation_angle() < 1e-9);
        assert!((mean.translation().x - 1.0).abs() < 1e-12);
    }

    #[test]
    fn zero_weights_have_no_mean() {
        let p = Pose2::new(1.0, 1.0, 0.0);
        assert!(Pose2::weighted_mean([(&p, 0.0)]).is_none());
        assert!(Pose3::weighted_mean(std::iter::empty()).is_none());
    }

    #[test]
    fn rotation_angle_is_exact_for_small_angles() {
        let p = Pose3::from_xyz_rpy(0.0, 0.0, 0.0, 1e-9, 0.0, 0.0);
        assert!((p.rotation_angle() - 1e-9).abs() < 1e-18);
    }
}
