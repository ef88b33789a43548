//! Wheel odometry with drift: the sample-based odometry motion model of Thrun, Burgard and Fox,
//! *Probabilistic Robotics* (2005), §5.4, Table 5.6 (`sample_motion_model_odometry`).
//!
//! Between two consecutive instants the true motion is decomposed into a rotation `δrot1`, a
//! translation `δtrans` and a rotation `δrot2`. Each is perturbed by zero-mean Gaussian noise
//! whose variance grows with the motion:
//!
//! ```text
//! δ̂rot1  = δrot1  − ε(α₁·δrot1² + α₂·δtrans²)
//! δ̂trans = δtrans − ε(α₃·δtrans² + α₄·(δrot1² + δrot2²))
//! δ̂rot2  = δrot2  − ε(α₁·δrot2² + α₂·δtrans²)
//! ```
//!
//! (`ε(b²)`: a sample of N(0, b²)), and the odometry pose integrates the noisy increments:
//! `x̄' = x̄ + δ̂trans·cos(θ̄ + δ̂rot1)`, `ȳ' = ȳ + δ̂trans·sin(θ̄ + δ̂rot1)`,
//! `θ̄' = θ̄ + δ̂rot1 + δ̂rot2`. Units: α₁ and α₃ are dimensionless, α₂ in rad²/m², α₄ in
//! m²/rad². The noise is applied per odometry interval (and per laser instant between them),
//! so the drift depends on the rate: the defaults are tuned for 10 Hz. When the robot turns in
//! place (`δtrans` < 0.1 mm), `δrot1` is 0 and the whole turn is `δrot2`.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use raypath_geometry::{Pose2, wrap_angle};
use serde::Serialize;

use crate::error::{Result, SimError};

/// Odometry noise and rate.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OdometryConfig {
    /// `[α₁, α₂, α₃, α₄]` of the motion model (see the module documentation).
    pub alphas: [f64; 4],
    /// Rate of the `ODOM` messages in Hz.
    pub rate_hz: f64,
    /// Whether the odometry frame starts at (0, 0, 0) (as in raw robot logs) rather than at
    /// the true start pose.
    pub start_at_origin: bool,
}

impl Default for OdometryConfig {
    fn default() -> Self {
        Self {
            alphas: [0.005, 0.0005, 0.002, 0.0005],
            rate_hz: 10.0,
            start_at_origin: true,
        }
    }
}

impl OdometryConfig {
    /// Perfect odometry (no noise).
    pub fn noiseless() -> Self {
        Self {
            alphas: [0.0; 4],
            ..Self::default()
        }
    }

    /// Checks the alphas and the rate.
    pub fn validate(&self) -> Result<()> {
        if self.alphas.iter().any(|a| !(a.is_finite() && *a >= 0.0)) {
            return Err(SimError::InvalidParameter {
                name: "alphas",
                reason: format!("must be finite and ≥ 0, got {:?}", self.alphas),
            });
        }
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0) {
            return Err(SimError::InvalidParameter {
                name: "rate_hz",
                reason: format!("must be positive, got {}", self.rate_hz),
            });
        }
        Ok(())
    }
}

/// `(δrot1, δtrans, δrot2)` of the motion from `a` to `b`.
pub fn decompose(a: &Pose2, b: &Pose2) -> (f64, f64, f64) {
    let d = b.translation() - a.translation();
    let trans = d.norm();
    let rot1 = if trans < 1e-4 {
        0.0
    } else {
        wrap_angle(d.y.atan2(d.x) - a.theta())
    };
    let rot2 = wrap_angle(b.theta() - a.theta() - rot1);
    (rot1, trans, rot2)
}

/// One step of the model: the odometry pose after the true motion `true_from → true_to`,
/// starting from the odometry pose `odom`.
pub fn sample_step<R: Rng + ?Sized>(
    alphas: &[f64; 4],
    true_from: &Pose2,
    true_to: &Pose2,
    odom: &Pose2,
    rng: &mut R,
) -> Pose2 {
    let (rot1, trans, rot2) = decompose(true_from, true_to);
    let [a1, a2, a3, a4] = *alphas;
    let mut eps = |variance: f64| -> f64 {
        let z: f64 = StandardNormal.sample(rng);
        variance.max(0.0).sqrt() * z
    };
    let rot1_hat = rot1 - eps(a1 * rot1 * rot1 + a2 * trans * trans);
    let trans_hat = trans - eps(a3 * trans * trans + a4 * (rot1 * rot1 + rot2 * rot2));
    let rot2_hat = rot2 - eps(a1 * rot2 * rot2 + a2 * trans * trans);
    let heading = odom.theta() + rot1_hat;
    Pose2::new(
        odom.x() + trans_hat * heading.cos(),
        odom.y() + trans_hat * heading.sin(),
        wrap_angle(heading + rot2_hat),
    )
}

/// The odometry poses at the instants of `true_poses` (the first maps to `start`).
pub fn simulate<R: Rng + ?Sized>(
    alphas: &[f64; 4],
    true_poses: &[Pose2],
    start: Pose2,
    rng: &mut R,
) -> Vec<Pose2> {
    let mut out = Vec::with_capacity(true_poses.len());
    let mut odom = start;
    for (k, pose) in true_poses.iter().enumerate() {
        if let Some(prev) = k.checked_sub(1).and_then(|i| true_poses.get(i)) {
            odom = sample_step(alphas, prev, pose, &odom, rng);
        }
        out.push(odom);
    }
    out
}
