//! Writing CARMEN logs: `PARAM`, `ODOM`, `FLASER`/`RLASER` and `ROBOTLASER1` lines in the
//! layout the reader (and CARMEN itself) expects.
//!
//! The writer takes the reader's typed records ([`LaserMessage`], [`OdometryMessage`],
//! [`Record`]), so a log read and written again gives the same records. Numbers are written
//! with a fixed, documented [`NumberFormat`]: the same values always give the same bytes
//! (Rust's float formatting is exact and platform-independent), which the simulator relies on
//! for byte-identical data sets.
//!
//! Line layouts (one message per line, fields separated by one space, `\n` line endings):
//!
//! ```text
//! PARAM name value ipc_timestamp ipc_hostname logger_timestamp
//! ODOM x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp
//! FLASER n r_1 … r_n x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname logger_timestamp
//! ROBOTLASER1 laser_type start_angle fov angular_res max_range accuracy remission_mode
//!             n r_1 … r_n n_rem rem_1 … laser_x laser_y laser_theta robot_x robot_y robot_theta
//!             tv rv forward_safety side_safety turn_axis ipc_timestamp ipc_hostname logger_timestamp
//! ```
//!
//! `PARAM` lines are written with the full three-field tail of newer CARMEN logs
//! (`0.000000 nohost 0.000000` by default), which the reader separates from the value even
//! when the value contains spaces or ends in a number. A `FLASER` line carries no beam angles:
//! write `PARAM laser_front_laser_fov` and `laser_front_laser_resolution` lines (degrees) so
//! readers place the beams as intended, see [`crate::carmen::FanConvention`].

use std::io::Write;
use std::path::{Path, PathBuf};

use raypath_geometry::Pose2;

use super::record::{LaserKind, LaserMessage, OdometryMessage, Record};
use crate::error::{Error, Location, Result};

/// How many decimals a number is written with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decimals {
    /// Exactly this many digits after the decimal point (`format!("{:.N}")`, correctly
    /// rounded), like C's `%.Nf`.
    Fixed(u8),
    /// The shortest decimal that reads back as the same `f64` (`format!("{}")`): lossless.
    Shortest,
}

impl Decimals {
    fn write(self, out: &mut String, value: f64) {
        use std::fmt::Write as _;
        // Writing into a String cannot fail.
        let _ = match self {
            Decimals::Fixed(n) => write!(out, "{:.*}", usize::from(n), value),
            Decimals::Shortest => write!(out, "{value}"),
        };
    }
}

/// The number formatting of a [`CarmenWriter`], per kind of field.
///
/// The default is the layout of the raw CARMEN logs (`%f`, six decimals, for poses, angles
/// and timestamps) with millimetre ranges (three decimals, as in `ROBOTLASER1` logs; older
/// `FLASER` logs such as intel's use two): it rewrites the `ROBOTLASER1` lines of
/// fr-clinic byte for byte.
///
/// | field | default |
/// |---|---|
/// | ranges | 3 decimals (mm) |
/// | remissions | 3 decimals |
/// | poses, velocities, acceleration, and the `ROBOTLASER1` angles, maximum range, accuracy, safety distances and turn axis | 6 decimals |
/// | timestamps (IPC and logger) | 6 decimals (µs) |
///
/// [`NumberFormat::exact`] writes every number losslessly instead.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NumberFormat {
    /// Range readings (metres).
    pub range: Decimals,
    /// Remission (intensity) values.
    pub remission: Decimals,
    /// Pose coordinates (metres, radians), velocities, acceleration, and the other numbers
    /// of `ROBOTLASER1` lines (beam angles, maximum range, accuracy, safety distances, turn
    /// axis).
    pub pose: Decimals,
    /// IPC and logger timestamps (seconds).
    pub time: Decimals,
}

impl Default for NumberFormat {
    fn default() -> Self {
        Self {
            range: Decimals::Fixed(3),
            remission: Decimals::Fixed(3),
            pose: Decimals::Fixed(6),
            time: Decimals::Fixed(6),
        }
    }
}

impl NumberFormat {
    /// Every number in its shortest lossless form: a log read and written again reads back
    /// bit-identical.
    pub fn exact() -> Self {
        Self {
            range: Decimals::Shortest,
            remission: Decimals::Shortest,
            pose: Decimals::Shortest,
            time: Decimals::Shortest,
        }
    }
}

