//! The model variants that are scored, all built from one set of statistics.

use crate::dimension::Dimension;
use crate::models::SensorModel;
use crate::stats::DenseStats;
use crate::{
    BetaPosteriorConfig, DecayRateConfig, DecayRateModel, DecayRatePosteriorModel,
    GammaPosteriorConfig, LikelihoodFieldConfig, LikelihoodFieldModel, LogOddsConfig, LogOddsModel,
    ReflectionConfig, ReflectionModel, SensorModelError, SensorRange,
};

/// The model names of the scoring rows, in row order (the `raypath score-model` contract).
pub const MODEL_NAMES: [&str; 5] = [
    "decay-rate",
    "reflection",
    "endpoint",
    "likelihood-field",
    "log-odds",
];

/// One scored model: its row name, whether it is the full-posterior version, and the model.
pub(crate) struct Variant<D: Dimension> {
    pub name: &'static str,
    pub posterior: bool,
    pub model: Box<dyn SensorModel<D>>,
}

/// Every row of Table 7.3 / 8.2 / 8.3, built from `stats`:
///
/// | row | map | ray likelihood |
/// |---|---|---|
/// | `decay-rate`, ML | `λ_i = H_i/R_i` (Eq. 7.10) | Eq. 7.13 |
/// | `decay-rate`, posterior | `Gamma(H_i+α, R_i+β)` (Eq. 8.17) | Eq. 8.21 |
/// | `reflection`, ML | `μ_i = H_i/(H_i+M_i)` (Eq. 7.22) | Eq. 7.23 → density by Eq. 7.32 |
/// | `reflection`, posterior | `Beta(H_i+α, M_i+β)` (Eq. 8.15) | Eq. 8.22 → Eq. 7.32 |
/// | `endpoint` | Gaussian field of the distance to the nearest hit cell | per-ray normalized to `1 − P` (Sec. 7.6.2) |
/// | `likelihood-field` | AMCL mixture `z_hit 0.5, z_rand 0.5, σ 0.2 m` | per-ray normalized |
/// | `log-odds` | OctoMap occupancy (0.7 / 0.4, clamps 0.12 / 0.97) | Bernoulli field → Eq. 7.32 |
///
/// The **endpoint** model of the thesis is "a likelihood field from the distance to the
/// nearest mapped reflection" with an absolute probability `P` for out-of-range readings:
/// [`LikelihoodFieldModel`] with `z_hit = 1`, `z_rand = 0` (a pure Gaussian field,
/// `σ = endpoint_sigma`, distances clamped at `max(10σ, 2 m)` so the field's floor is
/// `e^{−50}`), `P = 0.05`, normalized per ray. The likelihood-field row is the
/// same model with AMCL's defaults (the uniform `z_rand` term makes it robust to
/// unexplained returns).
pub(crate) fn build<D: Dimension>(
    stats: &DenseStats<D>,
    range: SensorRange,
    endpoint_sigma_m: f64,
) -> Result<Vec<Variant<D>>, SensorModelError> {
    let endpoint = LikelihoodFieldConfig {
        range,
        z_hit: 1.0,
        z_rand: 0.0,
        sigma_hit_m: endpoint_sigma_m,
        max_distance_m: (10.0 * endpoint_sigma_m).max(2.0),
        ..LikelihoodFieldConfig::default()
    };
    let variant = |name, posterior, model: Box<dyn SensorModel<D>>| Variant {
        name,
        posterior,
        model,
    };
    Ok(vec![
        variant(
            "decay-rate",
            false,
            Box::new(DecayRateModel::new(
                stats,
                DecayRateConfig {
                    range,
                    ..DecayRateConfig::default()
                },
            )?),
        ),
        variant(
            "decay-rate",
            true,
            Box::new(DecayRatePosteriorModel::new(
                stats,
                GammaPosteriorConfig { range, prior: None },
            )?),
        ),
        variant(
            "reflection",
            false,
            Box::new(ReflectionModel::maximum_likelihood(
                stats,
                ReflectionConfig {
                    range,
                    ..ReflectionConfig::default()
                },
            )?),
        ),
        variant(
            "reflection",
            true,
            Box::new(ReflectionModel::posterior(
                stats,
                BetaPosteriorConfig { range, prior: None },
            )?),
        ),
        variant(
            "endpoint",
            false,
            Box::new(LikelihoodFieldModel::new(stats, endpoint)?),
        ),
        variant(
            "likelihood-field",
            false,
            Box::new(LikelihoodFieldModel::new(
                stats,
                LikelihoodFieldConfig {
                    range,
                    ..LikelihoodFieldConfig::default()
                },
            )?),
        ),
        variant(
            "log-odds",
            false,
            Box::new(LogOddsModel::new(
                stats,
                LogOddsConfig {
                    range,
                    ..LogOddsConfig::default()
                },
            )?),
        ),
    ])
}
