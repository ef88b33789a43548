//! Sensor models: per-ray log-likelihoods on a map, behind one trait.

pub(crate) mod bernoulli;
mod decay_rate;
mod decay_rate_posterior;
mod likelihood_field;
mod log_odds;
mod prior;
mod reflection;

pub use bernoulli::BernoulliField;
pub use decay_rate::{DecayRateConfig, DecayRateModel, DecayRateModel2, DecayRateModel3};
pub use decay_rate_posterior::{
    DecayRatePosteriorModel, DecayRatePosteriorModel2, DecayRatePosteriorModel3,
    GammaPosteriorConfig,
};
pub use likelihood_field::{
    LikelihoodFieldConfig, LikelihoodFieldModel, LikelihoodFieldModel2, LikelihoodFieldModel3,
};
pub use log_odds::{LogOddsConfig, LogOddsModel, LogOddsModel2, LogOddsModel3};
pub use prior::{BetaPrior, GammaPrior, MomentStatistics};
pub use reflection::{
    BetaPosteriorConfig, ReflectionConfig, ReflectionModel, ReflectionModel2, ReflectionModel3,
};

use crate::SensorRange;
use crate::dimension::Dimension;

/// A lidar sensor model: the log-likelihood of one ray's measurement given the map.
///
/// `ray_in_map` is a ray in the map frame (origin at the sensor, unit direction, and its
/// [`Range`](raypath_geometry::Range)); the model classifies it with its
/// [`SensorRange`] (Eq. 7.14) and returns, in natural-log space (Eq. 7.15):
///
/// * a return `r ∈ [r_min, r_max)`: the log **density** `ln p(r | s, m)` in `ln(1/m)`;
/// * a no-return (or a return at or beyond `r_max`): `ln P(sup | s, m)`;
/// * a return below `r_min`: `ln P(sub | s, m)`.
///
/// Densities of all models are comparable (the reflection-type models are converted with
/// Eq. 7.32, the likelihood field is normalized per ray, Sec. 7.6.2). The result may be
/// `−∞` (an impossible measurement) but is never NaN.
///
/// A scan's likelihood is the sum over its rays (rays independent given pose and map,
/// Eq. 7.15); [`crate::ScanLikelihood`] does that for a pose and a scan.
pub trait SensorModel<D: Dimension>: Sync {
    /// `ln p(z | s, m)` of one ray in the map frame (see the trait docs).
    fn ray_log_likelihood(&self, ray_in_map: &D::Ray) -> f64;

    /// The range limits the model classifies readings with.
    fn sensor_range(&self) -> SensorRange;
}

impl<D: Dimension, M: SensorModel<D> + ?Sized> SensorModel<D> for &M {
    fn ray_log_likelihood(&self, ray_in_map: &D::Ray) -> f64 {
        (**self).ray_log_likelihood(ray_in_map)
    }
    fn sensor_range(&self) -> SensorRange {
        (**self).sensor_range()
    }
}

/// `ln(1 − e^{−x})` for `x ≥ 0`, accurate for small and large `x` (Mächler 2012).
#[inline]
pub(crate) fn ln_one_minus_exp_neg(x: f64) -> f64 {
    if x.is_nan() || x <= 0.0 {
        f64::NEG_INFINITY
    } else if x < std::f64::consts::LN_2 {
        (-(-x).exp_m1()).ln()
    } else {
        (-(-x).exp()).ln_1p()
    }
}

/// Replaces NaN by `−∞` (the models' contract: never NaN).
#[inline]
pub(crate) fn finite_or_neg_inf(value: f64) -> f64 {
    if value.is_nan() {
        f64::NEG_INFINITY
    } else {
        value
    }
}
