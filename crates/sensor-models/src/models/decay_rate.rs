//! The decay-rate model with maximum-likelihood maps (Schaefer 2020, ch. 7).

use serde::{Deserialize, Serialize};

use crate::dimension::{Crossing, Dimension, Planar, Spatial};
use crate::models::{SensorModel, finite_or_neg_inf, ln_one_minus_exp_neg};
use crate::stats::DenseStats;
use crate::{MomentStatistics, Reading, SensorModelError, SensorRange};

/// Configuration of [`DecayRateModel`].
///
/// Defaults (ours; the thesis gives no values):
/// * `min_rate_per_m = 1e-3` — floor of every cell's λ. A cell crossed but never hit has
///   the ML value λ = 0 (Eq. 7.10), so a ray ending there would get `ln 0 = −∞`; the floor
///   applies to the whole map (not only to the endpoint), so the model stays a proper
///   decay process and its probabilities still sum to one.
/// * `unknown_rate_per_m = None` — the rate of cells no ray crossed (`R_i = 0`) and of
///   space outside the grid ("a single prior for all points outside the region of
///   interest", Sec. 7.6); `None` takes the mean ML rate of the observed cells.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DecayRateConfig {
    /// Range limits of the sensor.
    pub range: SensorRange,
    /// Floor of λ in 1/m.
    pub min_rate_per_m: f64,
    /// λ of unobserved cells and of space outside the grid, in 1/m (`None`: mean of the
    /// observed ML rates).
    pub unknown_rate_per_m: Option<f64>,
}

impl Default for DecayRateConfig {
    fn default() -> Self {
        Self {
            range: SensorRange::default(),
            min_rate_per_m: 1e-3,
            unknown_rate_per_m: None,
        }
    }
}

impl DecayRateConfig {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), SensorModelError> {
        self.range.validate()?;
        if !(self.min_rate_per_m.is_finite() && self.min_rate_per_m > 0.0) {
            return Err(SensorModelError::InvalidParameter {
                name: "min_rate_per_m",
                reason: format!("must be positive and finite, got {}", self.min_rate_per_m),
            });
        }
        if let Some(rate) = self.unknown_rate_per_m
            && !(rate.is_finite() && rate > 0.0)
        {
            return Err(SensorModelError::InvalidParameter {
                name: "unknown_rate_per_m",
                reason: format!("must be positive and finite, got {rate}"),
            });
        }
        Ok(())
    }
}

/// The decay-rate model (Schaefer 2020, ch. 7) on an ML map.
///
/// Map: `λ_i = H_i / R_i` (Eq. 7.10), floored at `min_rate_per_m`; unobserved cells and
/// space outside the grid get the unknown rate. Ray likelihood (Eq. 7.13, log space):
///
/// ```text
/// ln p(r | s, m)   = ln λ_k − Σ_i λ_i d_i          (k: cell of the endpoint)
/// ln P(sup | s, m) = −Σ_{i ∈ I(r_max)} λ_i d_i      (Eq. 7.16)
/// ln P(sub | s, m) = ln(1 − exp(−Σ_{i ∈ I(r_min)} λ_i d_i))
/// ```
#[derive(Clone, Debug)]
pub struct DecayRateModel<D: Dimension> {
    grid: D::Grid,
    rates: Vec<f64>,
    unknown_rate: f64,
    config: DecayRateConfig,
}

/// The decay-rate model on a 2-D map.
pub type DecayRateModel2 = DecayRateModel<Planar>;
/// The decay-rate model on a 3-D map.
pub type DecayRateModel3 = DecayRateModel<Spatial>;

impl<D: Dimension> DecayRateModel<D> {
    /// The ML map of `stats` (Eq. 7.10) with the floors and unknown rate of `config`.
    pub fn new(stats: &DenseStats<D>, config: DecayRateConfig) -> Result<Self, SensorModelError> {
        config.validate()?;
        let unknown_rate = config
            .unknown_rate_per_m
            .or_else(|| MomentStatistics::decay_rate(stats.cells()).map(|m| m.mean))
            .unwrap_or(config.min_rate_per_m)
            .max(config.min_rate_per_m);
        let rates = stats
            .cells()
            .iter()
            .map(|cell| {
                let r = cell.path_length_m();
                if r > 0.0 {
                    (cell.h() / r).max(config.min_rate_per_m) // Eq. (7.10)
                } else {
                    unknown_rate
                }
            })
            .collect();
        Ok(Self {
            grid: *stats.grid(),
            rates,
            unknown_rate,
            config,
        })
    }

    /// The grid.
    pub fn grid(&self) -> &D::Grid {
        &self.grid
    }

    /// λ of every cell in 1/m (floored; unknown cells hold the unknown rate).
    pub fn rates(&self) -> &[f64] {
        &self.rates
    }

    /// λ of unobserved cells and of space outside the grid, in 1/m.
    pub fn unknown_rate_per_m(&self) -> f64 {
        self.unknown_rate
    }

    /// The configuration.
    pub fn config(&self) -> &DecayRateConfig {
        &self.config
    }

    /// The optical depth `Σ_i λ_i d_i` along `ray` from its origin to `length_m` metres,
    /// counting path outside the grid at the unknown rate.
    #[inline]
    pub fn optical_depth(&self, ray: &D::Ray, length_m: f64) -> f64 {
        let mut inside = 0.0;
        let mut depth = 0.0;
        D::traverse(&self.grid, ray, length_m).for_each(|c| {
            let d = c.length();
            inside += d;
            depth += self
                .rates
                .get(c.index())
                .copied()
                .unwrap_or(self.unknown_rate)
                * d;
        });
        depth + self.unknown_rate * (length_m - inside).max(0.0)
    }

    /// λ of the cell containing the point at `t_m` along the ray (unknown rate outside).
    #[inline]
    pub fn rate_at(&self, ray: &D::Ray, t_m: f64) -> f64 {
        D::cell_index_at(&self.grid, ray, t_m)
            .and_then(|k| self.rates.get(k).copied())
            .unwrap_or(self.unknown_rate)
    }
}

impl<D: Dimension> SensorModel<D> for DecayRateModel<D> {
    fn ray_log_likelihood(&self, ray_in_map: &D::Ray) -> f64 {
        let range = self.config.range;
        let value = match range.classify(D::range(ray_in_map)) {
            Reading::Hit(r) => {
                // Eq. (7.13): ln λ_k − Σ_i λ_i d_i
                self.rate_at(ray_in_map, r).ln() - self.optical_depth(ray_in_map, r)
            }
            Reading::Sup => -self.optical_depth(ray_in_map, range.max_range_m), // Eq. (7.16)
            Reading::Sub => ln_one_minus_exp_neg(self.optical_depth(ray_in_map, range.min_range_m)),
        };
        finite_or_neg_inf(value)
    }

    fn sensor_range(&self) -> SensorRange {
        self.config.range
    }
}
