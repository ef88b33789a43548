//! Simulated return intensities from surface reflectivity, range and incidence angle.
//!
//! The Lambertian lidar equation says the received power is `P ∝ ϱ cos α / r²` (Khan 2017,
//! eq. 3.1; `ϱ` the diffuse reflectivity, `α` the incidence angle, `r` the range), but real
//! scanners deviate from it in two documented ways (Khan 2017, §3.3.1): intensities *drop* at
//! close range (receiver defocusing) and the angle dependence is not `cos α` and changes with
//! range, so `f(r, α)` does not separate. This model keeps both effects, normalized so that a
//! white Lambertian surface (`ϱ = 1`) seen head-on at mid range reads about 1:
//!
//! ```text
//! I = clamp( ϱ · near(r) · far(r) · cos(α)^k(r) + n,  0, 1 )
//! near(r) = 1 − exp(−(r / r_near)²)          defocusing below r_near
//! far(r)  = 1 / (1 + (r / r_ref)²)            inverse-square fall-off beyond r_ref
//! k(r)    = k₀ · (1 + c · r / r_ref)           angle exponent growing with range
//! n ~ N(0, σ_I²)
//! ```
//!
//! The result is in `[0, 1]`, the unit of KITTI's reflectance channel; NCLT stores intensities
//! as `u8`, so writers scale by 255. A return whose noise-free intensity falls below the
//! detection threshold is lost (weak echoes of dark surfaces at grazing angles and long range,
//! the main cause of missing returns on real roads).

use crate::error::{Result, SimError};

/// Parameters of the intensity model (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IntensityModel {
    /// `r_near` in metres: below it the intensity drops (defocusing). 0 disables the effect.
    pub near_range_m: f64,
    /// `r_ref` in metres: the range at which the inverse-square fall-off halves the intensity.
    pub reference_range_m: f64,
    /// `k₀`: exponent of `cos α` at zero range (1 = Lambertian).
    pub angle_exponent: f64,
    /// `c`: growth of the angle exponent with range, per `r_ref` (0 = separable model).
    pub angle_range_coupling: f64,
    /// `σ_I`: standard deviation of additive Gaussian noise on the intensity.
    pub noise_sigma: f64,
    /// Returns with a noise-free intensity below this value are lost (0 keeps all).
    pub detection_threshold: f64,
}

impl Default for IntensityModel {
    /// Values for a Velodyne-like sensor: defocusing below 1.5 m, half intensity at 40 m,
    /// Lambertian near the sensor and steeper with range, 1 % noise, echoes below 0.002 lost.
    fn default() -> Self {
        Self {
            near_range_m: 1.5,
            reference_range_m: 40.0,
            angle_exponent: 1.0,
            angle_range_coupling: 0.5,
            noise_sigma: 0.01,
            detection_threshold: 0.002,
        }
    }
}

impl IntensityModel {
    /// The model without noise or detection threshold and without range effects beyond
    /// Lambert's cosine law (`I = ϱ cos α`).
    pub fn lambertian() -> Self {
        Self {
            near_range_m: 0.0,
            reference_range_m: f64::INFINITY,
            angle_exponent: 1.0,
            angle_range_coupling: 0.0,
            noise_sigma: 0.0,
            detection_threshold: 0.0,
        }
    }

    /// Checks that every parameter is finite (`r_ref` may be +∞) and non-negative, and
    /// `r_ref` positive.
    pub fn validate(&self) -> Result<()> {
        let checks = [
            ("intensity.near_range_m", self.near_range_m, false),
            ("intensity.reference_range_m", self.reference_range_m, true),
            ("intensity.angle_exponent", self.angle_exponent, false),
            (
                "intensity.angle_range_coupling",
                self.angle_range_coupling,
                false,
            ),
            ("intensity.noise_sigma", self.noise_sigma, false),
            (
                "intensity.detection_threshold",
                self.detection_threshold,
                false,
            ),
        ];
        for (name, value, may_be_infinite) in checks {
            let finite_ok = value.is_finite() || (may_be_infinite && value == f64::INFINITY);
            if !(finite_ok && value >= 0.0) {
                return Err(SimError::InvalidParameter {
                    name,
                    reason: format!("{value} (expected a finite value ≥ 0)"),
                });
            }
        }
        if self.reference_range_m <= 0.0 {
            return Err(SimError::InvalidParameter {
                name: "intensity.reference_range_m",
                reason: "must be positive".into(),
            });
        }
        Ok(())
    }

    /// The noise-free intensity of a surface of `reflectivity` at `range_m`, hit with
    /// `cos_incidence = |cos α|`; in `[0, 1]`.
    pub fn expected(&self, reflectivity: f64, range_m: f64, cos_incidence: f64) -> f64 {
        let near = if self.near_range_m > 0.0 {
            let x = range_m / self.near_range_m;
            1.0 - (-x * x).exp()
        } else {
            1.0
        };
        let rho = range_m / self.reference_range_m;
        let far = 1.0 / (1.0 + rho * rho);
        let k = self.angle_exponent * (1.0 + self.angle_range_coupling * rho);
        let angle = cos_incidence.clamp(0.0, 1.0).powf(k);
        (reflectivity * near * far * angle).clamp(0.0, 1.0)
    }

    /// The measured intensity: [`expected`](Self::expected) plus `σ_I · standard_normal`,
    /// clamped to `[0, 1]`.
    pub fn measured(&self, expected: f64, standard_normal: f64) -> f64 {
        (expected + self.noise_sigma * standard_normal).clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn falls_off_with_range_and_angle_and_drops_near_the_sensor() {
        let m = IntensityModel::default();
        let head_on = |r| m.expected(0.8, r, 1.0);
        assert!(head_on(0.3) < head_on(3.0));
        assert!(head_on(3.0) > head_on(30.0));
        assert!((head_on(40.0) - 0.8 * 0.5).abs() < 0.01);
        assert!(m.expected(0.8, 10.0, 0.5) < head_on(10.0));
        // Non-separable: the relative angle fall-off is stronger far away.
        let rel = |r| m.expected(0.8, r, 0.5) / m.expected(0.8, r, 1.0);
        assert!(rel(60.0) < rel(5.0));
        let lambert = IntensityModel::lambertian();
        assert!((lambert.expected(0.6, 123.0, 0.5) - 0.3).abs() < 1e-12);
    }

    #[test]
    fn rejects_bad_parameters() {
        let bad = IntensityModel {
            noise_sigma: f64::NAN,
            ..IntensityModel::default()
        };
        assert!(bad.validate().is_err());
        assert!(IntensityModel::lambertian().validate().is_ok());
    }
}
