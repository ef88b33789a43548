//! 2-D sensor models whose path integrals come from an [`OpticalDepthTable`].

use raypath_geometry::Ray2;

use crate::dimension::{Dimension, Planar};
use crate::models::bernoulli::MIN_CHORD_FRACTION;
use crate::models::{SensorModel, finite_or_neg_inf, ln_one_minus_exp_neg};
use crate::optical_depth::{OpticalDepthConfig, OpticalDepthTable};
use crate::{
    DecayRateModel2, DecayRatePosteriorModel2, LikelihoodFieldModel2, LogOddsModel2, Reading,
    ReflectionModel2, SensorModelError, SensorRange,
};

/// A 2-D model whose ray integrals are looked up in an [`OpticalDepthTable`] instead of
/// traversed: O(1) per ray, approximate (the exact model stays the reference; the crate
/// docs list the measured accuracy and speed).
///
/// * [`DecayRateModel2`]: the table holds `∫ λ`; `ln p = ln λ_k − Σ λ_i d_i` (Eq. 7.13) with
///   the sum from the table and `λ_k` from the map.
/// * [`DecayRatePosteriorModel2`] (full map posterior, Sec. 8.4.5): a cell crossed for `d`
///   metres has the miss exponent `a_i ln(1 + d / b_i)`, not linear in `d`, so it is no line
///   integral of a fixed field. The table counts every crossed cell as crossed for the mean
///   chord `d̄(θ) = c / (|cos θ| + |sin θ|)` of a line in direction θ (the inverse of the
///   reflection model's cells per metre), i.e. it integrates
///   `ρ_i(θ) = a_i ln(1 + d̄(θ) / b_i) / d̄(θ)` per metre ([`OpticalDepthTable::directional`]);
///   exact where `d ≪ b_i` (well-observed cells, where it is `a_i / b_i` per metre). The
///   endpoint cell is evaluated exactly: its share of the table sum is replaced by
///   `a_k ln(1 + r_k / b_k)` and `ln a_k − ln(b_k + r_k)` is added, `r_k` the in-cell length.
/// * [`ReflectionModel2`] (ML or posterior) and [`LogOddsModel2`]: the product
///   `Π (1 − μ_i)` over crossed cells is `exp(−Σ ρ_i)` with `ρ_i = −ln(1 − μ_i)`; the count
///   of cells is turned into a line integral by the mean number of cells a line in
///   direction θ crosses per metre, `(|cos θ| + |sin θ|) / c`. The endpoint cell's own
///   share is removed from the sum, and the density conversion (Eq. 7.32) uses the exact
///   chord of the endpoint cell.
/// * [`LikelihoodFieldModel2`]: the table holds `∫ q`, the per-ray normalizer.
///
/// The path outside the grid uses the model's outside value, as in the exact models.
#[derive(Clone, Debug)]
pub struct Tabulated<M> {
    model: M,
    table: OpticalDepthTable,
    /// Per-cell value used at the endpoint (`ln λ_k`, `[ln μ_k, ρ_k]` or the posterior's
    /// `[a_k, b_k]`).
    endpoint: Vec<[f64; 2]>,
    /// Integrand outside the grid, per metre.
    outside_rate: f64,
}

impl<M> Tabulated<M> {
    /// The exact model.
    pub fn model(&self) -> &M {
        &self.model
    }

    /// The table.
    pub fn table(&self) -> &OpticalDepthTable {
        &self.table
    }

    /// `∫ ρ` along the ray over `[from_m, to_m]`: the table inside the grid plus the outside
    /// rate times the length outside.
    #[inline]
    fn path_integral(&self, ray: &Ray2, from_m: f64, to_m: f64) -> f64 {
        let length = (to_m - from_m).max(0.0);
        match self.table.grid().bounds().clip_segment(
            &ray.origin,
            ray.direction.as_ref(),
            from_m,
            to_m,
        ) {
            Some((t0, t1)) if t1 > t0 => {
                self.table.integral(&ray.origin, &ray.direction, t0, t1)
                    + self.outside_rate * (length - (t1 - t0)).max(0.0)
            }
            _ => self.outside_rate * length,
        }
    }
}

impl Tabulated<DecayRateModel2> {
    /// Tabulates the decay rates of `model`.
    pub fn new(
        model: DecayRateModel2,
        config: OpticalDepthConfig,
    ) -> Result<Self, SensorModelError> {
        let table = OpticalDepthTable::new(model.grid(), model.rates(), |_| 1.0, config)?;
        let endpoint = model.rates().iter().map(|l| [l.ln(), 0.0]).collect();
        let outside_rate = model.unknown_rate_per_m();
        Ok(Self {
            model,
            table,
            endpoint,
            outside_rate,
        })
    }
}

