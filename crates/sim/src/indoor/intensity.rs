//! Simulated laser intensities (remissions) from surface reflectivity, range and angle of
//! incidence.
//!
//! Khan (2017, §3.3) finds that real 2-D scanners (Hokuyo UTM-30LX, SICK LMS 291) do **not** follow
//! the Lambertian lidar equation `I ∝ ρ cos α / r²`: the intensity *drops* at short range
//! ("near-distance effect"), and the fall-off with the angle of incidence is not `cos α` and
//! changes with range, so the joint model `I = ρ · f(r, α)` (eq. 3.3) is needed, calibrated as a
//! look-up table. The simulated model has both effects so that a calibration has something to
//! recover, while staying a closed-form ground truth ([`IntensityModel::expected`]):
//!
//! ```text
//! I = clip( gain · ρ · h(r) · cos(α)^(p₀ + p₁·r) · (1 + ε_rel) + ε_abs,  0, saturation )
//! h(r) = 4 r_n² r² / (r² + r_n²)²          (0 at r = 0, peak 1 at r = r_n, ≈ 4 r_n²/r² far away)
//! ε_rel ~ N(0, σ_rel²),  ε_abs ~ N(0, σ_abs²)
//! ```
//!
//! `ρ` is the surface's reflectivity in [0, 1], `r` the true range in metres, `α` the angle
//! between the beam and the surface normal. The exponent `p₀ + p₁·r` makes the angular
//! fall-off steeper with range (`p₀ = 1` is Lambertian at short range), so `f(r, α)` does not
//! separate into `f(r)·f(α)`. Intensities are written as `ROBOTLASER1` remissions; a
//! no-return has remission 0.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Serialize;

/// Parameters of the intensity model (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct IntensityModel {
    /// Intensity of a white (ρ = 1) surface at the peak range `r_n`, head-on.
    pub gain: f64,
    /// Range of the intensity peak `r_n` in metres (the near-distance effect below it).
    pub near_range_m: f64,
    /// Angular exponent at zero range `p₀` (1 = Lambertian).
    pub angle_exponent: f64,
    /// Growth of the angular exponent per metre of range `p₁`.
    pub angle_exponent_per_m: f64,
    /// Relative (multiplicative) noise `σ_rel`.
    pub sigma_relative: f64,
    /// Absolute (additive) noise `σ_abs` in intensity units.
    pub sigma_absolute: f64,
    /// Largest reported intensity (the receiver saturates).
    pub saturation: f64,
}

impl Default for IntensityModel {
    fn default() -> Self {
        Self {
            gain: 1000.0,
            near_range_m: 1.5,
            angle_exponent: 1.0,
            angle_exponent_per_m: 0.08,
            sigma_relative: 0.02,
            sigma_absolute: 2.0,
            saturation: 1000.0,
        }
    }
}

impl IntensityModel {
    /// The range factor `h(r)` in [0, 1].
    pub fn range_factor(&self, range_m: f64) -> f64 {
        let (r2, n2) = (range_m * range_m, self.near_range_m * self.near_range_m);
        let denom = (r2 + n2) * (r2 + n2);
        if denom > 0.0 {
            4.0 * n2 * r2 / denom
        } else {
            0.0
        }
    }

    /// The angle factor `cos(α)^(p₀ + p₁·r)` in [0, 1].
    pub fn angle_factor(&self, range_m: f64, incidence_rad: f64) -> f64 {
        let c = incidence_rad.cos().clamp(0.0, 1.0);
        c.powf(self.angle_exponent + self.angle_exponent_per_m * range_m)
    }

    /// The noise-free intensity of a surface of reflectivity `reflectivity` at `range_m` and
    /// angle of incidence `incidence_rad` (clipped to the saturation).
    pub fn expected(&self, reflectivity: f64, range_m: f64, incidence_rad: f64) -> f64 {
        (self.gain
            * reflectivity
            * self.range_factor(range_m)
            * self.angle_factor(range_m, incidence_rad))
        .clamp(0.0, self.saturation)
    }

    /// A noisy intensity sample.
    pub fn sample<R: Rng + ?Sized>(
        &self,
        reflectivity: f64,
        range_m: f64,
        incidence_rad: f64,
        rng: &mut R,
    ) -> f64 {
        let clean = self.gain
            * reflectivity
            * self.range_factor(range_m)
            * self.angle_factor(range_m, incidence_rad);
        let rel: f64 = rng.sample(StandardNormal);
        let abs: f64 = StandardNormal.sample(rng);
        (clean * (1.0 + self.sigma_relative * rel) + self.sigma_absolute * abs)
            .clamp(0.0, self.saturation)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_distance_effect_and_non_separable_angle_fall_off() {
        let m = IntensityModel::default();
        // Peak at r_n, lower closer and farther.
        assert!((m.range_factor(1.5) - 1.0).abs() < 1e-12);
        assert!(m.range_factor(0.5) < m.range_factor(1.5));
        assert!(m.range_factor(10.0) < m.range_factor(1.5));
        assert_eq!(m.range_factor(0.0), 0.0);
        // Far away it falls off as 1/r².
        let ratio = m.range_factor(20.0) / m.range_factor(40.0);
        assert!((ratio - 4.0).abs() < 0.1);
        // The normalized angular fall-off differs with range.
        let near = m.angle_factor(1.0, 0.8) / m.angle_factor(1.0, 0.0);
        let far = m.angle_factor(15.0, 0.8) / m.angle_factor(15.0, 0.0);
        assert!(far < near - 0.1);
        assert!((m.expected(0.5, 1.5, 0.0) - 500.0).abs() < 1e-9);
        assert!(m.expected(1.0, 5.0, std::f64::consts::FRAC_PI_2) < 1e-12);
    }
}