/// The CARMEN comment block written by [`CarmenWriter::header`] (CARMEN's own logger writes
/// the same lines, listing the messages it defines).
const HEADER: &str = "\
# CARMEN Logfile
# file format is one message per line
# message_name [message contents] ipc_timestamp ipc_hostname logger_timestamp
# message formats defined: PARAM SYNC ODOM FLASER RLASER ROBOTLASER1
# PARAM param_name param_value
# ODOM x y theta tv rv accel
# FLASER num_readings [range_readings] x y theta odom_x odom_y odom_theta
# RLASER num_readings [range_readings] x y theta odom_x odom_y odom_theta
# ROBOTLASER1 laser_type start_angle field_of_view angular_resolution maximum_range accuracy remission_mode num_readings [range_readings] num_remissions [remission values] laser_pose_x laser_pose_y laser_pose_theta robot_pose_x robot_pose_y robot_pose_theta laser_tv laser_rv forward_safety_dist side_safty_dist turn_axis
";

/// Writes CARMEN messages to any [`Write`], one line each.
///
/// ```
/// use raypath_geometry::Pose2;
/// use raypath_io::carmen::{CarmenReader, CarmenWriter, OdometryMessage, Record, Velocities};
///
/// let mut writer = CarmenWriter::new(Vec::new(), "mem.log");
/// writer.param("robot_front_laser_max", "30")?;
/// writer.odometry(&OdometryMessage {
///     world_from_robot: Pose2::new(1.0, 2.0, 0.5),
///     velocities: Velocities { tv_mps: 0.3, rv_radps: 0.0 },
///     accel_mps2: 0.0,
///     ipc_timestamp_secs: 1000.25,
///     hostname: "robot".into(),
///     logger_timestamp_secs: 0.25,
///     line: 0,
/// })?;
/// let bytes = writer.finish()?;
/// assert!(String::from_utf8_lossy(&bytes).ends_with(
///     "ODOM 1.000000 2.000000 0.500000 0.300000 0.000000 0.000000 1000.250000 robot 0.250000\n"
/// ));
/// let records: Vec<_> = CarmenReader::new(std::io::Cursor::new(bytes), "mem.log").collect();
/// assert!(matches!(records[1], Ok(Record::Odometry(_))));
/// # Ok::<(), raypath_io::Error>(())
/// ```
pub struct CarmenWriter<W: Write> {
    writer: W,
    name: PathBuf,
    format: NumberFormat,
    line: String,
    lines_written: u64,
}

impl<W: Write> CarmenWriter<W> {
    /// A writer with the default [`NumberFormat`]; `name` names the destination in errors.
    pub fn new(writer: W, name: impl Into<PathBuf>) -> Self {
        Self::with_format(writer, name, NumberFormat::default())
    }

    /// A writer with the number format `format`.
    pub fn with_format(writer: W, name: impl Into<PathBuf>, format: NumberFormat) -> Self {
        Self {
            writer,
            name: name.into(),
            format,
            line: String::with_capacity(4096),
            lines_written: 0,
        }
    }

    /// The number format in use.
    pub fn format(&self) -> &NumberFormat {
        &self.format
    }

    /// Number of lines written so far.
    pub fn lines_written(&self) -> u64 {
        self.lines_written
    }

    /// Writes CARMEN's comment block that opens a log (the message formats).
    pub fn header(&mut self) -> Result<()> {
        for line in HEADER.lines() {
            self.line.clear();
            self.line.push_str(line);
            self.emit()?;
        }
        Ok(())
    }

    /// Writes `# text`. The text must be a single line.
    pub fn comment(&mut self, text: &str) -> Result<()> {
        self.check_single_line(text, "comment")?;
        self.line.clear();
        self.line.push_str("# ");
        self.line.push_str(text);
        self.emit()
    }

    /// Writes `PARAM name value 0.000000 nohost 0.000000` (zero timestamps formatted with
    /// [`NumberFormat::time`]). The name must be one word; the value may contain spaces but
    /// not line breaks.
    pub fn param(&mut self, name: &str, value: &str) -> Result<()> {
        self.check_word(name, "parameter name")?;
        self.check_single_line(value, "parameter value")?;
        if value.trim().is_empty() {
            return Err(self.unwritable(format!("parameter {name} has an empty value")));
        }
        self.line.clear();
        self.line.push_str("PARAM ");
        self.line.push_str(name);
        self.line.push(' ');
        self.line.push_str(value.trim());
        self.stamps(0.0, "nohost", 0.0)?;
        self.emit()
    }