impl SensorModel<Planar> for Tabulated<DecayRateModel2> {
    fn ray_log_likelihood(&self, ray_in_map: &Ray2) -> f64 {
        let range = self.model.config().range;
        let value = match range.classify(ray_in_map.range) {
            Reading::Hit(r) => {
                let ln_rate = Planar::cell_index_at(self.model.grid(), ray_in_map, r)
                    .and_then(|k| self.endpoint.get(k))
                    .map_or(self.outside_rate.ln(), |e| e[0]);
                ln_rate - self.path_integral(ray_in_map, 0.0, r) // Eq. (7.13)
            }
            Reading::Sup => -self.path_integral(ray_in_map, 0.0, range.max_range_m),
            Reading::Sub => {
                ln_one_minus_exp_neg(self.path_integral(ray_in_map, 0.0, range.min_range_m))
            }
        };
        finite_or_neg_inf(value)
    }

    fn sensor_range(&self) -> SensorRange {
        self.model.config().range
    }
}

/// The mean chord `c / (|cos θ| + |sin θ|)` of the cells a line of unit direction `(x, y)`
/// crosses (cell edge `c`).
#[inline]
fn mean_chord(c: f64, x: f64, y: f64) -> f64 {
    c / (x.abs() + y.abs())
}

impl Tabulated<DecayRatePosteriorModel2> {
    /// Tabulates the Gamma posterior's miss exponent per metre of mean chord (see the type
    /// docs).
    pub fn new(
        model: DecayRatePosteriorModel2,
        config: OpticalDepthConfig,
    ) -> Result<Self, SensorModelError> {
        let c = Planar::cell_size(model.grid());
        let params = model.params();
        let table = OpticalDepthTable::directional(
            model.grid(),
            |theta: f64| {
                let chord = mean_chord(c, theta.cos(), theta.sin());
                params
                    .iter()
                    .map(|[a, b]| a * (chord / b).ln_1p() / chord) // −ln l_dec(d̄, 0) / d̄, Sec. 8.4.5
                    .collect()
            },
            config,
        )?;
        let endpoint = params.to_vec();
        let outside_rate = model.outside_rate_per_m();
        Ok(Self {
            model,
            table,
            endpoint,
            outside_rate,
        })
    }
}

impl SensorModel<Planar> for Tabulated<DecayRatePosteriorModel2> {
    fn ray_log_likelihood(&self, ray_in_map: &Ray2) -> f64 {
        let range = self.model.config().range;
        let value = match range.classify(ray_in_map.range) {
            Reading::Hit(r) => self.posterior_hit(ray_in_map, r),
            Reading::Sup => -self.path_integral(ray_in_map, 0.0, range.max_range_m),
            Reading::Sub => {
                ln_one_minus_exp_neg(self.path_integral(ray_in_map, 0.0, range.min_range_m))
            }
        };
        finite_or_neg_inf(value)
    }

    fn sensor_range(&self) -> SensorRange {
        self.model.config().range
    }
}

impl Tabulated<DecayRatePosteriorModel2> {
    /// `ln L` of a return at `r`: the table's miss exponent with the endpoint cell's share
    /// replaced by the exact `ln l_dec(r_k, 1)` (Sec. 8.4.5).
    #[inline]
    fn posterior_hit(&self, ray: &Ray2, r: f64) -> f64 {
        let depth = self.path_integral(ray, 0.0, r);
        let grid = self.model.grid();
        let Some((k, [a, b])) =
            Planar::cell_index_at(grid, ray, r).and_then(|k| self.endpoint.get(k).map(|e| (k, e)))
        else {
            return self.outside_rate.ln() - depth;
        };
        let (t0, _) = Planar::chord(grid, ray, k);
        let r_k = (r - t0.max(0.0)).max(0.0);
        let chord = mean_chord(Planar::cell_size(grid), ray.direction.x, ray.direction.y);
        let own = a * (chord / b).ln_1p() / chord * r_k;
        // ln l_dec(r_k, 1) = −a_k ln(1 + r_k / b_k) + ln a_k − ln(b_k + r_k), Sec. 8.4.5
        -(depth - own).max(0.0) - a * (r_k / b).ln_1p() + a.ln() - (b + r_k).ln()
    }
}

