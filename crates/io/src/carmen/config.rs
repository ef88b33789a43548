//! Reader options: beam-angle convention of old-format scans, no-return threshold, overrides.

use std::f64::consts::PI;
use std::path::Path;

use crate::error::{Error, Location, Result};

/// How the `n` beams of an old-format scan (`FLASER`/`RLASER`, whose lines carry no angles)
/// are spread over the field of view `fov` (π unless a `PARAM` or the configuration says
/// otherwise). Angles are counter-clockwise (REP-103), so beam 0 points to the robot's right.
///
/// | convention | increment | first beam | last beam |
/// |---|---|---|---|
/// | [`Closed`](FanConvention::Closed) | fov/(n−1) | −fov/2 | +fov/2 |
/// | [`HalfOpen`](FanConvention::HalfOpen) | fov/n | −fov/2 | +fov/2 − fov/n |
/// | [`Centered`](FanConvention::Centered) | fov/n | −fov/2 + fov/(2n) | +fov/2 − fov/(2n) |
/// | [`Auto`](FanConvention::Auto) (default) | `Closed` for odd n, `HalfOpen` for even n | −fov/2 | |
///
/// When the resolution is known (a `PARAM laser_front_laser_resolution` line or
/// [`CarmenConfig::angle_increment_rad`]) it is the increment, and the first beam is placed
/// by the same rule (−inc·(n−1)/2 for `Closed` and `Centered`, −inc·n/2 for `HalfOpen`).
///
/// **The default was measured**, not assumed: `cargo xtask eval carmen-angles` renders every
/// corrected Radish log with its reference poses under each convention and counts the
/// occupied 5 cm cells (report: `docs/results/carmen-angles.md`). The 180- and 360-beam
/// logs (aces, fhw, freiburg-079/-101/-campus, infinite-corridor, intel) are crisper with
/// `HalfOpen` (1° or 0.5° steps from −90°, the last beam at +89° or +89.5°): the runner-up
/// needs 0.3–10.5 % more cells (intel: 26 488 cells half-open, 28 041 centered, 28 735
/// closed, 99 389 mirrored). The 181- and 361-beam logs (acapulco, belgioioso, csail) are
/// crisper with `Closed` (the same 1° or 0.5° steps, ending at +90°; runner-up +0.7–3 %).
/// Both are "beam `i` at −90° + i·180°/(n − n mod 2)", which is what `Auto` does; moving the
/// first or the last beam by half a step either way makes every log's map less crisp.
/// Schaefer's reference reader uses `linspace(−fov/2, fov/2, n)` (`Closed`) for every count,
/// which turns the beams of a 180-beam scan by up to 1°.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum FanConvention {
    /// `Closed` for an odd number of beams, `HalfOpen` for an even number: beam `i` at
    /// −fov/2 + i·fov/(n − n mod 2). The measured convention of the Radish logs.
    #[default]
    Auto,
    /// `linspace(−fov/2, +fov/2, n)`: both ends of the field of view are beams.
    Closed,
    /// Start at −fov/2 with step fov/n: the beam at +fov/2 is missing (a 180-beam scan at 1°
    /// ends at +89°).
    HalfOpen,
    /// Step fov/n with the fan symmetric about 0 (a 180-beam scan spans ±89.5°).
    Centered,
}

impl FanConvention {
    /// All conventions, for evaluations and tests.
    pub const ALL: [FanConvention; 4] = [
        FanConvention::Auto,
        FanConvention::Closed,
        FanConvention::HalfOpen,
        FanConvention::Centered,
    ];

