//! Conjugate priors and their estimation by the method of moments (Schaefer 2020, Sec. 8.5).

use serde::{Deserialize, Serialize};

use crate::SensorModelError;
use crate::stats::CellStats;

/// Mean and variance of a map's ML cell values, over the cells that enter the estimate (observed
/// cells with a finite ML value; Sec. 8.5 does not say which cells enter).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MomentStatistics {
    /// Number of cells.
    pub cells: u64,
    /// Empirical mean `E`.
    pub mean: f64,
    /// Empirical (population) variance `V`.
    pub variance: f64,
}

impl MomentStatistics {
    /// Moments of `values` (Welford's algorithm); `None` when empty.
    pub fn of(values: impl IntoIterator<Item = f64>) -> Option<Self> {
        let mut n = 0u64;
        let mut mean = 0.0;
        let mut m2 = 0.0;
        for x in values {
            n += 1;
            let delta = x - mean;
            mean += delta / n as f64;
            m2 += delta * (x - mean);
        }
        (n > 0).then(|| Self {
            cells: n,
            mean,
            variance: m2 / n as f64,
        })
    }

    /// Moments of the ML reflection map `μ_i = H_i / (H_i + M_i)` (Eq. 8.16) over cells
    /// with `H_i + M_i > 0`.
    pub fn reflection<'a>(cells: impl IntoIterator<Item = &'a CellStats>) -> Option<Self> {
        Self::of(cells.into_iter().filter_map(|c| {
            let n = c.h() + c.m();
            (n > 0.0).then(|| c.h() / n)
        }))
    }

    /// Moments of the ML decay-rate map `λ_i = H_i / R_i` (Eq. 7.10) over cells with
    /// `R_i > 0`.
    pub fn decay_rate<'a>(cells: impl IntoIterator<Item = &'a CellStats>) -> Option<Self> {
        Self::of(cells.into_iter().filter_map(|c| {
            let r = c.path_length_m();
            (r > 0.0).then(|| c.h() / r)
        }))
    }
}

/// A Beta(α, β) prior of the reflection probability μ (Eq. 8.15).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BetaPrior {
    /// α > 0 (pseudo-hits).
    pub alpha: f64,
    /// β > 0 (pseudo-misses).
    pub beta: f64,
}

impl Default for BetaPrior {
    /// The uniform prior Beta(1, 1), whose posterior mode is Hähnel's ML map (Eq. 8.16).
    fn default() -> Self {
        Self {
            alpha: 1.0,
            beta: 1.0,
        }
    }
}

impl BetaPrior {
    /// A prior with α, β > 0 (finite).
    pub fn new(alpha: f64, beta: f64) -> Result<Self, SensorModelError> {
        if !(alpha.is_finite() && beta.is_finite() && alpha > 0.0 && beta > 0.0) {
            return Err(SensorModelError::InvalidParameter {
                name: "Beta prior",
                reason: format!("need finite alpha, beta > 0, got ({alpha}, {beta})"),
            });
        }
        Ok(Self { alpha, beta })
    }

    /// Method of moments (Sec. 8.5): `α = E (E(1−E)/V − 1)`, `β = (1−E)(E(1−E)/V − 1)`
    /// (the thesis's form `α = −E(E² − E + V)/V` rearranged). When the moments admit no
    /// Beta distribution (`V = 0`, `V ≥ E(1−E)`, `E ∈ {0, 1}`) the uniform prior is used.
    pub fn from_moments(moments: &MomentStatistics) -> Self {
        let (e, v) = (moments.mean, moments.variance);
        let common = e * (1.0 - e) / v - 1.0; // Sec. 8.5, rearranged
        let alpha = e * common;
        let beta = (1.0 - e) * common;
        Self::new(alpha, beta).unwrap_or_default()
    }

    /// Method of moments like [`from_moments`](Self::from_moments), but degenerate moments
    /// are clamped instead of replaced by the uniform prior: the mean `E` into
    /// `[1e-6, 1 − 1e-6]` (0.5 when not finite), the concentration `α + β = E(1−E)/V − 1` to
    /// at least `min_concentration` (also when `V` is 0 or not finite). So the prior keeps
    /// the data's mean and, for a (nearly) binary ML map, where the moments admit no Beta
    /// distribution, a weight of `min_concentration` pseudo-observations, negligible beside
    /// one count (the pole extractor's occupancy, Schaefer 2020, §12.4.1).
    pub fn from_moments_clamped(moments: &MomentStatistics, min_concentration: f64) -> Self {
        let floor = if min_concentration.is_finite() {
            min_concentration.max(f64::MIN_POSITIVE)
        } else {
            f64::MIN_POSITIVE
        };
        let e = if moments.mean.is_finite() {
            moments.mean.clamp(1e-6, 1.0 - 1e-6)
        } else {
            0.5
        };
        let common = e * (1.0 - e) / moments.variance - 1.0; // Sec. 8.5, rearranged
        let common = if common.is_finite() {
            common.max(floor)
        } else {
            floor
        };
        Self {
            alpha: e * common,
            beta: (1.0 - e) * common,
        }
    }

    /// Method of moments over the ML reflection map of `cells` (uniform prior when no cell
    /// was observed).
    pub fn estimate<'a>(cells: impl IntoIterator<Item = &'a CellStats>) -> Self {
        MomentStatistics::reflection(cells)
            .map(|m| Self::from_moments(&m))
            .unwrap_or_default()
    }

    /// Prior mean `α / (α + β)`.
    pub fn mean(&self) -> f64 {
        self.alpha / (self.alpha + self.beta)
    }
}

