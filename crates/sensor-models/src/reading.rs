//! What a ray measured, relative to the sensor's range limits (thesis Eq. 7.14).

use raypath_geometry::Range;
use serde::{Deserialize, Serialize};

use crate::SensorModelError;

/// The sensor's range limits `[r_min, r_max]` in metres (Schaefer 2020, Sec. 7.4.4).
///
/// The thesis does not state the limits it used; the defaults are `r_min = 0` (no `sub`
/// readings) and `r_max = 80 m` (the CARMEN logs' lasers report no-returns at 81.83 /
/// 81.91 m; an HDL-64E sees about 120 m, so 3-D callers usually set their own).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SensorRange {
    /// Minimum range `r_min` in metres; returns below it are `sub` readings.
    pub min_range_m: f64,
    /// Maximum range `r_max` in metres; no-returns are traced up to it, and returns at or
    /// beyond it count as no-returns (`sup`).
    pub max_range_m: f64,
}

impl Default for SensorRange {
    fn default() -> Self {
        Self {
            min_range_m: 0.0,
            max_range_m: 80.0,
        }
    }
}

impl SensorRange {
    /// Limits `[min_range_m, max_range_m]`, checked.
    pub fn new(min_range_m: f64, max_range_m: f64) -> Result<Self, SensorModelError> {
        let range = Self {
            min_range_m,
            max_range_m,
        };
        range.validate()?;
        Ok(range)
    }

    /// Checks `0 ≤ r_min < r_max < ∞`.
    pub fn validate(&self) -> Result<(), SensorModelError> {
        if !(self.min_range_m.is_finite()
            && self.max_range_m.is_finite()
            && self.min_range_m >= 0.0
            && self.min_range_m < self.max_range_m)
        {
            return Err(SensorModelError::InvalidParameter {
                name: "sensor range",
                reason: format!(
                    "need 0 <= min_range_m < max_range_m < inf, got [{}, {}]",
                    self.min_range_m, self.max_range_m
                ),
            });
        }
        Ok(())
    }

    /// Classifies a ray's [`Range`] (Eq. 7.14): a return below `r_min` is [`Reading::Sub`]
    /// (so is a negative one), a return at or beyond `r_max`, a NaN range and a no-return are
    /// [`Reading::Sup`], anything else is [`Reading::Hit`].
    #[inline]
    pub fn classify(&self, range: Range) -> Reading {
        match range {
            Range::Hit(r) if r.is_nan() => Reading::Sup,
            Range::Hit(r) if r < self.min_range_m || r < 0.0 => Reading::Sub,
            Range::Hit(r) if r >= self.max_range_m => Reading::Sup,
            Range::Hit(r) => Reading::Hit(r),
            Range::NoReturn => Reading::Sup,
        }
    }
}

/// A measurement in the thesis's mixed space `{sub, sup} ∪ [r_min, r_max]` (Eq. 7.14).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reading {
    /// A reflection below the minimum range (`sub`).
    Sub,
    /// A reflection at this range in metres, `r_min ≤ r < r_max`.
    Hit(f64),
    /// No reflection within the maximum range (`sup`, ch. 9's `super`).
    Sup,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classification() {
        let range = SensorRange::new(0.5, 10.0).unwrap();
        assert_eq!(range.classify(Range::Hit(0.2)), Reading::Sub);
        assert_eq!(range.classify(Range::Hit(-1.0)), Reading::Sub);
        assert_eq!(range.classify(Range::Hit(0.5)), Reading::Hit(0.5));
        assert_eq!(range.classify(Range::Hit(10.0)), Reading::Sup);
        assert_eq!(range.classify(Range::Hit(f64::NAN)), Reading::Sup);
        assert_eq!(range.classify(Range::Hit(f64::INFINITY)), Reading::Sup);
        assert_eq!(range.classify(Range::NoReturn), Reading::Sup);
        assert!(SensorRange::new(1.0, 1.0).is_err());
        assert!(SensorRange::new(-1.0, 1.0).is_err());
        assert!(SensorRange::new(0.0, f64::INFINITY).is_err());
    }
}
