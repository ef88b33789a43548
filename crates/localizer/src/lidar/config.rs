//! Configuration shared by the lidar adapters.

use serde::{Deserialize, Serialize};

use crate::LocalizerError;

/// How a scan is turned into a particle weight (see the [module docs](super)).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LidarConfig {
    /// Use every `beam_step`-th beam or point (≥ 1; default 1 = all).
    pub beam_step: usize,
    /// The scan counts as this many independent beams: the summed log-likelihood of `J`
    /// kept beams is multiplied by γ = min(1, n / J). Default `Some(8.0)`; `None` keeps
    /// γ = 1 (the plain product of Eq. 7.15).
    pub effective_beams: Option<f64>,
    /// Weight ε ∈ [0, 1) of a random measurement mixed into every beam:
    /// `p̃(z_j) = (1 − ε) p(z_j | s, m) + ε / r_max` for a return (AMCL's `z_rand`, Thrun et
    /// al. 2005, §6.3; `sup` readings are not mixed, see the [module docs](super)).
    /// Default [`DEFAULT_RANDOM_WEIGHT`]; 0 gives the sensor model's own value.
    #[serde(default = "default_random_weight")]
    pub random_weight: f64,
}

/// The default of [`LidarConfig::random_weight`].
pub const DEFAULT_RANDOM_WEIGHT: f64 = 0.05;

fn default_random_weight() -> f64 {
    DEFAULT_RANDOM_WEIGHT
}

impl Default for LidarConfig {
    fn default() -> Self {
        Self {
            beam_step: 1,
            effective_beams: Some(8.0),
            random_weight: DEFAULT_RANDOM_WEIGHT,
        }
    }
}

impl LidarConfig {
    /// Checks `beam_step ≥ 1`, a positive finite `effective_beams` and `random_weight ∈ [0, 1)`.
    pub fn validate(&self) -> Result<(), LocalizerError> {
        if self.beam_step == 0 {
            return Err(LocalizerError::InvalidParameter {
                name: "beam_step",
                reason: "must be at least 1".to_owned(),
            });
        }
        if let Some(n) = self.effective_beams
            && !(n.is_finite() && n > 0.0)
        {
            return Err(LocalizerError::InvalidParameter {
                name: "effective_beams",
                reason: format!("must be positive and finite, got {n}"),
            });
        }
        if !(0.0..1.0).contains(&self.random_weight) {
            return Err(LocalizerError::InvalidParameter {
                name: "random_weight",
                reason: format!("must be in [0, 1), got {}", self.random_weight),
            });
        }
        Ok(())
    }

    /// The exponent γ for a scan with `beams` kept beams (1 for an empty scan).
    pub fn exponent(&self, beams: usize) -> f64 {
        match self.effective_beams {
            Some(n) if beams > 0 => (n / beams as f64).min(1.0),
            _ => 1.0,
        }
    }
}
