//! The `PARAM` lines the reader uses: field of view, resolution, maximum range and mounting of
//! the front and rear lasers.

use std::f64::consts::TAU;

use super::record::LaserKind;

/// What the log's `PARAM` lines say about one laser.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct LaserParams {
    /// `laser_front_laser_fov`: radians (values above 2π are taken as degrees).
    pub fov_rad: Option<f64>,
    /// `laser_front_laser_resolution`: degrees in the log, radians here.
    pub resolution_rad: Option<f64>,
    /// `robot_front_laser_max`: metres.
    pub max_range_m: Option<f64>,
    /// `laser_front_laser_flipped`.
    pub flipped: Option<bool>,
}

/// The laser parameters of a log; the first value of each parameter wins.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Params {
    pub front: LaserParams,
    pub rear: LaserParams,
}

impl Params {
    /// The parameters of the laser that sends `kind` messages (ROBOTLASER1 states its own).
    pub fn of(&self, kind: LaserKind) -> &LaserParams {
        match kind {
            LaserKind::Rear => &self.rear,
            LaserKind::Front | LaserKind::RobotLaser1 => &self.front,
        }
    }

    /// Records `name = value` when it is a laser parameter not set before. Returns an error
    /// message when the value of a used parameter cannot be understood.
    pub fn apply(&mut self, name: &str, value: &str) -> Result<(), String> {
        let (laser, key) = if let Some(key) = strip_laser(name, "front") {
            (&mut self.front, key)
        } else if let Some(key) = strip_laser(name, "rear") {
            (&mut self.rear, key)
        } else {
            return Ok(());
        };
        let number = || -> Result<f64, String> {
            value
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v > 0.0)
                .ok_or_else(|| format!("parameter {name}: {value:?} is not a positive number"))
        };
        match key {
            Key::Fov => {
                let v = number()?;
                let fov = if v > TAU + 1e-6 { v.to_radians() } else { v };
                laser.fov_rad.get_or_insert(fov);
            }
            Key::Resolution => {
                let resolution = number()?.to_radians();
                laser.resolution_rad.get_or_insert(resolution);
            }
            Key::MaxRange => {
                let max = number()?;
                laser.max_range_m.get_or_insert(max);
            }
            Key::Flipped => {
                let flipped = match value {
                    "1" | "on" | "yes" | "true" => true,
                    "0" | "off" | "no" | "false" => false,
                    _ => return Err(format!("parameter {name}: {value:?} is not 0/1/on/off")),
                };
                laser.flipped.get_or_insert(flipped);
            }
        }
        Ok(())
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Key {
    Fov,
    Resolution,
    MaxRange,
    Flipped,
}

/// Recognizes `laser_<side>_laser_<key>`, `laser_<side>laser_<key>` and
/// `robot_<side>_laser_max` (with or without the underscore).
fn strip_laser(name: &str, side: &str) -> Option<Key> {
    let rest = name
        .strip_prefix("laser_")
        .and_then(|r| r.strip_prefix(side));
    if let Some(rest) = rest {
        let key = rest
            .strip_prefix("_laser_")
            .or_else(|| rest.strip_prefix("laser_"))?;
        return match key {
            "fov" => Some(Key::Fov),
            "resolution" => Some(Key::Resolution),
            "flipped" => Some(Key::Flipped),
            _ => None,
        };
    }
    let rest = name.strip_prefix("robot_")?.strip_prefix(side)?;
    matches!(rest, "_laser_max" | "laser_max").then_some(Key::MaxRange)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recognizes_spellings_and_keeps_first() {
        let mut p = Params::default();
        p.apply("laser_front_laser_resolution", "0.5").unwrap();
        p.apply("laser_frontlaser_resolution", "1").unwrap();
        p.apply("laser_front_laser_fov", "180").unwrap();
        p.apply("laser_rear_laser_fov", "3.1").unwrap();
        p.apply("robot_front_laser_max", "80.99").unwrap();
        p.apply("laser_front_laser_flipped", "0").unwrap();
        p.apply("robot_frontlaser_offset", "-0.04").unwrap();
        assert!((p.front.resolution_rad.unwrap() - 0.5f64.to_radians()).abs() < 1e-15);
        assert!((p.front.fov_rad.unwrap() - std::f64::consts::PI).abs() < 1e-12);
        assert_eq!(p.rear.fov_rad, Some(3.1));
        assert_eq!(p.front.max_range_m, Some(80.99));
        assert_eq!(p.front.flipped, Some(false));
        assert_eq!(p.of(LaserKind::RobotLaser1), &p.front);
        assert!(p.apply("robot_rear_laser_max", "far").is_err());
        assert!(p.apply("laser_rear_laser_flipped", "maybe").is_err());
        assert!(p.apply("laser_rear_laser_resolution", "-1").is_err());
    }
}