/// A Gamma(α, β) prior of the decay rate λ in shape–rate form: density
/// `β^α λ^{α−1} e^{−βλ} / Γ(α)`, mean `α/β` [1/m] (Eq. 8.17).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GammaPrior {
    /// Shape α > 0 (pseudo-hits).
    pub alpha: f64,
    /// Rate β > 0 in metres (pseudo path length).
    pub beta: f64,
}

impl Default for GammaPrior {
    /// Gamma(1, 1): an exponential prior with mean 1 /m (used only when no moments exist).
    fn default() -> Self {
        Self {
            alpha: 1.0,
            beta: 1.0,
        }
    }
}

impl GammaPrior {
    /// A prior with α, β > 0 (finite). β > 0 is required: with the "uninformative" β = 0 an
    /// unobserved cell blocks every ray (the closed-form likelihood of Sec. 8.4.5).
    pub fn new(alpha: f64, beta: f64) -> Result<Self, SensorModelError> {
        if !(alpha.is_finite() && beta.is_finite() && alpha > 0.0 && beta > 0.0) {
            return Err(SensorModelError::InvalidParameter {
                name: "Gamma prior",
                reason: format!("need finite alpha, beta > 0, got ({alpha}, {beta})"),
            });
        }
        Ok(Self { alpha, beta })
    }

    /// Method of moments (Sec. 8.5): `α = E²/V`, `β = E/V`. With `V = 0` or `E = 0` it
    /// falls back to Gamma(1, 1/E) (an exponential prior with the observed mean), or
    /// Gamma(1, 1) when `E = 0` too.
    pub fn from_moments(moments: &MomentStatistics) -> Self {
        let (e, v) = (moments.mean, moments.variance);
        Self::new(e * e / v, e / v) // Sec. 8.5
            .or_else(|_| Self::new(1.0, 1.0 / e))
            .unwrap_or_default()
    }

    /// Method of moments over the ML decay-rate map of `cells`.
    pub fn estimate<'a>(cells: impl IntoIterator<Item = &'a CellStats>) -> Self {
        MomentStatistics::decay_rate(cells)
            .map(|m| Self::from_moments(&m))
            .unwrap_or_default()
    }

    /// Prior mean `α / β` in 1/m.
    pub fn mean(&self) -> f64 {
        self.alpha / self.beta
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn beta_moments_round_trip() {
        // Beta(2, 5): mean 2/7, variance 10 / (49 · 8).
        let moments = MomentStatistics {
            cells: 10,
            mean: 2.0 / 7.0,
            variance: 10.0 / (49.0 * 8.0),
        };
        let prior = BetaPrior::from_moments(&moments);
        assert!((prior.alpha - 2.0).abs() < 1e-12 && (prior.beta - 5.0).abs() < 1e-12);
        // The thesis's own form of α and β gives the same numbers.
        let (e, v) = (moments.mean, moments.variance);
        let alpha = -e * (e * e - e + v) / v;
        let beta = (e - v + e * v - 2.0 * e * e + e * e * e) / v;
        assert!((prior.alpha - alpha).abs() < 1e-12 && (prior.beta - beta).abs() < 1e-12);
    }

    #[test]
    fn clamped_beta_moments_keep_the_mean_of_degenerate_data() {
        // Regular moments: the same prior as `from_moments`.
        let moments = MomentStatistics {
            cells: 10,
            mean: 0.25,
            variance: 12.0 / 576.0,
        };
        let prior = BetaPrior::from_moments_clamped(&moments, 1e-3);
        assert_eq!(prior, BetaPrior::from_moments(&moments));
        assert!((prior.alpha - 2.0).abs() < 1e-9 && (prior.beta - 6.0).abs() < 1e-9);
        // A binary map (V = E(1 − E)): the concentration is clamped, the mean kept.
        let binary = MomentStatistics::of([1.0, 0.0, 1.0, 0.0, 0.0]).unwrap();
        let prior = BetaPrior::from_moments_clamped(&binary, 1e-3);
        assert!((prior.alpha + prior.beta - 1e-3).abs() < 1e-15);
        assert!((prior.mean() - 0.4).abs() < 1e-12);
        // No data: mean 0.5 at the floor.
        let none = MomentStatistics {
            cells: 0,
            mean: f64::NAN,
            variance: f64::NAN,
        };
        let prior = BetaPrior::from_moments_clamped(&none, 1e-3);
        assert_eq!((prior.alpha, prior.beta), (5e-4, 5e-4));
    }

    #[test]
    fn gamma_moments_round_trip() {
        // Gamma(3, 2): mean 1.5, variance 0.75.
        let moments = MomentStatistics {
            cells: 10,
            mean: 1.5,
            variance: 0.75,
        };
        let prior = GammaPrior::from_moments(&moments);
        assert!((prior.alpha - 3.0).abs() < 1e-12 && (prior.beta - 2.0).abs() < 1e-12);
        let flat = MomentStatistics {
            cells: 3,
            mean: 0.5,
            variance: 0.0,
        };
        assert_eq!(
            GammaPrior::from_moments(&flat),
            GammaPrior::new(1.0, 2.0).unwrap()
        );
    }

    #[test]
    fn degenerate_moments_fall_back() {
        let all_hits = [CellStats::new(3, 0, 1.0), CellStats::new(1, 0, 0.5)];
        assert_eq!(BetaPrior::estimate(&all_hits), BetaPrior::default());
        assert_eq!(GammaPrior::estimate(&[]), GammaPrior::default());
        let m = MomentStatistics::of([1.0, 2.0, 3.0]).unwrap();
        assert!((m.mean - 2.0).abs() < 1e-15 && (m.variance - 2.0 / 3.0).abs() < 1e-15);
    }
}
