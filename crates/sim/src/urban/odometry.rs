//! Wheel odometry with configurable noise: the true planar increments between consecutive
//! samples, corrupted by zero-mean Gaussian noise whose standard deviations grow with the
//! distance driven and the angle turned, and integrated from the identity (the odometry frame
//! starts where the vehicle starts, as NCLT's `odometry_mu_100hz.csv`).

use rand::Rng;
use rand_distr::StandardNormal;
use raypath_geometry::Pose2;

use crate::rng::SimRng;

/// Standard deviations of the odometry noise per increment.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct OdometryNoise {
    /// Longitudinal error per metre driven (fraction).
    pub longitudinal_per_m: f64,
    /// Lateral error per metre driven (fraction).
    pub lateral_per_m: f64,
    /// Heading error per radian turned.
    pub heading_per_rad: f64,
    /// Heading error per metre driven, rad/m.
    pub heading_per_m_rad: f64,
}

impl Default for OdometryNoise {
    /// About 1–2 % of the distance and 2 % of the rotation, as for a car's wheel odometry
    /// fused with a gyroscope.
    fn default() -> Self {
        Self {
            longitudinal_per_m: 0.015,
            lateral_per_m: 0.005,
            heading_per_rad: 0.02,
            heading_per_m_rad: 2e-4,
        }
    }
}

impl OdometryNoise {
    /// No noise.
    pub fn none() -> Self {
        Self {
            longitudinal_per_m: 0.0,
            lateral_per_m: 0.0,
            heading_per_rad: 0.0,
            heading_per_m_rad: 0.0,
        }
    }

    /// Variances of (x, y, heading) of an increment `(dx, dy, dθ)`.
    pub fn variances(&self, increment: &Pose2) -> [f64; 3] {
        let d = increment.x().hypot(increment.y());
        let turn = increment.theta().abs();
        [
            (self.longitudinal_per_m * d).powi(2),
            (self.lateral_per_m * d).powi(2),
            (self.heading_per_rad * turn + self.heading_per_m_rad * d).powi(2),
        ]
    }
}

/// Simulated odometry along a sequence of true poses.
#[derive(Clone, Debug, PartialEq)]
pub struct Odometry {
    /// Integrated odometry at every sample, starting at the identity.
    pub poses: Vec<Pose2>,
    /// Variances of (x, y, heading) of the increment into each sample (zeros for the first).
    pub variances: Vec<[f64; 3]>,
}

impl Odometry {
    /// The noisy increment from sample `a` to sample `b` and the sum of the step variances
    /// in between (a diagonal approximation of its covariance).
    pub fn between(&self, a: usize, b: usize) -> Option<(Pose2, [f64; 3])> {
        let from = self.poses.get(a)?;
        let to = self.poses.get(b)?;
        let mut var = [0.0; 3];
        for v in self.variances.get(a + 1..=b).unwrap_or(&[]) {
            for k in 0..3 {
                var[k] += v[k];
            }
        }
        Some((from.inverse() * *to, var))
    }
}

/// Odometry along `truth` (planar poses at consecutive samples).
pub fn simulate(truth: &[Pose2], noise: &OdometryNoise, rng: &mut SimRng) -> Odometry {
    let mut poses = Vec::with_capacity(truth.len());
    let mut variances = Vec::with_capacity(truth.len());
    let mut current = Pose2::identity();
    if !truth.is_empty() {
        poses.push(current);
        variances.push([0.0; 3]);
    }
    for pair in truth.windows(2) {
        let step = pair[0].inverse() * pair[1];
        let var = noise.variances(&step);
        let n = |rng: &mut SimRng, v: f64| v.sqrt() * rng.sample::<f64, _>(StandardNormal);
        let noisy = Pose2::new(
            step.x() + n(rng, var[0]),
            step.y() + n(rng, var[1]),
            step.theta() + n(rng, var[2]),
        );
        current = current * noisy;
        poses.push(current);
        variances.push(var);
    }
    Odometry { poses, variances }
}