    /// A short name: `auto`, `closed`, `half-open`, `centered`.
    pub fn name(self) -> &'static str {
        match self {
            FanConvention::Auto => "auto",
            FanConvention::Closed => "closed",
            FanConvention::HalfOpen => "half-open",
            FanConvention::Centered => "centered",
        }
    }

    /// `(angle_min_rad, angle_increment_rad)` of `n` beams over `fov_rad`, or with the given
    /// increment when `increment_rad` is `Some`.
    pub fn layout(self, n: usize, fov_rad: f64, increment_rad: Option<f64>) -> (f64, f64) {
        if self == FanConvention::Auto {
            let resolved = if n % 2 == 1 {
                FanConvention::Closed
            } else {
                FanConvention::HalfOpen
            };
            return resolved.layout(n, fov_rad, increment_rad);
        }
        let n_f = n as f64;
        let increment = increment_rad.unwrap_or(match self {
            FanConvention::Closed if n > 1 => fov_rad / (n_f - 1.0),
            FanConvention::Closed => fov_rad,
            _ => fov_rad / n_f.max(1.0),
        });
        let first = match self {
            FanConvention::HalfOpen => -increment * n_f / 2.0,
            _ => -increment * (n_f - 1.0).max(0.0) / 2.0,
        };
        (first, increment)
    }
}

/// How the reader decides which readings are no-returns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NoReturnRange {
    /// Infer the log's no-return code (a repeated maximum reading) before reading, see
    /// [`crate::carmen::no_return`]. Where none is found, the `PARAM robot_front_laser_max`
    /// (`robot_rear_laser_max`) value, the `ROBOTLASER1` line's maximum range, or
    /// [`CarmenConfig::default_max_range_m`] is used, in this order.
    Infer,
    /// Readings at or above this many metres are no-returns, in every scan.
    Fixed(f64),
}

/// Options of [`crate::carmen::CarmenReader`]. `CarmenConfig::default()` reads every log of
/// the Radish collection correctly; the fields override what the reader infers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CarmenConfig {
    /// Beam layout of `FLASER`/`RLASER` scans.
    pub fan: FanConvention,
    /// Field of view of `FLASER`/`RLASER` scans in radians; `None`: the `PARAM
    /// laser_front_laser_fov` value, else π.
    pub fov_rad: Option<f64>,
    /// Angle between beams of `FLASER`/`RLASER` scans in radians; `None`: the `PARAM
    /// laser_front_laser_resolution` value (degrees in the log), else from the field of view
    /// and the convention.
    pub angle_increment_rad: Option<f64>,
    /// Angle of the first beam of `FLASER`/`RLASER` scans in radians; `None`: from the
    /// convention.
    pub angle_min_rad: Option<f64>,
    /// Beams counted clockwise (an upside-down laser); `None`: the `PARAM
    /// laser_front_laser_flipped` value, else `false`.
    pub flipped: Option<bool>,
    /// No-return threshold: inferred (default) or fixed.
    pub no_return: NoReturnRange,
    /// How many laser messages [`crate::carmen::CarmenReader::new`] reads ahead (and keeps)
    /// to infer the no-return code of a stream. [`crate::carmen::CarmenReader::open`] reads
    /// the whole file instead, in a first pass.
    pub lookahead_scans: usize,
    /// Maximum range in metres when nothing else says (the value Schaefer's reader assumes).
    pub default_max_range_m: f64,
    /// Refuse a log that ends mid-line. By default (`false`) an unreadable last line
    /// without a line break — a log cut off while it was written or copied — is skipped:
    /// the complete records before it are read and a warning names the file and the line
    /// ([`crate::carmen::CarmenReader::take_warnings`]). A malformed line anywhere else is
    /// an error either way.
    pub strict: bool,
}

impl Default for CarmenConfig {
    fn default() -> Self {
        Self {
            fan: FanConvention::default(),
            fov_rad: None,
            angle_increment_rad: None,
            angle_min_rad: None,
            flipped: None,
            no_return: NoReturnRange::Infer,
            lookahead_scans: 1000,
            default_max_range_m: 50.0,
            strict: false,
        }
    }
}