/// The reflection-type models share the Bernoulli field.
macro_rules! tabulated_bernoulli {
    ($model:ty, $doc:literal) => {
        impl Tabulated<$model> {
            #[doc = $doc]
            pub fn new(
                model: $model,
                config: OpticalDepthConfig,
            ) -> Result<Self, SensorModelError> {
                let field = model.field();
                let c = Planar::cell_size(field.grid());
                let rho: Vec<f64> = field.log_probs().iter().map(|p| -p[1]).collect();
                let table = OpticalDepthTable::new(
                    field.grid(),
                    &rho,
                    |theta: f64| (theta.cos().abs() + theta.sin().abs()) / c,
                    config,
                )?;
                let endpoint = field.log_probs().iter().map(|p| [p[0], -p[1]]).collect();
                let outside_rate = -(-field.outside_probability()).ln_1p() / c;
                Ok(Self {
                    model,
                    table,
                    endpoint,
                    outside_rate,
                })
            }
        }

        impl SensorModel<Planar> for Tabulated<$model> {
            fn ray_log_likelihood(&self, ray_in_map: &Ray2) -> f64 {
                bernoulli_log_likelihood(self, self.model.field(), ray_in_map)
            }

            fn sensor_range(&self) -> SensorRange {
                self.model.field().sensor_range()
            }
        }
    };
}

tabulated_bernoulli!(
    ReflectionModel2,
    "Tabulates `ρ_i = −ln(1 − μ_i)` of a reflection model (ML or posterior)."
);
tabulated_bernoulli!(
    LogOddsModel2,
    "Tabulates `ρ_i = −ln(1 − p_i)` of an occupancy map."
);

/// The reflection-model ray likelihood with table sums.
#[inline]
fn bernoulli_log_likelihood<M>(
    tabulated: &Tabulated<M>,
    field: &crate::BernoulliField<Planar>,
    ray: &Ray2,
) -> f64 {
    let range = field.sensor_range();
    let grid = field.grid();
    let c = Planar::cell_size(grid);
    let value = match range.classify(ray.range) {
        Reading::Hit(r) => {
            let depth = tabulated.path_integral(ray, 0.0, r);
            match Planar::cell_index_at(grid, ray, r)
                .and_then(|k| tabulated.endpoint.get(k).map(|e| (k, e)))
            {
                Some((k, [ln_mu, rho])) => {
                    let (t0, t1) = Planar::chord(grid, ray, k);
                    // Remove the endpoint cell's own share of the table sum.
                    let theta_scale = (ray.direction.x.abs() + ray.direction.y.abs()) / c;
                    let own = rho * theta_scale * (r - t0.max(0.0)).max(0.0);
                    let chord = (t1.min(range.max_range_m) - t0.max(range.min_range_m))
                        .max(MIN_CHORD_FRACTION * c);
                    // Eq. (7.23) and (7.32)
                    ln_mu - chord.ln() - (depth - own).max(0.0)
                }
                None => {
                    let mu0 = field.outside_probability();
                    mu0.ln() - c.ln() - depth
                }
            }
        }
        Reading::Sup => -tabulated.path_integral(ray, 0.0, range.max_range_m),
        Reading::Sub => ln_one_minus_exp_neg(tabulated.path_integral(ray, 0.0, range.min_range_m)),
    };
    finite_or_neg_inf(value)
}

impl Tabulated<LikelihoodFieldModel2> {
    /// Tabulates the likelihood field `q` for the per-ray normalizer.
    pub fn new(
        model: LikelihoodFieldModel2,
        config: OpticalDepthConfig,
    ) -> Result<Self, SensorModelError> {
        let table = OpticalDepthTable::new(model.grid(), model.field(), |_| 1.0, config)?;
        let outside_rate = model.outside_value();
        Ok(Self {
            model,
            table,
            endpoint: Vec::new(),
            outside_rate,
        })
    }
}

impl SensorModel<Planar> for Tabulated<LikelihoodFieldModel2> {
    fn ray_log_likelihood(&self, ray_in_map: &Ray2) -> f64 {
        let config = self.model.config();
        let reading = config.range.classify(ray_in_map.range);
        match reading {
            Reading::Hit(r) => {
                let q = self.model.field_at(ray_in_map, r);
                let normalizer = config.normalize.then(|| {
                    self.path_integral(
                        ray_in_map,
                        config.range.min_range_m,
                        config.range.max_range_m,
                    )
                });
                self.model.log_likelihood_with(reading, q, normalizer)
            }
            _ => self.model.log_likelihood_with(reading, 0.0, None),
        }
    }

    fn sensor_range(&self) -> SensorRange {
        self.model.config().range
    }
}
