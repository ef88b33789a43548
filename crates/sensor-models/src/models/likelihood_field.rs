//! The endpoint (likelihood-field) model as in AMCL, normalized per ray (Sec. 7.6.2).

use serde::{Deserialize, Serialize};

use crate::dimension::{Crossing, Dimension, Planar, Spatial};
use crate::edt::squared_distance_transform;
use crate::models::{SensorModel, finite_or_neg_inf};
use crate::stats::DenseStats;
use crate::{Reading, SensorModelError, SensorRange};

/// Configuration of [`LikelihoodFieldModel`]. Defaults are nav2 AMCL's
/// (`nav2_amcl/src/amcl_node.cpp`): `z_hit = 0.5`, `z_rand = 0.5`, `sigma_hit = 0.2 m`,
/// `laser_likelihood_max_dist = 2.0 m`, and `z_max = 0.05` as the out-of-range
/// probabilities; `normalize = true` turns the heuristic values into densities as
/// Sec. 7.6.2 of the thesis does.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LikelihoodFieldConfig {
    /// Range limits of the sensor (`z_rand` is spread over `max_range_m`).
    pub range: SensorRange,
    /// Weight of the Gaussian term.
    pub z_hit: f64,
    /// Weight of the uniform term `z_rand / r_max`.
    pub z_rand: f64,
    /// Standard deviation of the Gaussian in metres.
    pub sigma_hit_m: f64,
    /// Distances to the nearest hit are clamped to this value, in metres (also used for
    /// endpoints outside the grid and maps without hits).
    pub max_distance_m: f64,
    /// Absolute probability `P` of a no-return (`sup`).
    pub no_return_probability: f64,
    /// Absolute probability of a `sub` reading (used when `r_min > 0`).
    pub sub_probability: f64,
    /// Normalize per ray to a density (see [`LikelihoodFieldModel`]); `false` returns
    /// AMCL's raw value `ln q(endpoint)`.
    pub normalize: bool,
}

impl Default for LikelihoodFieldConfig {
    fn default() -> Self {
        Self {
            range: SensorRange::default(),
            z_hit: 0.5,
            z_rand: 0.5,
            sigma_hit_m: 0.2,
            max_distance_m: 2.0,
            no_return_probability: 0.05,
            sub_probability: 0.05,
            normalize: true,
        }
    }
}

impl LikelihoodFieldConfig {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), SensorModelError> {
        self.range.validate()?;
        let ok = self.z_hit >= 0.0
            && self.z_rand >= 0.0
            && self.z_hit + self.z_rand > 0.0
            && self.z_hit.is_finite()
            && self.z_rand.is_finite()
            && self.sigma_hit_m.is_finite()
            && self.sigma_hit_m > 0.0
            && self.max_distance_m.is_finite()
            && self.max_distance_m >= 0.0
            && self.no_return_probability > 0.0
            && self.sub_probability > 0.0
            && self.no_return_probability + self.sub_probability < 1.0;
        if !ok {
            return Err(SensorModelError::InvalidParameter {
                name: "likelihood-field parameters",
                reason: format!("{self:?}"),
            });
        }
        Ok(())
    }

    /// `q(d) = z_hit · exp(−d² / (2σ²)) + z_rand / r_max` for a distance `d` (clamped to
    /// `max_distance_m`), as in AMCL's likelihood-field model.
    pub fn field_value(&self, distance_m: f64) -> f64 {
        let d = distance_m.min(self.max_distance_m);
        self.z_hit * (-d * d / (2.0 * self.sigma_hit_m * self.sigma_hit_m)).exp()
            + self.z_rand / self.range.max_range_m
    }
}

/// The endpoint model (likelihood field; Thrun 2001, Probabilistic Robotics Table 6.3,
/// as implemented in AMCL).
///
/// **Field.** The distance from every cell centre to the nearest cell with a hit
/// (`H_i > 0`) by an exact Euclidean distance transform ([`crate::edt`]), precomputed into
/// `q_i = z_hit · exp(−d_i²/(2σ²)) + z_rand / r_max` (AMCL's form, without the Gaussian's
/// normalizing constant), so an endpoint costs one look-up.
///
/// **Density** (Sec. 7.6.2: the endpoint model "assumes an absolute probability P for
/// out-of-range measurements" and its in-range values are normalized per ray so that their
/// integral over the sensor range is `1 − P`):
///
/// ```text
/// p(r | s, m) = (1 − P_sup − P_sub) · q(x(r)) / ∫_{r_min}^{r_max} q(x(r')) dr'
/// P(sup) = P_sup,  P(sub) = P_sub
/// ```
///
/// (`P_sub` counts only when `r_min > 0`; with `r_min = 0` the in-range mass is `1 − P_sup`,
/// and a negative range, which no sensor reports, is still scored `ln P_sub`.)
///
/// `q` is piecewise constant on cells, so the integral is `Σ_i q_i d_i` over the cells the
/// ray's line crosses in `[r_min, r_max]` (exact traversal; outside the grid
/// `q = q(max_distance)`). For 2-D localization, [`crate::Tabulated`] replaces the traversal
/// by two look-ups in a cumulative table.
#[derive(Clone, Debug)]
pub struct LikelihoodFieldModel<D: Dimension> {
    grid: D::Grid,
    distances_m: Vec<f64>,
    field: Vec<f64>,
    outside_value: f64,
    config: LikelihoodFieldConfig,
}

