//! The decay-rate model with full map posteriors: Gamma(H + α, R + β) per cell
//! (Schaefer 2020, ch. 8).

use serde::{Deserialize, Serialize};

use crate::dimension::{Crossing, Dimension, Planar, Spatial};
use crate::models::{SensorModel, finite_or_neg_inf, ln_one_minus_exp_neg};
use crate::stats::DenseStats;
use crate::{GammaPrior, Reading, SensorModelError, SensorRange};

/// Configuration of [`DecayRatePosteriorModel`].
///
/// Default: the default [`SensorRange`] and `prior = None`, i.e. α, β by the method of
/// moments over the observed cells' ML rates (Sec. 8.5, [`GammaPrior::estimate`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GammaPosteriorConfig {
    /// Range limits of the sensor.
    pub range: SensorRange,
    /// The Gamma prior (shape α, rate β); `None` estimates it from the map.
    pub prior: Option<GammaPrior>,
}

/// The decay-rate model on the full map posterior (Schaefer 2020, Sec. 8.4.3–8.4.5).
///
/// Each cell's decay rate has the posterior `Gamma(a_i, b_i)` with `a_i = H_i + α`,
/// `b_i = R_i + β` (Eq. 8.17); the ray likelihood integrates the map out (Eq. 8.20–8.21).
/// Per cell crossed for `r_i` metres, in log space:
///
/// ```text
/// ln l_dec(r_i, 0) = a_i (ln b_i − ln(b_i + r_i))                  (miss)
/// ln l_dec(r_k, 1) = a_k (ln b_k − ln(b_k + r_k)) + ln a_k − ln(b_k + r_k)   (endpoint)
/// ```
///
/// and a ray's log-likelihood is the sum over its cells; `P(sup)` and `P(sub)` use the miss
/// factors up to `r_max` / `r_min` (Sec. 8.4.5). Unobserved cells use the prior
/// (`a = α`, `b = β`). Space outside the grid is a homogeneous medium with the rate
/// `κ₀ = (α / c) ln(1 + c/β)` (a cell of edge `c` crossed lengthwise has the prior miss
/// factor `e^{−κ₀ c}`), so probabilities there still sum to one.
#[derive(Clone, Debug)]
pub struct DecayRatePosteriorModel<D: Dimension> {
    grid: D::Grid,
    /// Per cell `(a_i, b_i)`.
    params: Vec<[f64; 2]>,
    prior: GammaPrior,
    outside_rate: f64,
    config: GammaPosteriorConfig,
}

/// The posterior decay-rate model on a 2-D map.
pub type DecayRatePosteriorModel2 = DecayRatePosteriorModel<Planar>;
/// The posterior decay-rate model on a 3-D map.
pub type DecayRatePosteriorModel3 = DecayRatePosteriorModel<Spatial>;

impl<D: Dimension> DecayRatePosteriorModel<D> {
    /// The posterior map of `stats` (Eq. 8.17).
    pub fn new(
        stats: &DenseStats<D>,
        config: GammaPosteriorConfig,
    ) -> Result<Self, SensorModelError> {
        config.range.validate()?;
        let prior = match config.prior {
            Some(prior) => GammaPrior::new(prior.alpha, prior.beta)?,
            None => GammaPrior::estimate(stats.cells()),
        };
        let params = stats
            .cells()
            .iter()
            .map(|cell| [cell.h() + prior.alpha, cell.path_length_m() + prior.beta]) // Eq. (8.17)
            .collect();
        let c = D::cell_size(stats.grid());
        Ok(Self {
            grid: *stats.grid(),
            params,
            prior,
            outside_rate: prior.alpha / c * (c / prior.beta).ln_1p(),
            config,
        })
    }

    /// The grid.
    pub fn grid(&self) -> &D::Grid {
        &self.grid
    }

    /// The prior in use.
    pub fn prior(&self) -> GammaPrior {
        self.prior
    }

    /// Posterior parameters `(a_i, b_i) = (H_i + α, R_i + β)` of every cell.
    pub fn params(&self) -> &[[f64; 2]] {
        &self.params
    }

    /// The configuration (`prior` as given; [`Self::prior`] is the prior in use).
    pub fn config(&self) -> &GammaPosteriorConfig {
        &self.config
    }

    /// The rate `κ₀ = (α / c) ln(1 + c/β)` in 1/m of the homogeneous medium outside the grid.
    pub fn outside_rate_per_m(&self) -> f64 {
        self.outside_rate
    }

    /// Posterior mean decay rate `a_i / b_i` of cell `index` in 1/m.
    pub fn mean_rate(&self, index: usize) -> f64 {
        self.params
            .get(index)
            .map_or(self.prior.mean(), |[a, b]| a / b)
    }

    /// Sum of the log miss factors along the ray up to `length_m`, and the endpoint's
    /// cell parameters and in-cell length when the point at `length_m` lies in the grid.
    #[inline]
    fn trace(&self, ray: &D::Ray, length_m: f64) -> (f64, f64, Option<usize>) {
        let mut inside = 0.0;
        let mut log_miss = 0.0;
        let mut last_length = 0.0;
        D::traverse(&self.grid, ray, length_m).for_each(|c| {
            let d = c.length();
            inside += d;
            last_length = d;
            if let Some([a, b]) = self.params.get(c.index()) {
                log_miss -= a * (d / b).ln_1p(); // ln l_dec(r_i, 0), Sec. 8.4.5
            }
        });
        log_miss -= self.outside_rate * (length_m - inside).max(0.0);
        (
            log_miss,
            last_length,
            D::cell_index_at(&self.grid, ray, length_m),
        )
    }
}

impl<D: Dimension> SensorModel<D> for DecayRatePosteriorModel<D> {
    fn ray_log_likelihood(&self, ray_in_map: &D::Ray) -> f64 {
        let range = self.config.range;
        let value = match range.classify(D::range(ray_in_map)) {
            Reading::Hit(r) => {
                let (log_miss, r_k, endpoint) = self.trace(ray_in_map, r);
                match endpoint.and_then(|k| self.params.get(k)) {
                    // ln l_dec(r_k, 1) adds ln a_k − ln(b_k + r_k) to the miss factors.
                    Some([a, b]) => log_miss + a.ln() - (b + r_k).ln(),
                    None => log_miss + self.outside_rate.ln(),
                }
            }
            Reading::Sup => self.trace(ray_in_map, range.max_range_m).0,
            Reading::Sub => ln_one_minus_exp_neg(-self.trace(ray_in_map, range.min_range_m).0),
        };
        finite_or_neg_inf(value)
    }

    fn sensor_range(&self) -> SensorRange {
        self.config.range
    }
}
