//! How rays become statistics: the mapping configuration and the summary of a build.

use serde::{Deserialize, Serialize};

use crate::{SensorModelError, SensorRange};

/// Configuration of map building (algorithm MAP-DECAY, Schaefer 2020, Sec. 7.4.2).
///
/// Defaults ([`MappingConfig::default`]): the default [`SensorRange`] (`r_min = 0`, `r_max = 80 m`)
/// and no-returns included (the thesis is silent on them: a `sup` ray is traced to `r_max` and adds
/// path length and misses, no hit; with it the closed-form ML map `λ_i = H_i / R_i` still maximizes
/// the likelihood of all rays, because `ln P(sup) = −Σ λ_i d_i` is linear in λ). `sub` readings
/// (returns below `r_min`) are always ignored in mapping: `ln P(sub) = ln(1 − e^{−Σ λ_i d_i})` has
/// no closed-form maximizer and is not a factorizing likelihood (ch. 8), so it admits no conjugate
/// update.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MappingConfig {
    /// Range limits; returns at or beyond `max_range_m` count as no-returns.
    pub range: SensorRange,
    /// Trace no-returns (and returns beyond `r_max`) to `r_max` as pure misses.
    pub include_no_returns: bool,
}

impl Default for MappingConfig {
    fn default() -> Self {
        Self {
            range: SensorRange::default(),
            include_no_returns: true,
        }
    }
}

impl MappingConfig {
    /// The default configuration with range limits `[min_range_m, max_range_m]`.
    pub fn with_range(min_range_m: f64, max_range_m: f64) -> Result<Self, SensorModelError> {
        Ok(Self {
            range: SensorRange::new(min_range_m, max_range_m)?,
            ..Self::default()
        })
    }

    /// Checks the range limits.
    pub fn validate(&self) -> Result<(), SensorModelError> {
        self.range.validate()
    }
}

/// Counts of what happened to the rays of a build (merged by addition).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct MappingSummary {
    /// Rays offered to the map.
    pub rays: u64,
    /// Returns whose endpoint cell (inside the grid) got a hit.
    pub hits: u64,
    /// Returns whose endpoint lies outside the grid (their in-grid cells got misses only).
    pub endpoints_outside: u64,
    /// No-returns (and returns beyond `r_max`) traced to `r_max`.
    pub no_returns_traced: u64,
    /// No-returns skipped because `include_no_returns` is off.
    pub no_returns_skipped: u64,
    /// `sub` readings (below `r_min`), ignored.
    pub sub_ignored: u64,
    /// Returns of zero length, or rays that never enter the grid: nothing to record.
    pub empty: u64,
    /// Total cell crossings recorded.
    pub crossings: u64,
}

impl MappingSummary {
    /// Adds another summary.
    pub fn merge(&mut self, other: &MappingSummary) {
        self.rays += other.rays;
        self.hits += other.hits;
        self.endpoints_outside += other.endpoints_outside;
        self.no_returns_traced += other.no_returns_traced;
        self.no_returns_skipped += other.no_returns_skipped;
        self.sub_ignored += other.sub_ignored;
        self.empty += other.empty;
        self.crossings += other.crossings;
    }
}