    /// Writes an `ODOM` line.
    pub fn odometry(&mut self, odom: &OdometryMessage) -> Result<()> {
        self.line.clear();
        self.line.push_str("ODOM");
        self.pose(&odom.world_from_robot, "odometry pose")?;
        let v = odom.velocities;
        self.numbers(
            &[v.tv_mps, v.rv_radps, odom.accel_mps2],
            self.format.pose,
            "velocity",
        )?;
        self.stamps(
            odom.ipc_timestamp_secs,
            &odom.hostname,
            odom.logger_timestamp_secs,
        )?;
        self.emit()
    }

    /// Writes a laser message as the line of its [`LaserMessage::kind`]: `FLASER`, `RLASER`
    /// (ranges and the two poses; the beam angles are not part of the line) or `ROBOTLASER1`
    /// (angles from the scan; the other stated fields from [`LaserMessage::robot_laser`], or
    /// defaults when it is `None`: laser type 0, field of view (n − 1)·|increment|, maximum
    /// range [`raypath_geometry::Scan2::max_range_m`], accuracy 0, remission mode 1 with
    /// remissions and 0 without, zero safety distances and turn axis; velocities 0 when
    /// [`LaserMessage::velocities`] is `None`).
    pub fn laser(&mut self, laser: &LaserMessage) -> Result<()> {
        let scan = &laser.scan;
        if let Some(intensities) = &scan.intensities
            && intensities.len() != scan.ranges.len()
        {
            return Err(self.unwritable(format!(
                "{} remissions for {} ranges",
                intensities.len(),
                scan.ranges.len()
            )));
        }
        self.line.clear();
        self.line.push_str(laser.kind.tag());
        match laser.kind {
            LaserKind::Front | LaserKind::Rear => {
                self.count(scan.ranges.len());
                self.numbers(&scan.ranges, self.format.range, "range reading")?;
                self.pose(&laser.world_from_laser, "laser pose")?;
                self.pose(&laser.world_from_robot, "odometry pose")?;
            }
            LaserKind::RobotLaser1 => {
                let n = scan.ranges.len();
                let remissions = scan.intensities.as_deref().unwrap_or_default();
                let info = laser.robot_laser;
                let fov = info.map_or(
                    n.saturating_sub(1) as f64 * scan.angle_increment_rad.abs(),
                    |i| i.fov_rad,
                );
                self.line.push(' ');
                self.line
                    .push_str(&info.map_or(0, |i| i.laser_type).to_string());
                self.numbers(
                    &[scan.angle_min_rad, fov, scan.angle_increment_rad],
                    self.format.pose,
                    "beam angle",
                )?;
                self.numbers(
                    &[
                        info.map_or(scan.max_range_m, |i| i.stated_max_range_m),
                        info.map_or(0.0, |i| i.accuracy_m),
                    ],
                    self.format.pose,
                    "maximum range or accuracy",
                )?;
                let mode = info.map_or(i64::from(!remissions.is_empty()), |i| i.remission_mode);
                self.line.push(' ');
                self.line.push_str(&mode.to_string());
                self.count(n);
                self.numbers(&scan.ranges, self.format.range, "range reading")?;
                self.count(remissions.len());
                self.numbers(remissions, self.format.remission, "remission")?;
                self.pose(&laser.world_from_laser, "laser pose")?;
                self.pose(&laser.world_from_robot, "robot pose")?;
                let v = laser.velocities;
                self.numbers(
                    &[
                        v.map_or(0.0, |v| v.tv_mps),
                        v.map_or(0.0, |v| v.rv_radps),
                        info.map_or(0.0, |i| i.forward_safety_m),
                        info.map_or(0.0, |i| i.side_safety_m),
                        info.map_or(0.0, |i| i.turn_axis),
                    ],
                    self.format.pose,
                    "velocity or safety field",
                )?;
            }
        }
        self.stamps(
            laser.ipc_timestamp_secs,
            &laser.hostname,
            laser.logger_timestamp_secs,
        )?;
        self.emit()
    }

