//! Choosing and building a 2-D sensor model at run time (the CLI's `--model`, the
//! evaluation's model list).

use std::fmt;
use std::str::FromStr;

use raypath_sensor_models::{
    BetaPosteriorConfig, DecayRateConfig, DecayRateModel2, DecayRatePosteriorModel2, DenseStats2,
    GammaPosteriorConfig, LikelihoodFieldConfig, LikelihoodFieldModel2, LogOddsConfig,
    LogOddsModel2, OpticalDepthConfig, Planar, ReflectionConfig, ReflectionModel2, SensorModel,
    SensorModelError, SensorRange, Tabulated,
};
use serde::{Deserialize, Serialize};

use crate::LocalizerError;

/// A boxed 2-D sensor model (run-time choice; one virtual call per ray).
pub type BoxedPlanarModel = Box<dyn SensorModel<Planar> + Send + Sync>;

/// The sensor models the localizer can build from a statistics map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ModelKind {
    /// Decay-rate model (Schaefer 2020, Sec. 7.4), λ = H / R; with `posterior` the Gamma
    /// full map posterior (Sec. 8.4).
    DecayRate,
    /// Reflection model (Sec. 7.5.2), μ = H / (H + M); with `posterior` the Beta posterior.
    Reflection,
    /// Endpoint model: the likelihood field normalized per ray to a density (Sec. 7.6.2).
    Endpoint,
    /// AMCL's likelihood field, unnormalized (`ln q(endpoint)`).
    LikelihoodField,
    /// Log-odds occupancy (OctoMap defaults) used as a reflection-type model.
    LogOdds,
}

impl ModelKind {
    /// Every kind, in table order.
    pub const ALL: [ModelKind; 5] = [
        ModelKind::DecayRate,
        ModelKind::Reflection,
        ModelKind::Endpoint,
        ModelKind::LikelihoodField,
        ModelKind::LogOdds,
    ];

    /// The name used on command lines and in tables (`decay-rate`, …).
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::DecayRate => "decay-rate",
            ModelKind::Reflection => "reflection",
            ModelKind::Endpoint => "endpoint",
            ModelKind::LikelihoodField => "likelihood-field",
            ModelKind::LogOdds => "log-odds",
        }
    }
}

impl fmt::Display for ModelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ModelKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        ModelKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = ModelKind::ALL.iter().map(|k| k.name()).collect();
                format!("unknown model {s:?}; choose one of {}", names.join(", "))
            })
    }
}

/// Which model to build and how.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelSpec {
    /// The model.
    pub kind: ModelKind,
    /// The full-map-posterior variant (FMP, Schaefer 2020, Sec. 8.4.4–8.4.5; decay-rate and
    /// reflection only; ignored otherwise): the closed-form likelihood `L(z, x)` with the
    /// map integrated out under the Gamma (decay-rate) or Beta (reflection) posterior, the
    /// prior's α, β estimated from the map by the method of moments (Sec. 8.5,
    /// [`raypath_sensor_models::GammaPrior::estimate`],
    /// [`raypath_sensor_models::BetaPrior::estimate`]). The MLM and FMP variants of a model
    /// are built from the same statistics and differ only in the weighting.
    pub posterior: bool,
    /// Look path integrals up in an optical-depth table instead of traversing the grid
    /// (O(1) per ray, approximate; for the decay-rate posterior every crossed cell counts
    /// as crossed for the mean chord of its direction, see
    /// [`raypath_sensor_models::Tabulated`]; the unnormalized likelihood field needs no
    /// path integral and stays exact).
    pub tabulated: Option<OpticalDepthConfig>,
}

impl ModelSpec {
    /// The exact (traversing) model of `kind`, maximum likelihood (MLM).
    pub fn exact(kind: ModelKind) -> Self {
        Self {
            kind,
            posterior: false,
            tabulated: None,
        }
    }

    /// The tabulated model of `kind` with the default table, maximum likelihood (MLM).
    pub fn tabulated(kind: ModelKind) -> Self {
        Self {
            kind,
            posterior: false,
            tabulated: Some(OpticalDepthConfig::default()),
        }
    }

    /// A short label (`decay-rate`, `reflection (FMP)`, `decay-rate [table]`, …).
    pub fn label(&self) -> String {
        let mut label = self.kind.name().to_owned();
        if self.posterior && matches!(self.kind, ModelKind::DecayRate | ModelKind::Reflection) {
            label.push_str(" (FMP)");
        }
        if self.tabulated.is_some() && self.uses_table() {
            label.push_str(" [table]");
        }
        label
    }

    fn uses_table(&self) -> bool {
        self.kind != ModelKind::LikelihoodField
    }

    /// Builds the model on `stats` with range limits `range`.
    pub fn build(
        &self,
        stats: &DenseStats2,
        range: SensorRange,
    ) -> Result<BoxedPlanarModel, LocalizerError> {
        self.build_inner(stats, range)
            .map_err(|e| LocalizerError::InvalidParameter {
                name: "map",
                reason: e.to_string(),
            })
    }

    fn build_inner(
        &self,
        stats: &DenseStats2,
        range: SensorRange,
    ) -> Result<BoxedPlanarModel, SensorModelError> {
        let table = self.tabulated;
        Ok(match (self.kind, self.posterior) {
            (ModelKind::DecayRate, false) => {
                let model = DecayRateModel2::new(
                    stats,
                    DecayRateConfig {
                        range,
                        ..DecayRateConfig::default()
                    },
                )?;
                match table {
                    Some(config) => Box::new(Tabulated::<DecayRateModel2>::new(model, config)?),
                    None => Box::new(model),
                }
            }
            (ModelKind::DecayRate, true) => {
                // Sec. 8.4.5, prior by the method of moments (Sec. 8.5).
                let model = DecayRatePosteriorModel2::new(
                    stats,
                    GammaPosteriorConfig { range, prior: None },
                )?;
                match table {
                    Some(config) => {
                        Box::new(Tabulated::<DecayRatePosteriorModel2>::new(model, config)?)
                    }
                    None => Box::new(model),
                }
            }
            (ModelKind::Reflection, posterior) => {
                let model = if posterior {
                    ReflectionModel2::posterior(stats, BetaPosteriorConfig { range, prior: None })?
                } else {
                    ReflectionModel2::maximum_likelihood(
                        stats,
                        ReflectionConfig {
                            range,
                            ..ReflectionConfig::default()
                        },
                    )?
                };
                match table {
                    Some(config) => Box::new(Tabulated::<ReflectionModel2>::new(model, config)?),
                    None => Box::new(model),
                }
            }
            (ModelKind::Endpoint | ModelKind::LikelihoodField, _) => {
                let normalize = self.kind == ModelKind::Endpoint;
                let model = LikelihoodFieldModel2::new(
                    stats,
                    LikelihoodFieldConfig {
                        range,
                        normalize,
                        ..LikelihoodFieldConfig::default()
                    },
                )?;
                match table {
                    Some(config) if normalize => {
                        Box::new(Tabulated::<LikelihoodFieldModel2>::new(model, config)?)
                    }
                    _ => Box::new(model),
                }
            }
            (ModelKind::LogOdds, _) => {
                let model = LogOddsModel2::new(
                    stats,
                    LogOddsConfig {
                        range,
                        ..LogOddsConfig::default()
                    },
                )?;
                match table {
                    Some(config) => Box::new(Tabulated::<LogOddsModel2>::new(model, config)?),
                    None => Box::new(model),
                }
            }
        })
    }
}
