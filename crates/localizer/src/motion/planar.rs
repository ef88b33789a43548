//! The Gaussian increment model of Schaefer (2020), ch. 12 (pole-based localization):
//! the particle moves by a sample of the odometry increment,
//!
//! ```text
//!   ξ ~ N(χ, s · Σ),   X_t = X_{t−1} · transform(ξ),   χ = [x, y, φ]ᵀ
//! ```
//!
//! with χ and Σ the odometry increment and its covariance (NCLT provides both) and s a
//! variance scale (the thesis inflates NCLT's covariance by s = 2² = 4, i.e. doubles the
//! standard deviations). Composition on the right (body frame), as the reference implementation;
//! the thesis prints `transform(ξ) · X_{t−1}`.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use raypath_geometry::{Pose2, wrap_angle};
use serde::{Deserialize, Serialize};

use crate::error::{LocalizerError, require_non_negative};
use crate::models::MotionModel;

/// One odometry increment with its covariance, factorized once for sampling.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanarIncrement {
    /// The mean increment χ = (x m, y m, φ rad) in the previous body frame.
    pub mean: Vector3<f64>,
    /// A square root `L` of the covariance (`L Lᵀ = Σ`), units of `mean`.
    pub sqrt_covariance: Matrix3<f64>,
}

impl PlanarIncrement {
    /// The increment `previous_from_current` with covariance `covariance` (of x, y, φ).
    /// The covariance must be symmetric positive semi-definite (zero is allowed).
    pub fn new(
        previous_from_current: &Pose2,
        covariance: &Matrix3<f64>,
    ) -> Result<Self, LocalizerError> {
        if !previous_from_current.is_finite() {
            return Err(LocalizerError::NonFinite {
                what: "increment",
                index: 0,
            });
        }
        if let Some(index) = covariance.iter().position(|v| !v.is_finite()) {
            return Err(LocalizerError::NonFinite {
                what: "covariance entry",
                index,
            });
        }
        let scale = covariance.abs().max().max(f64::MIN_POSITIVE);
        if (covariance - covariance.transpose()).abs().max() > 1e-9 * scale {
            return Err(LocalizerError::NotPositiveDefinite { name: "covariance" });
        }
        let eigen = SymmetricEigen::new(*covariance);
        if eigen.eigenvalues.min() < -1e-9 * scale {
            return Err(LocalizerError::NotPositiveDefinite { name: "covariance" });
        }
        let roots = eigen.eigenvalues.map(|v| v.max(0.0).sqrt());
        let sqrt_covariance = eigen.eigenvectors * Matrix3::from_diagonal(&roots);
        Ok(Self {
            mean: Vector3::new(
                previous_from_current.x(),
                previous_from_current.y(),
                previous_from_current.theta(),
            ),
            sqrt_covariance,
        })
    }

    /// The increment with independent standard deviations (x m, y m, φ rad).
    pub fn with_std(previous_from_current: &Pose2, std: [f64; 3]) -> Result<Self, LocalizerError> {
        for (i, s) in std.iter().enumerate() {
            require_non_negative(["std x", "std y", "std phi"][i.min(2)], *s)?;
        }
        let variances = Vector3::new(std[0] * std[0], std[1] * std[1], std[2] * std[2]);
        Self::new(previous_from_current, &Matrix3::from_diagonal(&variances))
    }
}

/// The Gaussian increment motion model (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanarGaussianMotionModel {
    /// Scale s of the covariance (variance units). Default 1; the thesis uses 4 on NCLT.
    pub covariance_scale: f64,
}

impl Default for PlanarGaussianMotionModel {
    fn default() -> Self {
        Self {
            covariance_scale: 1.0,
        }
    }
}

impl MotionModel<Pose2> for PlanarGaussianMotionModel {
    type Control = PlanarIncrement;

    fn sample(&self, state: &Pose2, control: &PlanarIncrement, rng: &mut impl Rng) -> Pose2 {
        let noise = Vector3::new(
            StandardNormal.sample(rng),
            StandardNormal.sample(rng),
            StandardNormal.sample(rng),
        );
        let xi = control.mean
            + self.covariance_scale.max(0.0).sqrt() * (control.sqrt_covariance * noise);
        let increment = Pose2::new(xi.x, xi.y, wrap_angle(xi.z));
        *state * increment
    }
}
