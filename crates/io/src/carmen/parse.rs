//! Parsing one line of a CARMEN log into a message whose beam angles are not resolved yet.

use std::path::Path;
use std::str::SplitAsciiWhitespace;

use raypath_geometry::Pose2;

use super::record::{LaserKind, OdometryMessage, RobotLaserInfo, Velocities};
use crate::error::{Error, Location, Result};

/// A parsed line, before the reader applies its beam-angle convention and no-return range.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Parsed {
    /// A comment or blank line.
    Skip,
    /// A laser message.
    Laser(RawLaser),
    /// An `ODOM` message.
    Odometry(OdometryMessage),
    /// A `PARAM` message.
    Param { name: String, value: String },
    /// Any other message.
    Other { tag: String, text: String },
}

/// A laser message as written: ranges and poses, angles only for ROBOTLASER1.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct RawLaser {
    pub kind: LaserKind,
    pub ranges_m: Vec<f64>,
    pub remissions: Option<Vec<f64>>,
    /// ROBOTLASER1: `(start_angle_rad, angular_resolution_rad)`.
    pub stated_angles: Option<(f64, f64)>,
    pub robot_laser: Option<RobotLaserInfo>,
    pub world_from_laser: Pose2,
    pub world_from_robot: Pose2,
    pub velocities: Option<Velocities>,
    pub ipc_timestamp_secs: f64,
    pub hostname: String,
    pub logger_timestamp_secs: f64,
    pub line: u64,
}

/// The whitespace-separated fields of one line, with errors naming the line and the field.
struct Fields<'a> {
    iter: SplitAsciiWhitespace<'a>,
    line_len: usize,
    path: &'a Path,
    line: u64,
    tag: &'a str,
}

impl<'a> Fields<'a> {
    fn error(&self, reason: impl std::fmt::Display) -> Error {
        Error::malformed(
            self.path,
            Location::Line(self.line),
            format!("{} message: {reason}", self.tag),
        )
    }

    fn text(&mut self, what: &str) -> Result<&'a str> {
        self.iter
            .next()
            .ok_or_else(|| self.error(format_args!("line ends before the {what}")))
    }

    fn number(&mut self, what: &str) -> Result<f64> {
        let text = self.text(what)?;
        match text.parse::<f64>() {
            Ok(value) if value.is_finite() => Ok(value),
            Ok(_) => Err(self.error(format_args!("{what} {text:?} is not a finite number"))),
            Err(_) => Err(self.error(format_args!("{what} {text:?} is not a number"))),
        }
    }

    fn integer(&mut self, what: &str) -> Result<i64> {
        let text = self.text(what)?;
        text.parse::<i64>()
            .map_err(|_| self.error(format_args!("{what} {text:?} is not an integer")))
    }

    /// A count of values that follow; it must fit in the line (every value takes at least
    /// two characters), so a corrupt count cannot make the reader allocate.
    fn count(&mut self, what: &str) -> Result<usize> {
        let text = self.text(what)?;
        let n = text
            .parse::<usize>()
            .map_err(|_| self.error(format_args!("{what} {text:?} is not a count")))?;
        if n > self.line_len / 2 {
            return Err(self.error(format_args!(
                "{what} {n} cannot fit in a line of {} characters",
                self.line_len
            )));
        }
        Ok(n)
    }

    fn numbers(&mut self, n: usize, what: &str) -> Result<Vec<f64>> {
        let mut values = Vec::with_capacity(n);
        for i in 0..n {
            let text = self
                .iter
                .next()
                .ok_or_else(|| self.error(format_args!("line ends after {i} of {n} {what}")))?;
            match text.parse::<f64>() {
                Ok(value) if value.is_finite() => values.push(value),
                _ => {
                    return Err(self.error(format_args!(
                        "{what} {} of {n}: {text:?} is not a finite number",
                        i + 1
                    )));
                }
            }
        }
        Ok(values)
    }

    /// Three numbers `x y theta`, named in errors by `names`.
    fn pose(&mut self, names: [&str; 3]) -> Result<Pose2> {
        let [x, y, theta] = names;
        let x = self.number(x)?;
        let y = self.number(y)?;
        let theta = self.number(theta)?;
        Ok(Pose2::new(x, y, theta))
    }

    /// `ipc_timestamp ipc_hostname logger_timestamp`, then the end of the line.
    fn stamps(&mut self) -> Result<(f64, String, f64)> {
        let ipc = self.number("ipc timestamp")?;
        let host = self.text("ipc hostname")?.to_owned();
        let logger = self.number("logger timestamp")?;
        self.end()?;
        Ok((ipc, host, logger))
    }

    fn end(&mut self) -> Result<()> {
        let extra = self.iter.by_ref().count();
        if extra > 0 {
            return Err(self.error(format_args!(
                "{extra} unexpected field(s) after the logger timestamp"
            )));
        }
        Ok(())
    }
}

