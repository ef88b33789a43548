//! The odometry motion model of Thrun, Burgard and Fox, *Probabilistic Robotics* (2005),
//! §5.4, Table 5.6 (`sample_motion_model_odometry`), with AMCL's two refinements.
//!
//! The relative motion between two odometry readings x̄ = (x̄, ȳ, θ̄) and x̄' is decomposed
//! into a rotation, a translation and a second rotation:
//!
//! ```text
//!   δrot1  = atan2(ȳ' − ȳ, x̄' − x̄) − θ̄
//!   δtrans = √((x̄' − x̄)² + (ȳ' − ȳ)²)
//!   δrot2  = θ̄' − θ̄ − δrot1
//! ```
//!
//! Each is perturbed by zero-mean Gaussian noise whose **variance** grows with the motion:
//!
//! ```text
//!   δ̂rot1  = δrot1  − ε(α1 δrot1² + α2 δtrans²)
//!   δ̂trans = δtrans − ε(α3 δtrans² + α4 δrot1² + α4 δrot2²)
//!   δ̂rot2  = δrot2  − ε(α1 δrot2² + α2 δtrans²)
//!   x' = x + δ̂trans cos(θ + δ̂rot1),  y' = y + δ̂trans sin(θ + δ̂rot1),  θ' = θ + δ̂rot1 + δ̂rot2
//! ```
//!
//! where ε(b²) samples N(0, b²). Units: α1 rad²/rad², α2 rad²/m², α3 m²/m², α4 m²/rad².
//!
//! AMCL refinements (ROS `amcl`, `AMCLOdom::UpdateAction`, model `diff-corrected`):
//! * for δtrans < 1 cm, δrot1 = 0 (the heading of a tiny translation is noise);
//! * in the noise terms δrot is replaced by min(|δrot|, π − |δrot|), so driving backwards
//!   (δrot1 ≈ ±π) is not mistaken for a half turn.
//!
//! Defaults α1 = α2 = α3 = α4 = 0.2, the defaults of ROS AMCL (`odom_alpha1..4`).

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use std::f64::consts::PI;

use nalgebra::{Isometry2, UnitComplex, Vector2};
use raypath_geometry::{Pose2, wrap_angle};
use serde::{Deserialize, Serialize};

use crate::error::{LocalizerError, require_non_negative};
use crate::models::MotionModel;

/// Translations shorter than this (metres) have δrot1 = 0 (AMCL).
const MIN_TRANSLATION_FOR_HEADING_M: f64 = 0.01;

/// The odometry motion model (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OdometryMotionModel {
    /// α1: rotation noise from rotation. Default 0.2.
    pub alpha1: f64,
    /// α2: rotation noise from translation. Default 0.2.
    pub alpha2: f64,
    /// α3: translation noise from translation. Default 0.2.
    pub alpha3: f64,
    /// α4: translation noise from rotation. Default 0.2.
    pub alpha4: f64,
}

impl Default for OdometryMotionModel {
    fn default() -> Self {
        Self {
            alpha1: 0.2,
            alpha2: 0.2,
            alpha3: 0.2,
            alpha4: 0.2,
        }
    }
}

impl OdometryMotionModel {
    /// The model with the given α1..α4, checked to be finite and non-negative.
    pub fn new(alpha1: f64, alpha2: f64, alpha3: f64, alpha4: f64) -> Result<Self, LocalizerError> {
        require_non_negative("alpha1", alpha1)?;
        require_non_negative("alpha2", alpha2)?;
        require_non_negative("alpha3", alpha3)?;
        require_non_negative("alpha4", alpha4)?;
        Ok(Self {
            alpha1,
            alpha2,
            alpha3,
            alpha4,
        })
    }

    /// The standard deviations (rot1 rad, trans m, rot2 rad) of the noise added to the three
    /// components of `control` (module docs).
    pub fn noise_std(&self, control: &OdometryControl) -> [f64; 3] {
        let fold = |a: f64| {
            // Controls from `from_poses` are wrapped already; skip the costly fmod then.
            let a = if a.abs() <= PI {
                a.abs()
            } else {
                wrap_angle(a).abs()
            };
            a.min(PI - a)
        };
        let r1 = fold(control.rot1_rad);
        let r2 = fold(control.rot2_rad);
        let t = control.trans_m;
        [
            (self.alpha1 * r1 * r1 + self.alpha2 * t * t).sqrt(),
            (self.alpha3 * t * t + self.alpha4 * (r1 * r1 + r2 * r2)).sqrt(),
            (self.alpha1 * r2 * r2 + self.alpha2 * t * t).sqrt(),
        ]
    }
}

