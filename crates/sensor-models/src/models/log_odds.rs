//! Log-odds occupancy (OctoMap's update rule) as a baseline sensor model.

use serde::{Deserialize, Serialize};

use crate::dimension::{Dimension, Planar, Spatial};
use crate::models::{BernoulliField, SensorModel};
use crate::stats::{CellStats, DenseStats};
use crate::{SensorModelError, SensorRange};

/// Configuration of [`LogOddsModel`]: OctoMap's defaults (Hornung et al., Autonomous
/// Robots 2013; `OccupancyOcTreeBase`): hit 0.7 (log-odds +0.847), miss 0.4 (−0.405),
/// clamping 0.12 (−1.99) and 0.97 (+3.48) — OctoMap's exact clamps are 0.1192 / 0.971
/// (log-odds −2 / +3.5).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LogOddsConfig {
    /// Range limits of the sensor.
    pub range: SensorRange,
    /// Inverse-model probability of a hit update.
    pub hit_probability: f64,
    /// Inverse-model probability of a miss update.
    pub miss_probability: f64,
    /// Lower clamp of the occupancy probability.
    pub clamp_min_probability: f64,
    /// Upper clamp of the occupancy probability.
    pub clamp_max_probability: f64,
}

impl Default for LogOddsConfig {
    fn default() -> Self {
        Self {
            range: SensorRange::default(),
            hit_probability: 0.7,
            miss_probability: 0.4,
            clamp_min_probability: 0.12,
            clamp_max_probability: 0.97,
        }
    }
}

impl LogOddsConfig {
    /// Checks that all probabilities lie in `(0, 1)` and the clamps are ordered.
    pub fn validate(&self) -> Result<(), SensorModelError> {
        self.range.validate()?;
        let ps = [
            self.hit_probability,
            self.miss_probability,
            self.clamp_min_probability,
            self.clamp_max_probability,
        ];
        if !ps.iter().all(|p| *p > 0.0 && *p < 1.0)
            || self.clamp_min_probability > self.clamp_max_probability
        {
            return Err(SensorModelError::InvalidParameter {
                name: "log-odds probabilities",
                reason: format!("need all in (0, 1) and min clamp <= max clamp, got {ps:?}"),
            });
        }
        Ok(())
    }

    /// The occupancy probability of a cell: `L = H·logit(p_hit) + M·logit(p_miss)`,
    /// clamped to the clamping interval once (0.5 for unobserved cells).
    pub fn occupancy(&self, cell: &CellStats) -> f64 {
        if cell.hits() == 0 && cell.misses() == 0 {
            return 0.5;
        }
        let l = cell.h() * logit(self.hit_probability) + cell.m() * logit(self.miss_probability);
        let l = l.clamp(
            logit(self.clamp_min_probability),
            logit(self.clamp_max_probability),
        );
        1.0 / (1.0 + (-l).exp())
    }
}

fn logit(p: f64) -> f64 {
    (p / (1.0 - p)).ln()
}

/// Log-odds occupancy (Moravec & Elfes 1985; OctoMap's update) as a sensor model.
///
/// **Map.** From the counts: `L_i = clamp(H_i·logit(0.7) + M_i·logit(0.4))`,
/// `p_i = 1 / (1 + e^{−L_i})`. OctoMap clamps after every update, so its value depends on
/// the order of hits and misses; counts carry no order, so the clamp is applied once to the
/// sum (the same for a cell seen only hit or only missed; different for mixed cells, where
/// sequential clamping forgets old evidence). OctoMap also merges the rays of one scan per
/// cell (a cell hit and missed in one scan counts as hit); we count every ray.
///
/// **Ray likelihood.** An occupancy grid has no measurement model of its own. We use the
/// reflection-model form with `p_occ` in place of μ (Eq. 7.23 with the density conversion
/// Eq. 7.32), the way the thesis scores occupancy-style maps (GPOM and Hilbert maps in
/// ch. 9: "cumulate occupancy probabilities along rays"):
/// `ln p(r) = ln p_k + Σ_{i ∈ B(k)} ln(1 − p_i) − ln |chord_k|`. Unobserved cells and space
/// outside the grid have `p = 0.5`.
#[derive(Clone, Debug)]
pub struct LogOddsModel<D: Dimension> {
    field: BernoulliField<D>,
}

/// Log-odds occupancy on a 2-D map.
pub type LogOddsModel2 = LogOddsModel<Planar>;
/// Log-odds occupancy on a 3-D map.
pub type LogOddsModel3 = LogOddsModel<Spatial>;

impl<D: Dimension> LogOddsModel<D> {
    /// The occupancy map of `stats`.
    pub fn new(stats: &DenseStats<D>, config: LogOddsConfig) -> Result<Self, SensorModelError> {
        config.validate()?;
        let probabilities = stats.cells().iter().map(|cell| config.occupancy(cell));
        Ok(Self {
            field: BernoulliField::from_probabilities(
                *stats.grid(),
                probabilities,
                0.5,
                config.range,
            ),
        })
    }

    /// The per-cell occupancy probabilities and the ray likelihood.
    pub fn field(&self) -> &BernoulliField<D> {
        &self.field
    }

    /// The grid.
    pub fn grid(&self) -> &D::Grid {
        self.field.grid()
    }
}

impl<D: Dimension> SensorModel<D> for LogOddsModel<D> {
    fn ray_log_likelihood(&self, ray_in_map: &D::Ray) -> f64 {
        self.field.ray_log_likelihood(ray_in_map)
    }

    fn sensor_range(&self) -> SensorRange {
        self.field.sensor_range()
    }
}