impl CarmenConfig {
    /// Checks the overrides: positive finite field of view, maximum ranges and thresholds,
    /// finite non-zero increment, finite first angle, at least one look-ahead scan.
    pub fn validate(&self, name: &Path) -> Result<()> {
        let bad = |reason: String| {
            Err(Error::malformed(
                name,
                Location::File,
                format!("invalid CARMEN reader configuration: {reason}"),
            ))
        };
        if let Some(fov) = self.fov_rad
            && !(fov.is_finite() && fov > 0.0 && fov <= 2.0 * PI + 1e-9)
        {
            return bad(format!(
                "field of view must be in (0, 2π] radians, got {fov}"
            ));
        }
        if let Some(inc) = self.angle_increment_rad
            && !(inc.is_finite() && inc != 0.0)
        {
            return bad(format!(
                "angle increment must be finite and non-zero, got {inc}"
            ));
        }
        if let Some(min) = self.angle_min_rad
            && !min.is_finite()
        {
            return bad(format!("first beam angle must be finite, got {min}"));
        }
        if let NoReturnRange::Fixed(max) = self.no_return
            && !(max.is_finite() && max > 0.0)
        {
            return bad(format!("no-return range must be positive, got {max}"));
        }
        if !(self.default_max_range_m.is_finite() && self.default_max_range_m > 0.0) {
            return bad(format!(
                "default maximum range must be positive, got {}",
                self.default_max_range_m
            ));
        }
        if self.lookahead_scans == 0 {
            return bad("look-ahead must be at least one scan".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_of_180_beams() {
        let deg = PI / 180.0;
        let (min, inc) = FanConvention::Closed.layout(180, PI, None);
        assert!((min + 90.0 * deg).abs() < 1e-12);
        assert!((min + 179.0 * inc - 90.0 * deg).abs() < 1e-12);
        let (min, inc) = FanConvention::HalfOpen.layout(180, PI, None);
        assert!((min + 90.0 * deg).abs() < 1e-12 && (inc - deg).abs() < 1e-12);
        let (min, inc) = FanConvention::Centered.layout(180, PI, None);
        assert!((min + 89.5 * deg).abs() < 1e-12 && (inc - deg).abs() < 1e-12);
        // A stated resolution is the increment.
        let (min, inc) = FanConvention::Closed.layout(361, PI, Some(0.5 * deg));
        assert!((min + 90.0 * deg).abs() < 1e-12 && (inc - 0.5 * deg).abs() < 1e-12);
        assert_eq!(FanConvention::Closed.layout(1, PI, None).0, 0.0);
        // Auto: 1° steps from −90° for 180 and 181 beams, 0.5° for 360 and 361.
        for (n, step) in [(180, 1.0), (181, 1.0), (360, 0.5), (361, 0.5)] {
            let (min, inc) = FanConvention::Auto.layout(n, PI, None);
            assert!((min + 90.0 * deg).abs() < 1e-12, "{n}");
            assert!((inc - step * deg).abs() < 1e-12, "{n}");
        }
        assert_eq!(FanConvention::HalfOpen.layout(0, PI, None), (0.0, PI));
    }

    #[test]
    fn rejects_bad_overrides() {
        let name = Path::new("x.log");
        assert!(CarmenConfig::default().validate(name).is_ok());
        let bad = [
            CarmenConfig {
                fov_rad: Some(f64::NAN),
                ..CarmenConfig::default()
            },
            CarmenConfig {
                angle_increment_rad: Some(0.0),
                ..CarmenConfig::default()
            },
            CarmenConfig {
                no_return: NoReturnRange::Fixed(-1.0),
                ..CarmenConfig::default()
            },
            CarmenConfig {
                lookahead_scans: 0,
                ..CarmenConfig::default()
            },
        ];
        for config in bad {
            let err = config.validate(name).unwrap_err().to_string();
            assert!(err.starts_with("x.log: invalid CARMEN"), "{err}");
        }
    }
}
