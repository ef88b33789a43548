//! The per-beam random-measurement mixture (AMCL's `z_rand`, Thrun et al. 2005, §6.3):
//! `p̃(z_j) = (1 − ε) p(z_j | s, m) + ε q(z_j)`, evaluated in log space.

use raypath_sensor_models::{Dimension, Reading, ScanLikelihood, SensorModel, SensorRange};

use super::LidarConfig;
use crate::LocalizerError;

/// The scan likelihood of a lidar adapter ([`Scan2Measurement`](super::Scan2Measurement),
/// [`Scan3Measurement`](super::Scan3Measurement)): `model` under the random-measurement
/// mixture of weight `config.random_weight`, every prepared ray used. Fails when `config`
/// is invalid or, after that, when the sensor mounting is not finite (`mount_is_finite`;
/// `mount` names the parameter in the error).
pub(super) fn adapter_likelihood<D: Dimension, M: SensorModel<D>>(
    model: M,
    config: &LidarConfig,
    mount_is_finite: bool,
    mount: &'static str,
) -> Result<ScanLikelihood<RandomMixture<M>>, LocalizerError> {
    config.validate()?;
    if !mount_is_finite {
        return Err(LocalizerError::InvalidParameter {
            name: mount,
            reason: "must be finite".to_owned(),
        });
    }
    let range = model.sensor_range();
    Ok(ScanLikelihood::new(RandomMixture::new(
        model,
        range,
        config.random_weight,
    )))
}

/// `ln((1 − ε) e^{ln_p} + ε q)` given `ln_one_minus_eps = ln(1 − ε)` and `ln_eps_q = ln(ε q)`;
/// never NaN (a NaN `ln_p` counts as `−∞`).
#[inline]
pub(super) fn log_mix(ln_p: f64, ln_one_minus_eps: f64, ln_eps_q: f64) -> f64 {
    let a = if ln_p.is_nan() {
        f64::NEG_INFINITY
    } else {
        ln_p + ln_one_minus_eps
    };
    let b = ln_eps_q;
    let (hi, lo) = if a >= b { (a, b) } else { (b, a) };
    if hi == f64::NEG_INFINITY {
        f64::NEG_INFINITY
    } else if hi == f64::INFINITY {
        f64::INFINITY
    } else {
        hi + (lo - hi).exp().ln_1p()
    }
}

/// A sensor model with the random-measurement mixture applied to every ray.
///
/// The random component `q` is a proper distribution on the thesis's measurement space
/// `{sub} ∪ [r_min, r_max) ∪ {sup}` (Eq. 7.14): a reading unrelated to the map is a no-return
/// or a return uniform on `[0, r_max)` with equal probability, so `q(sup) = 1/2`,
/// `q(r) = 1 / (2 r_max)` and `q(sub) = r_min / (2 r_max)`. With `ε = 0` every ray's value
/// is the model's own.
#[derive(Clone, Debug)]
pub(super) struct RandomMixture<M> {
    model: M,
    range: SensorRange,
    ln_one_minus_eps: f64,
    ln_eps_hit: f64,
    ln_eps_sub: f64,
    ln_eps_sup: f64,
    enabled: bool,
}

impl<M> RandomMixture<M> {
    /// Wraps `model` with weight `eps ∈ [0, 1)` of the random component; `range` are the
    /// model's limits.
    pub(super) fn new(model: M, range: SensorRange, eps: f64) -> Self {
        let r_max = range.max_range_m;
        let r_min = range.min_range_m.max(0.0);
        Self {
            model,
            range,
            ln_one_minus_eps: (-eps).ln_1p(),
            ln_eps_hit: eps.ln() - (2.0 * r_max).ln(),
            ln_eps_sub: eps.ln() + (r_min / (2.0 * r_max)).ln(),
            ln_eps_sup: eps.ln() - std::f64::consts::LN_2,
            enabled: eps > 0.0,
        }
    }

    /// The wrapped model.
    pub(super) fn inner(&self) -> &M {
        &self.model
    }
}

impl<D: Dimension, M: SensorModel<D>> SensorModel<D> for RandomMixture<M> {
    #[inline]
    fn ray_log_likelihood(&self, ray_in_map: &D::Ray) -> f64 {
        let ln_p = self.model.ray_log_likelihood(ray_in_map);
        if !self.enabled {
            return ln_p;
        }
        let ln_eps_q = match self.range.classify(D::range(ray_in_map)) {
            Reading::Hit(_) => self.ln_eps_hit,
            Reading::Sub => self.ln_eps_sub,
            Reading::Sup => self.ln_eps_sup,
        };
        log_mix(ln_p, self.ln_one_minus_eps, ln_eps_q)
    }

    fn sensor_range(&self) -> SensorRange {
        self.model.sensor_range()
    }
}
