//! The reflection model: ML maps (Hähnel et al. 2003) and full Beta posteriors (ch. 8).

use serde::{Deserialize, Serialize};

use crate::dimension::{Dimension, Planar, Spatial};
use crate::models::{BernoulliField, SensorModel};
use crate::stats::DenseStats;
use crate::{BetaPrior, MomentStatistics, SensorModelError, SensorRange};

/// Configuration of the ML reflection model ([`ReflectionModel::maximum_likelihood`]).
///
/// Defaults (the thesis gives no values; they mirror [`crate::DecayRateConfig`]):
/// * `min_probability = 1e-3`, `max_probability = 1 − 1e-3` — the ML value
///   `μ = H/(H+M)` is clamped to this interval: `μ = 0` would make a return in the cell
///   impossible and `μ = 1` would block every ray through it (`ln 0 = −∞`).
/// * `unknown_probability = None` — μ of cells no ray entered and of space outside the
///   grid; `None` takes the mean ML value of the observed cells.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReflectionConfig {
    /// Range limits of the sensor.
    pub range: SensorRange,
    /// Lower clamp of μ.
    pub min_probability: f64,
    /// Upper clamp of μ.
    pub max_probability: f64,
    /// μ of unobserved cells and outside the grid (`None`: mean of the observed ML values).
    pub unknown_probability: Option<f64>,
}

impl Default for ReflectionConfig {
    fn default() -> Self {
        Self {
            range: SensorRange::default(),
            min_probability: 1e-3,
            max_probability: 1.0 - 1e-3,
            unknown_probability: None,
        }
    }
}

impl ReflectionConfig {
    /// Checks `0 < min_probability ≤ max_probability < 1` and the unknown value.
    pub fn validate(&self) -> Result<(), SensorModelError> {
        self.range.validate()?;
        let (lo, hi) = (self.min_probability, self.max_probability);
        if !(lo > 0.0 && lo <= hi && hi < 1.0) {
            return Err(SensorModelError::InvalidParameter {
                name: "reflection probability clamps",
                reason: format!("need 0 < min <= max < 1, got [{lo}, {hi}]"),
            });
        }
        if let Some(p) = self.unknown_probability
            && !(p > 0.0 && p < 1.0)
        {
            return Err(SensorModelError::InvalidParameter {
                name: "unknown_probability",
                reason: format!("must lie in (0, 1), got {p}"),
            });
        }
        Ok(())
    }
}

/// Configuration of the posterior reflection model ([`ReflectionModel::posterior`]).
///
/// Default: the default [`SensorRange`] and `prior = None`, i.e. α, β by the method of
/// moments over the observed cells' ML values (Sec. 8.5, [`BetaPrior::estimate`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BetaPosteriorConfig {
    /// Range limits of the sensor.
    pub range: SensorRange,
    /// The Beta prior; `None` estimates it from the map.
    pub prior: Option<BetaPrior>,
}

/// The reflection model (Hähnel et al. 2003; Schaefer 2020, Sec. 7.5.2 and 8.4).
///
/// Two maps from the same counts:
/// * [`ReflectionModel::maximum_likelihood`]: `μ_i = H_i / (H_i + M_i)` (Eq. 7.22/8.16),
///   clamped;
/// * [`ReflectionModel::posterior`]: the full posterior `Beta(H_i + α, M_i + β)` (Eq. 8.15).
///   Its closed-form ray likelihood (Eq. 8.22) multiplies the per-cell factors
///   `l_ref(1) = (H_i + α) / (H_i + α + M_i + β)` and `l_ref(0) = 1 − l_ref(1)`: it is the
///   reflection model with `μ_i` replaced by the posterior mean, so both share one
///   implementation ([`BernoulliField`]), including the density conversion of Eq. 7.32.
#[derive(Clone, Debug)]
pub struct ReflectionModel<D: Dimension> {
    field: BernoulliField<D>,
    prior: Option<BetaPrior>,
}

/// The reflection model on a 2-D map.
pub type ReflectionModel2 = ReflectionModel<Planar>;
/// The reflection model on a 3-D map.
pub type ReflectionModel3 = ReflectionModel<Spatial>;

impl<D: Dimension> ReflectionModel<D> {
    /// The ML reflection map of `stats` (Eq. 7.22).
    pub fn maximum_likelihood(
        stats: &DenseStats<D>,
        config: ReflectionConfig,
    ) -> Result<Self, SensorModelError> {
        config.validate()?;
        let clamp = |mu: f64| mu.clamp(config.min_probability, config.max_probability);
        let unknown = clamp(
            config
                .unknown_probability
                .or_else(|| MomentStatistics::reflection(stats.cells()).map(|m| m.mean))
                .unwrap_or(0.5),
        );
        let probabilities = stats.cells().iter().map(|cell| {
            let n = cell.h() + cell.m();
            if n > 0.0 {
                clamp(cell.h() / n) // Eq. (7.22)
            } else {
                unknown
            }
        });
        Ok(Self {
            field: BernoulliField::from_probabilities(
                *stats.grid(),
                probabilities,
                unknown,
                config.range,
            ),
            prior: None,
        })
    }

    /// The full-posterior reflection map of `stats` (Eq. 8.15, 8.22).
    pub fn posterior(
        stats: &DenseStats<D>,
        config: BetaPosteriorConfig,
    ) -> Result<Self, SensorModelError> {
        config.range.validate()?;
        let prior = match config.prior {
            Some(prior) => BetaPrior::new(prior.alpha, prior.beta)?,
            None => BetaPrior::estimate(stats.cells()),
        };
        // Eq. (8.22), δ = 1: μ = (h + α) / (h + α + m + β), kept as the two weights so that
        // a method-of-moments prior with α + β ≪ 1 (moments at the edge of the Beta family)
        // cannot round μ to 1 and a crossed cell to ln 0.
        let weights = stats
            .cells()
            .iter()
            .map(|cell| (cell.h() + prior.alpha, cell.m() + prior.beta));
        Ok(Self {
            field: BernoulliField::from_weights(*stats.grid(), weights, prior.mean(), config.range),
            prior: Some(prior),
        })
    }

    /// The per-cell probabilities and the ray likelihood.
    pub fn field(&self) -> &BernoulliField<D> {
        &self.field
    }

    /// The grid.
    pub fn grid(&self) -> &D::Grid {
        self.field.grid()
    }

    /// The Beta prior of a posterior model (`None` for the ML model).
    pub fn prior(&self) -> Option<BetaPrior> {
        self.prior
    }
}

impl<D: Dimension> SensorModel<D> for ReflectionModel<D> {
    fn ray_log_likelihood(&self, ray_in_map: &D::Ray) -> f64 {
        self.field.ray_log_likelihood(ray_in_map)
    }

    fn sensor_range(&self) -> SensorRange {
        self.field.sensor_range()
    }
}