/// The odometry input of one prediction step, decomposed into (δrot1, δtrans, δrot2).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OdometryControl {
    /// δrot1 in radians.
    pub rot1_rad: f64,
    /// δtrans in metres (non-negative).
    pub trans_m: f64,
    /// δrot2 in radians.
    pub rot2_rad: f64,
}

impl OdometryControl {
    /// The control between two odometry readings `odom_from_previous` and
    /// `odom_from_current` (poses of the robot in the odometry frame).
    pub fn from_poses(odom_from_previous: &Pose2, odom_from_current: &Pose2) -> Self {
        let dx = odom_from_current.x() - odom_from_previous.x();
        let dy = odom_from_current.y() - odom_from_previous.y();
        let trans_m = dx.hypot(dy);
        let rot1_rad = if trans_m < MIN_TRANSLATION_FOR_HEADING_M {
            0.0
        } else {
            wrap_angle(dy.atan2(dx) - odom_from_previous.theta())
        };
        let rot2_rad =
            wrap_angle(odom_from_current.theta() - odom_from_previous.theta() - rot1_rad);
        Self {
            rot1_rad,
            trans_m,
            rot2_rad,
        }
    }

    /// The control of a body-frame increment `previous_from_current`.
    pub fn from_increment(previous_from_current: &Pose2) -> Self {
        Self::from_poses(&Pose2::identity(), previous_from_current)
    }

    /// True when every component is finite.
    pub fn is_finite(&self) -> bool {
        self.rot1_rad.is_finite() && self.trans_m.is_finite() && self.rot2_rad.is_finite()
    }
}

impl MotionModel<Pose2> for OdometryMotionModel {
    type Control = OdometryControl;

    fn sample(&self, state: &Pose2, control: &OdometryControl, rng: &mut impl Rng) -> Pose2 {
        let [s_rot1, s_trans, s_rot2] = self.noise_std(control);
        let n1: f64 = StandardNormal.sample(rng);
        let n2: f64 = StandardNormal.sample(rng);
        let n3: f64 = StandardNormal.sample(rng);
        let rot1 = control.rot1_rad - s_rot1 * n1;
        let trans = control.trans_m - s_trans * n2;
        let rot2 = control.rot2_rad - s_rot2 * n3;
        // Rotations as unit complex numbers: two sin/cos, no atan2 or angle wrapping.
        let heading = state.isometry.rotation * UnitComplex::new(rot1);
        let direction = Vector2::new(heading.cos_angle(), heading.sin_angle());
        let translation = state.translation() + trans * direction;
        Pose2::from(Isometry2::from_parts(
            translation.into(),
            heading * UnitComplex::new(rot2),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::ParticleRng;

    #[test]
    fn noiseless_model_reproduces_the_odometry_increment() {
        let model = OdometryMotionModel::new(0.0, 0.0, 0.0, 0.0).unwrap();
        let a = Pose2::new(1.0, 2.0, 0.3);
        let b = Pose2::new(2.5, 1.0, -1.2);
        let control = OdometryControl::from_poses(&a, &b);
        let start = Pose2::new(-4.0, 3.0, 2.0);
        let end = model.sample(&start, &control, &mut ParticleRng::seed_from_u64(0));
        let expected = start * (a.inverse() * b);
        assert!((end.translation() - expected.translation()).norm() < 1e-12);
        assert!(wrap_angle(end.theta() - expected.theta()).abs() < 1e-12);
    }

    #[test]
    fn backward_motion_is_not_a_half_turn() {
        let control = OdometryControl::from_increment(&Pose2::new(-1.0, 0.0, 0.0));
        assert!((control.rot1_rad.abs() - PI).abs() < 1e-12);
        let std = OdometryMotionModel::default().noise_std(&control);
        // Only translation contributes: √(α2 · 1²) for the rotations.
        assert!((std[0] - 0.2f64.sqrt()).abs() < 1e-9);
        assert!((std[1] - 0.2f64.sqrt()).abs() < 1e-9);
    }

    #[test]
    fn rejects_negative_alphas() {
        assert!(OdometryMotionModel::new(0.1, -0.1, 0.1, 0.1).is_err());
        assert!(OdometryMotionModel::new(0.1, f64::NAN, 0.1, 0.1).is_err());
    }
}