/// Parses one line (without its line ending). `path` and `line` are used in errors.
pub(crate) fn parse_line(text: &str, path: &Path, line: u64) -> Result<Parsed> {
    let trimmed = text.trim_start();
    if trimmed.is_empty() || trimmed.starts_with('#') {
        return Ok(Parsed::Skip);
    }
    let mut iter = trimmed.split_ascii_whitespace();
    let tag = iter.next().unwrap_or_default();
    let mut fields = Fields {
        iter,
        line_len: trimmed.len(),
        path,
        line,
        tag,
    };
    match tag {
        "FLASER" => parse_old_laser(&mut fields, LaserKind::Front, line),
        "RLASER" => parse_old_laser(&mut fields, LaserKind::Rear, line),
        "ROBOTLASER1" => parse_robot_laser(&mut fields, line),
        "ODOM" => parse_odometry(&mut fields, line),
        "PARAM" => parse_param(&mut fields),
        _ => Ok(Parsed::Other {
            tag: tag.to_owned(),
            text: trimmed
                .get(tag.len()..)
                .unwrap_or_default()
                .trim()
                .to_owned(),
        }),
    }
}

/// `FLASER n r_1 … r_n x y theta odom_x odom_y odom_theta ipc_ts host logger_ts`.
fn parse_old_laser(fields: &mut Fields<'_>, kind: LaserKind, line: u64) -> Result<Parsed> {
    let n = fields.count("number of readings")?;
    let ranges_m = fields.numbers(n, "range readings")?;
    let world_from_laser = fields.pose(["laser pose x", "laser pose y", "laser pose theta"])?;
    let world_from_robot =
        fields.pose(["odometry pose x", "odometry pose y", "odometry pose theta"])?;
    let (ipc_timestamp_secs, hostname, logger_timestamp_secs) = fields.stamps()?;
    Ok(Parsed::Laser(RawLaser {
        kind,
        ranges_m,
        remissions: None,
        stated_angles: None,
        robot_laser: None,
        world_from_laser,
        world_from_robot,
        velocities: None,
        ipc_timestamp_secs,
        hostname,
        logger_timestamp_secs,
        line,
    }))
}

/// `ROBOTLASER1 type start fov res max_range accuracy remission_mode n r_1 … n_rem rem_1 …
/// laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv fwd_safety side_safety
/// turn_axis ipc_ts host logger_ts`.
fn parse_robot_laser(fields: &mut Fields<'_>, line: u64) -> Result<Parsed> {
    let laser_type = fields.integer("laser type")?;
    let start_angle = fields.number("start angle")?;
    let fov_rad = fields.number("field of view")?;
    let resolution = fields.number("angular resolution")?;
    let stated_max_range_m = fields.number("maximum range")?;
    let accuracy_m = fields.number("accuracy")?;
    let remission_mode = fields.integer("remission mode")?;
    let n = fields.count("number of readings")?;
    let ranges_m = fields.numbers(n, "range readings")?;
    let n_rem = fields.count("number of remissions")?;
    let remissions = fields.numbers(n_rem, "remission values")?;
    let remissions = match n_rem {
        0 => None,
        _ if n_rem == n => Some(remissions),
        _ => {
            return Err(fields.error(format_args!("{n_rem} remission values for {n} ranges")));
        }
    };
    let world_from_laser = fields.pose(["laser pose x", "laser pose y", "laser pose theta"])?;
    let world_from_robot = fields.pose(["robot pose x", "robot pose y", "robot pose theta"])?;
    let tv_mps = fields.number("translational velocity")?;
    let rv_radps = fields.number("rotational velocity")?;
    let forward_safety_m = fields.number("forward safety distance")?;
    let side_safety_m = fields.number("side safety distance")?;
    let turn_axis = fields.number("turn axis")?;
    let (ipc_timestamp_secs, hostname, logger_timestamp_secs) = fields.stamps()?;
    Ok(Parsed::Laser(RawLaser {
        kind: LaserKind::RobotLaser1,
        ranges_m,
        remissions,
        stated_angles: Some((start_angle, resolution)),
        robot_laser: Some(RobotLaserInfo {
            laser_type,
            fov_rad,
            stated_max_range_m,
            accuracy_m,
            remission_mode,
            forward_safety_m,
            side_safety_m,
            turn_axis,
        }),
        world_from_laser,
        world_from_robot,
        velocities: Some(Velocities { tv_mps, rv_radps }),
        ipc_timestamp_secs,
        hostname,
        logger_timestamp_secs,
        line,
    }))
}

