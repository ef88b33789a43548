//! KISS-ICP's adaptive correspondence threshold (Vizzo et al. 2023): σ is the root mean square
//! of how far the constant-velocity prediction was off, measured as the largest displacement
//! the deviation causes to a point within the sensor's range.

use raypath_geometry::Pose3;

/// The adaptive threshold σ: correspondences are gated at 3σ and the kernel scale is σ / 3.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveThreshold {
    min_motion_m: f64,
    max_range_m: f64,
    sum_squares: f64,
    samples: usize,
}

impl AdaptiveThreshold {
    /// Starts at σ = `initial_m`; deviations below `min_motion_m` are ignored; `max_range_m`
    /// turns a rotation into the displacement it causes at the edge of the scan.
    pub fn new(initial_m: f64, min_motion_m: f64, max_range_m: f64) -> Self {
        Self {
            min_motion_m,
            max_range_m,
            sum_squares: initial_m * initial_m,
            samples: 1,
        }
    }

    /// The current σ, metres.
    pub fn sigma(&self) -> f64 {
        (self.sum_squares / self.samples as f64).sqrt()
    }

    /// The model error of a deviation `prediction⁻¹ · estimate`: `‖t‖ + 2 r_max sin(θ / 2)`
    /// (the chord a rotation by θ moves a point at the maximum range), metres.
    pub fn model_error(&self, deviation: &Pose3) -> f64 {
        let theta = deviation.rotation().angle();
        deviation.translation().norm() + 2.0 * self.max_range_m * (theta / 2.0).sin()
    }

    /// Adds a deviation to the statistics when its model error exceeds the minimum motion.
    pub fn update(&mut self, deviation: &Pose3) {
        let error = self.model_error(deviation);
        if error.is_finite() && error > self.min_motion_m {
            self.sum_squares += error * error;
            self.samples += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sigma_is_the_rms_of_large_deviations() {
        let mut t = AdaptiveThreshold::new(2.0, 0.1, 100.0);
        assert_eq!(t.sigma(), 2.0);
        // Below the minimum motion: ignored.
        t.update(&Pose3::from_xyz_rpy(0.05, 0.0, 0.0, 0.0, 0.0, 0.0));
        assert_eq!(t.sigma(), 2.0);
        t.update(&Pose3::from_xyz_rpy(0.5, 0.0, 0.0, 0.0, 0.0, 0.0));
        assert!((t.sigma() - ((4.0 + 0.25) / 2.0f64).sqrt()).abs() < 1e-12);
        // 0.01 rad at 100 m moves a point by 2·100·sin(0.005) ≈ 1 m.
        let rot = Pose3::from_xyz_rpy(0.0, 0.0, 0.0, 0.0, 0.0, 0.01);
        assert!((t.model_error(&rot) - 200.0 * 0.005f64.sin()).abs() < 1e-9);
    }
}