/// The likelihood-field model on a 2-D map.
pub type LikelihoodFieldModel2 = LikelihoodFieldModel<Planar>;
/// The likelihood-field model on a 3-D map.
pub type LikelihoodFieldModel3 = LikelihoodFieldModel<Spatial>;

impl<D: Dimension> LikelihoodFieldModel<D> {
    /// The field of `stats`' hit cells.
    pub fn new(
        stats: &DenseStats<D>,
        config: LikelihoodFieldConfig,
    ) -> Result<Self, SensorModelError> {
        config.validate()?;
        let sites: Vec<bool> = stats.cells().iter().map(|c| c.hits() > 0).collect();
        let c = D::cell_size(stats.grid());
        let distances_m: Vec<f64> = squared_distance_transform(D::dims3(stats.grid()), &sites)
            .into_iter()
            .map(|d2| (d2.sqrt() * c).min(config.max_distance_m))
            .collect();
        let field = distances_m.iter().map(|&d| config.field_value(d)).collect();
        Ok(Self {
            grid: *stats.grid(),
            distances_m,
            field,
            outside_value: config.field_value(config.max_distance_m),
            config,
        })
    }

    /// The grid.
    pub fn grid(&self) -> &D::Grid {
        &self.grid
    }

    /// Distance of every cell to the nearest hit cell in metres, clamped to
    /// `max_distance_m`.
    pub fn distances_m(&self) -> &[f64] {
        &self.distances_m
    }

    /// The precomputed field `q_i` of every cell.
    pub fn field(&self) -> &[f64] {
        &self.field
    }

    /// `q` outside the grid.
    pub fn outside_value(&self) -> f64 {
        self.outside_value
    }

    /// The configuration.
    pub fn config(&self) -> &LikelihoodFieldConfig {
        &self.config
    }

    /// `q` at the point `t_m` along the ray (one look-up).
    #[inline]
    pub fn field_at(&self, ray: &D::Ray, t_m: f64) -> f64 {
        D::cell_index_at(&self.grid, ray, t_m)
            .and_then(|k| self.field.get(k).copied())
            .unwrap_or(self.outside_value)
    }

    /// `∫_{r_min}^{r_max} q(x(r)) dr` along the ray (exact traversal).
    pub fn normalizer(&self, ray: &D::Ray) -> f64 {
        let (lo, hi) = (self.config.range.min_range_m, self.config.range.max_range_m);
        let mut inside = 0.0;
        let mut integral = 0.0;
        D::traverse(&self.grid, ray, hi).for_each(|c| {
            let overlap = (c.t_exit().min(hi) - c.t_enter().max(lo)).max(0.0);
            inside += overlap;
            integral += self
                .field
                .get(c.index())
                .copied()
                .unwrap_or(self.outside_value)
                * overlap;
        });
        integral + self.outside_value * ((hi - lo) - inside).max(0.0)
    }

    /// The probability of `sub` readings: `sub_probability` when `r_min > 0`, else 0.
    fn sub_mass(&self) -> f64 {
        if self.config.range.min_range_m > 0.0 {
            self.config.sub_probability
        } else {
            0.0
        }
    }

    /// The log-likelihood given the normalizer (`None`: unnormalized AMCL value).
    #[inline]
    pub(crate) fn log_likelihood_with(
        &self,
        reading: Reading,
        q: f64,
        normalizer: Option<f64>,
    ) -> f64 {
        let config = &self.config;
        let value = match reading {
            Reading::Hit(_) => match normalizer {
                Some(z) => {
                    let mass = 1.0 - config.no_return_probability - self.sub_mass();
                    mass.ln() + q.ln() - z.ln()
                }
                None => q.ln(),
            },
            Reading::Sup => config.no_return_probability.ln(),
            Reading::Sub => config.sub_probability.ln(),
        };
        finite_or_neg_inf(value)
    }
}

impl<D: Dimension> SensorModel<D> for LikelihoodFieldModel<D> {
    fn ray_log_likelihood(&self, ray_in_map: &D::Ray) -> f64 {
        let reading = self.config.range.classify(D::range(ray_in_map));
        match reading {
            Reading::Hit(r) => {
                let q = self.field_at(ray_in_map, r);
                let normalizer = self.config.normalize.then(|| self.normalizer(ray_in_map));
                self.log_likelihood_with(reading, q, normalizer)
            }
            _ => self.log_likelihood_with(reading, 0.0, None),
        }
    }

    fn sensor_range(&self) -> SensorRange {
        self.config.range
    }
}