/// `ODOM x y theta tv rv accel ipc_ts host logger_ts`.
fn parse_odometry(fields: &mut Fields<'_>, line: u64) -> Result<Parsed> {
    let world_from_robot = fields.pose(["pose x", "pose y", "pose theta"])?;
    let tv_mps = fields.number("translational velocity")?;
    let rv_radps = fields.number("rotational velocity")?;
    let accel_mps2 = fields.number("acceleration")?;
    let (ipc_timestamp_secs, hostname, logger_timestamp_secs) = fields.stamps()?;
    Ok(Parsed::Odometry(OdometryMessage {
        world_from_robot,
        velocities: Velocities { tv_mps, rv_radps },
        accel_mps2,
        ipc_timestamp_secs,
        hostname,
        logger_timestamp_secs,
        line,
    }))
}

/// `PARAM name value [ipc_ts] host logger_ts`. Old logs write `nohost 0` after the value,
/// newer ones `ipc_ts host logger_ts`; a value may contain spaces. The tail is recognized
/// from the end: three fields `number word number` when something is left for the value,
/// else two fields `word number`, else the whole rest is the value.
fn parse_param(fields: &mut Fields<'_>) -> Result<Parsed> {
    let name = fields.text("parameter name")?.to_owned();
    let rest: Vec<&str> = fields.iter.by_ref().collect();
    if rest.is_empty() {
        return Err(fields.error(format_args!("parameter {name} has no value")));
    }
    let is_number = |s: &str| s.parse::<f64>().is_ok();
    let tail = match rest.as_slice() {
        [.., ts, host, logger]
            if rest.len() > 3 && is_number(ts) && !is_number(host) && is_number(logger) =>
        {
            3
        }
        [.., host, logger] if rest.len() > 2 && !is_number(host) && is_number(logger) => 2,
        _ => 0,
    };
    let value = rest.get(..rest.len() - tail).unwrap_or_default().join(" ");
    Ok(Parsed::Param { name, value })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Parsed> {
        parse_line(text, Path::new("t.log"), 7)
    }

    fn param(text: &str) -> (String, String) {
        match parse(text).unwrap() {
            Parsed::Param { name, value } => (name, value),
            other => panic!("not a param: {other:?}"),
        }
    }

    #[test]
    fn params_in_all_layouts() {
        let p = |n: &str, v: &str| (n.to_owned(), v.to_owned());
        assert_eq!(
            param("PARAM robot_use_laser on nohost 0"),
            p("robot_use_laser", "on")
        );
        assert_eq!(
            param("PARAM robot_rectangular 0 nohost 0"),
            p("robot_rectangular", "0")
        );
        assert_eq!(
            param("PARAM laser_frontlaser_resolution 1 0.0 nohost 0"),
            p("laser_frontlaser_resolution", "1")
        );
        assert_eq!(
            param("PARAM laser_front_laser_fov 3.14159 1134863807.736300 b21 1134863807.736297"),
            p("laser_front_laser_fov", "3.14159")
        );
        assert_eq!(param("PARAM map /tmp/a map.gz"), p("map", "/tmp/a map.gz"));
        assert_eq!(param("PARAM x 5"), p("x", "5"));
        assert!(parse("PARAM lonely").is_err());
    }

    #[test]
    fn comments_and_others() {
        assert_eq!(parse("# FLASER 3").unwrap(), Parsed::Skip);
        assert_eq!(parse("   ").unwrap(), Parsed::Skip);
        assert_eq!(
            parse("NEFF 27.6 0 pippo 0").unwrap(),
            Parsed::Other {
                tag: "NEFF".into(),
                text: "27.6 0 pippo 0".into()
            }
        );
    }

    #[test]
    fn errors_name_line_and_field() {
        let err = parse("FLASER 3 1 2 x 0 0 0 0 0 0 1 h 1")
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "t.log:7: FLASER message: range readings 3 of 3: \"x\" is not a finite number"
        );
        let err = parse("FLASER 3 1 2 3 0 0 0 0 0").unwrap_err().to_string();
        assert_eq!(
            err,
            "t.log:7: FLASER message: line ends before the odometry pose theta"
        );
        let err = parse("FLASER 99999999999 1").unwrap_err().to_string();
        assert!(err.contains("cannot fit"), "{err}");
        let err = parse("ODOM 0 0 0 0 0 0 1 h 1 extra")
            .unwrap_err()
            .to_string();
        assert!(err.contains("1 unexpected field(s)"), "{err}");
        let err = parse("ODOM 0 0 nan 0 0 0 1 h 1").unwrap_err().to_string();
        assert!(
            err.contains("pose theta \"nan\" is not a finite number"),
            "{err}"
        );
        let err =
            parse("ROBOTLASER1 0 -1.5 3.1 0.01 81.9 0.01 0 2 1 2 1 5 0 0 0 0 0 0 0 0 0 0 0 1 h 1")
                .unwrap_err()
                .to_string();
        assert!(err.contains("1 remission values for 2 ranges"), "{err}");
    }
}
