//! A 6-DOF Gaussian increment model for SE(3).
//!
//! Schaefer (2020, ch. 7 and 8) localizes in six dimensions but does not state the motion
//! model; this is ours. Given the body-frame odometry increment
//! Δ = (Δt, ΔR) with translation length d = ‖Δt‖ (m) and rotation angle a = ∠ΔR (rad), the
//! particle moves by the perturbed increment
//!
//! ```text
//!   x' = x · Δ · (ξ_t, exp(ξ_r)),   ξ_t ~ N(0, diag(σ_t²)),   ξ_r ~ N(0, diag(σ_r²))
//!   σ_t,j = k_tt · d + k_tr · a + c_t,j      (j = x, y, z of the frame at the end of Δ)
//!   σ_r,j = k_rt · d + k_rr · a + c_r,j      (j = roll, pitch, yaw axes, rotation vector)
//! ```
//!
//! i.e. noise proportional to the increment plus constant terms (the constants keep a
//! standing vehicle's particles from collapsing). The perturbation is applied in the frame
//! at the end of the increment; the rotation noise is a rotation vector (axis × angle).
//!
//! Defaults (documented choices, not from the thesis): k_tt = 0.05 (5 % of the distance),
//! k_tr = 0, k_rt = 0.005 rad/m, k_rr = 0.05, c_t = (0.01, 0.01, 0.01) m,
//! c_r = (0.001, 0.001, 0.002) rad per step.

use nalgebra::{UnitQuaternion, Vector3};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use raypath_geometry::Pose3;
use serde::{Deserialize, Serialize};

use crate::error::{LocalizerError, require_non_negative};
use crate::models::MotionModel;
use crate::state::FilterState;

/// The 6-DOF Gaussian increment model (module docs). The control is the body-frame
/// increment `previous_from_current` as a [`Pose3`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Gaussian6DofMotionModel {
    /// k_tt: translation std per metre travelled. Default 0.05.
    pub translation_per_m: f64,
    /// k_tr: translation std (m) per radian turned. Default 0.
    pub translation_per_rad: f64,
    /// k_rt: rotation std (rad) per metre travelled. Default 0.005.
    pub rotation_per_m: f64,
    /// k_rr: rotation std per radian turned. Default 0.05.
    pub rotation_per_rad: f64,
    /// c_t: constant translation std (x, y, z) in metres per step. Default 0.01 m each.
    pub const_translation_m: [f64; 3],
    /// c_r: constant rotation std (about x, y, z) in radians per step.
    /// Default (0.001, 0.001, 0.002).
    pub const_rotation_rad: [f64; 3],
}

impl Default for Gaussian6DofMotionModel {
    fn default() -> Self {
        Self {
            translation_per_m: 0.05,
            translation_per_rad: 0.0,
            rotation_per_m: 0.005,
            rotation_per_rad: 0.05,
            const_translation_m: [0.01; 3],
            const_rotation_rad: [0.001, 0.001, 0.002],
        }
    }
}

impl Gaussian6DofMotionModel {
    /// Checks that every coefficient is finite and non-negative.
    pub fn validate(&self) -> Result<(), LocalizerError> {
        require_non_negative("translation_per_m", self.translation_per_m)?;
        require_non_negative("translation_per_rad", self.translation_per_rad)?;
        require_non_negative("rotation_per_m", self.rotation_per_m)?;
        require_non_negative("rotation_per_rad", self.rotation_per_rad)?;
        for c in self.const_translation_m {
            require_non_negative("const_translation_m", c)?;
        }
        for c in self.const_rotation_rad {
            require_non_negative("const_rotation_rad", c)?;
        }
        Ok(())
    }

    /// The standard deviations (σ_t in m, σ_r in rad, per axis) for an increment.
    pub fn noise_std(&self, increment: &Pose3) -> ([f64; 3], [f64; 3]) {
        let d = increment.translation_norm();
        let a = increment.rotation_angle();
        let t = self.translation_per_m * d + self.translation_per_rad * a;
        let r = self.rotation_per_m * d + self.rotation_per_rad * a;
        (
            self.const_translation_m.map(|c| t + c),
            self.const_rotation_rad.map(|c| r + c),
        )
    }
}

impl MotionModel<Pose3> for Gaussian6DofMotionModel {
    type Control = Pose3;

    fn sample(&self, state: &Pose3, increment: &Pose3, rng: &mut impl Rng) -> Pose3 {
        let (sigma_t, sigma_r) = self.noise_std(increment);
        let mut draw = |s: f64| -> f64 {
            let n: f64 = StandardNormal.sample(rng);
            s * n
        };
        let xi_t = Vector3::new(draw(sigma_t[0]), draw(sigma_t[1]), draw(sigma_t[2]));
        let xi_r = Vector3::new(draw(sigma_r[0]), draw(sigma_r[1]), draw(sigma_r[2]));
        let noise = Pose3::from_parts(xi_t, UnitQuaternion::from_scaled_axis(xi_r));
        *state * *increment * noise
    }
}