    /// Writes any other message as `tag text` (the text as given, a single line).
    pub fn other(&mut self, tag: &str, text: &str) -> Result<()> {
        self.check_word(tag, "message tag")?;
        if matches!(tag, "PARAM" | "ODOM" | "FLASER" | "RLASER" | "ROBOTLASER1") {
            return Err(self.unwritable(format!(
                "{tag} is a typed message; write it with its own method"
            )));
        }
        self.check_single_line(text, "message text")?;
        self.line.clear();
        self.line.push_str(tag);
        if !text.is_empty() {
            self.line.push(' ');
            self.line.push_str(text);
        }
        self.emit()
    }

    /// Writes a record read by [`crate::carmen::CarmenReader`].
    pub fn record(&mut self, record: &Record) -> Result<()> {
        match record {
            Record::Laser(laser) => self.laser(laser),
            Record::Odometry(odom) => self.odometry(odom),
            Record::Param { name, value } => self.param(name, value),
            Record::Other { tag, text, .. } => self.other(tag, text),
        }
    }

    /// Flushes and returns the inner writer.
    pub fn finish(mut self) -> Result<W> {
        let location = Location::Line(self.lines_written);
        self.writer
            .flush()
            .map_err(|e| Error::io(&self.name, location, e))?;
        Ok(self.writer)
    }

    fn count(&mut self, n: usize) {
        self.line.push(' ');
        self.line.push_str(&n.to_string());
    }

    fn numbers(&mut self, values: &[f64], decimals: Decimals, what: &str) -> Result<()> {
        for (i, &value) in values.iter().enumerate() {
            if !value.is_finite() {
                return Err(self.unwritable(format!(
                    "{what} {} of {} is not finite ({value})",
                    i + 1,
                    values.len()
                )));
            }
            self.line.push(' ');
            decimals.write(&mut self.line, value);
        }
        Ok(())
    }

    fn pose(&mut self, pose: &Pose2, what: &str) -> Result<()> {
        self.numbers(&[pose.x(), pose.y(), pose.theta()], self.format.pose, what)
    }

    fn stamps(&mut self, ipc_secs: f64, host: &str, logger_secs: f64) -> Result<()> {
        self.check_word(host, "hostname")?;
        if host.parse::<f64>().is_ok() {
            return Err(self.unwritable(format!(
                "hostname {host:?} is a number, which readers cannot tell from a timestamp"
            )));
        }
        self.numbers(&[ipc_secs], self.format.time, "IPC timestamp")?;
        self.line.push(' ');
        self.line.push_str(host);
        self.numbers(&[logger_secs], self.format.time, "logger timestamp")
    }

    fn check_word(&self, word: &str, what: &str) -> Result<()> {
        if word.is_empty() || word.chars().any(|c| c.is_whitespace()) {
            return Err(self.unwritable(format!(
                "{what} {word:?} must be one non-empty word without spaces"
            )));
        }
        Ok(())
    }

    fn check_single_line(&self, text: &str, what: &str) -> Result<()> {
        if text.contains(['\n', '\r']) {
            return Err(self.unwritable(format!("{what} {text:?} contains a line break")));
        }
        Ok(())
    }

    fn unwritable(&self, reason: String) -> Error {
        Error::Unwritable {
            path: self.name.clone(),
            reason: format!("line {}: {reason}", self.lines_written + 1),
        }
    }

    fn emit(&mut self) -> Result<()> {
        self.line.push('\n');
        let location = Location::Line(self.lines_written + 1);
        self.writer
            .write_all(self.line.as_bytes())
            .map_err(|e| Error::io(&self.name, location, e))?;
        self.lines_written += 1;
        Ok(())
    }
}

impl CarmenWriter<std::io::BufWriter<std::fs::File>> {
    /// Creates (or truncates) the file `path` and writes to it, buffered. The file is plain
    /// text; compress it afterwards (or wrap a compressing writer with
    /// [`CarmenWriter::with_format`]) for `.gz`/`.bz2` logs.
    pub fn create(path: &Path) -> Result<Self> {
        let file = std::fs::File::create(path).map_err(|e| Error::io(path, Location::File, e))?;
        Ok(Self::new(std::io::BufWriter::new(file), path))
    }
}
