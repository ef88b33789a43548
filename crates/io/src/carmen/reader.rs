//! The streaming reader: lines in, typed records out.

use std::collections::VecDeque;
use std::f64::consts::PI;
use std::io::BufRead;
use std::path::{Path, PathBuf};

use raypath_geometry::Scan2;

use super::config::{CarmenConfig, NoReturnRange};
use super::no_return::{NoReturnEstimate, NoReturnHistogram};
use super::params::Params;
use super::parse::{Parsed, RawLaser, parse_line};
use super::record::{LaserKind, LaserMessage, Record};
use crate::error::{Error, Location, Result};
use crate::source::LineReader;

/// Reads a CARMEN log record by record.
///
/// ```no_run
/// use raypath_io::carmen::{CarmenReader, Record};
/// let path = std::path::Path::new("datasets/carmen/corrected/intel-corrected.log.gz");
/// for record in CarmenReader::open(path)? {
///     if let Record::Laser(laser) = record? {
///         let hits = laser.scan.points(laser.world_from_laser).count();
///         println!("{:.3} s: {hits} hits", laser.logger_timestamp_secs);
///     }
/// }
/// # Ok::<(), raypath_io::Error>(())
/// ```
///
/// Each item is one message line. A malformed line (or one that is not UTF-8) gives an `Err`
/// naming the line and the field, and reading goes on with the next line; a read error of
/// the file (a damaged gzip stream, for example) ends the iteration after its `Err`.
pub struct CarmenReader {
    name: PathBuf,
    lines: LineReader,
    config: CarmenConfig,
    params: Params,
    estimates: [Option<NoReturnEstimate>; 3],
    pending: VecDeque<Pending>,
    done: bool,
    warnings: Vec<String>,
}

/// A line read ahead: its number, what it parsed to, and whether it ended with a line break.
type Pending = (u64, Result<Parsed>, bool);

/// The look-ahead also stops after this many kept lines per laser message it may read.
const LOOKAHEAD_LINES_PER_SCAN: usize = 100;

/// What the first pass (or the look-ahead) learns: range histograms and laser parameters.
#[derive(Default)]
struct Prepass {
    histograms: [NoReturnHistogram; 3],
    params: Params,
}

impl Prepass {
    fn feed(&mut self, parsed: &Parsed) {
        match parsed {
            Parsed::Laser(raw) => self.histograms[kind_index(raw.kind)].add_all(&raw.ranges_m),
            // An unusable value is reported when the record is read.
            Parsed::Param { name, value } => self.params.apply(name, value).unwrap_or_default(),
            _ => {}
        }
    }
}

fn kind_index(kind: LaserKind) -> usize {
    match kind {
        LaserKind::Front => 0,
        LaserKind::Rear => 1,
        LaserKind::RobotLaser1 => 2,
    }
}

impl CarmenReader {
    /// Opens a log (plain, gzip or bzip2) with the default configuration.
    pub fn open(path: &Path) -> Result<Self> {
        Self::open_with(path, CarmenConfig::default())
    }

    /// Opens a log with `config`. With [`NoReturnRange::Infer`] the file is read twice: a
    /// first pass over all laser messages infers the no-return code and collects the laser
    /// `PARAM`s, then the records are read.
    pub fn open_with(path: &Path, config: CarmenConfig) -> Result<Self> {
        config.validate(path)?;
        let mut prepass = Prepass::default();
        if config.no_return == NoReturnRange::Infer {
            let mut lines = LineReader::open(path)?;
            // Errors are left to the second pass, which reports them at their line.
            let mut line = 0;
            while let Ok(Some(text)) = lines.next_line() {
                line += 1;
                if let Ok(parsed) = parse_line(text, path, line) {
                    prepass.feed(&parsed);
                }
            }
        }
        Ok(Self::from_parts(
            LineReader::open(path)?,
            config,
            prepass,
            VecDeque::new(),
            false,
        ))
    }

    /// Reads a log from `reader` (already decompressed) with the default configuration;
    /// `name` is used in error messages.
    pub fn new(reader: impl BufRead + Send + 'static, name: impl Into<PathBuf>) -> Self {
        let lines = LineReader::new(reader, name);
        Self::lookahead(lines, CarmenConfig::default())
    }

    /// Reads a log from `reader` with `config`. With [`NoReturnRange::Infer`] the first
    /// [`CarmenConfig::lookahead_scans`] laser messages (and the lines between them, at most
    /// 100 lines per look-ahead scan in all) are read and kept now to infer the no-return
    /// code.
    pub fn with_config(
        reader: impl BufRead + Send + 'static,
        name: impl Into<PathBuf>,
        config: CarmenConfig,
    ) -> Result<Self> {
        let name = name.into();
        config.validate(&name)?;
        Ok(Self::lookahead(LineReader::new(reader, name), config))
    }

    fn lookahead(mut lines: LineReader, config: CarmenConfig) -> Self {
        let name = lines.path().to_path_buf();
        let mut prepass = Prepass::default();
        let mut pending = VecDeque::new();
        let mut done = false;
        let mut scans = 0;
        // Bounded in lines too, so a log without laser messages is not read into memory.
        let max_lines = config
            .lookahead_scans
            .saturating_mul(LOOKAHEAD_LINES_PER_SCAN);
        while config.no_return == NoReturnRange::Infer
            && scans < config.lookahead_scans
            && pending.len() < max_lines
        {
            let line = lines.line_number() + 1;
            let parsed = match lines.next_line() {
                Ok(Some(text)) => parse_line(text, &name, line),
                Ok(None) => {
                    done = true;
                    break;
                }
                Err(e) => {
                    // A line that is not UTF-8 is skipped; a read error ends the stream.
                    let fatal = matches!(e, Error::Io { .. });
                    pending.push_back((line, Err(e), true));
                    if fatal {
                        done = true;
                        break;
                    }
                    continue;
                }
            };
            let terminated = lines.line_terminated();
            match parsed {
                Ok(Parsed::Skip) => {}
                Ok(parsed) => {
                    scans += usize::from(matches!(parsed, Parsed::Laser(_)));
                    prepass.feed(&parsed);
                    pending.push_back((line, Ok(parsed), terminated));
                }
                Err(e) => pending.push_back((line, Err(e), terminated)),
            }
        }
        Self::from_parts(lines, config, prepass, pending, done)
    }

    fn from_parts(
        lines: LineReader,
        config: CarmenConfig,
        prepass: Prepass,
        pending: VecDeque<Pending>,
        done: bool,
    ) -> Self {
        let [front, rear, robot] = &prepass.histograms;
        Self {
            name: lines.path().to_path_buf(),
            lines,
            config,
            params: prepass.params,
            estimates: [front.estimate(), rear.estimate(), robot.estimate()],
            pending,
            done,
            warnings: Vec::new(),
        }
    }

    /// Warnings since the last call (a last line cut off mid-line and skipped), each naming
    /// the file and the line.
    pub fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }

    /// The inferred no-return encoding of the messages of `kind` (`None` when the
    /// configuration fixes the range or no value repeats; see [`super::no_return`]).
    pub fn no_return(&self, kind: LaserKind) -> Option<NoReturnEstimate> {
        self.estimates[kind_index(kind)]
    }

    /// The configuration in use.
    pub fn config(&self) -> &CarmenConfig {
        &self.config
    }

    /// The file name used in errors.
    pub fn path(&self) -> &Path {
        &self.name
    }

    /// The range at or above which readings of `kind` messages are no-returns, for a message
    /// whose line states `stated_max_m` (ROBOTLASER1) or not.
    pub fn no_return_range_m(&self, kind: LaserKind, stated_max_m: Option<f64>) -> f64 {
        let stated = stated_max_m.filter(|m| m.is_finite() && *m > 0.0);
        match self.config.no_return {
            NoReturnRange::Fixed(range_m) => range_m,
            NoReturnRange::Infer => match (self.no_return(kind), stated) {
                (Some(e), Some(s)) => e.threshold_m.min(s),
                (Some(e), None) => e.threshold_m,
                (None, Some(s)) => s,
                (None, None) => self
                    .params
                    .of(kind)
                    .max_range_m
                    .unwrap_or(self.config.default_max_range_m),
            },
        }
    }

    /// `(angle_min_rad, angle_increment_rad)` of an old-format (`FLASER`/`RLASER`) scan of
    /// `n` beams, from the configuration, the `PARAM`s and the fan convention.
    pub fn old_format_layout(&self, kind: LaserKind, n: usize) -> (f64, f64) {
        let params = self.params.of(kind);
        let fov = self.config.fov_rad.or(params.fov_rad).unwrap_or(PI);
        let increment = self.config.angle_increment_rad.or(params.resolution_rad);
        let (mut min, mut increment) = self.config.fan.layout(n, fov, increment);
        if self.config.flipped.or(params.flipped).unwrap_or(false) {
            min = -min;
            increment = -increment;
        }
        (self.config.angle_min_rad.unwrap_or(min), increment)
    }

    fn finish(&mut self, line: u64, parsed: Parsed) -> Result<Option<Record>> {
        Ok(Some(match parsed {
            Parsed::Skip => return Ok(None),
            Parsed::Laser(raw) => Record::Laser(self.laser(raw)?),
            Parsed::Odometry(odometry) => Record::Odometry(odometry),
            Parsed::Param { name, value } => {
                self.params
                    .apply(&name, &value)
                    .map_err(|reason| Error::malformed(&self.name, Location::Line(line), reason))?;
                Record::Param { name, value }
            }
            Parsed::Other { tag, text } => Record::Other { tag, line, text },
        }))
    }

    fn laser(&self, raw: RawLaser) -> Result<LaserMessage> {
        let n = raw.ranges_m.len();
        let (angle_min_rad, angle_increment_rad) = match raw.stated_angles {
            Some(stated) => stated,
            None => self.old_format_layout(raw.kind, n),
        };
        let stated_max = raw.robot_laser.map(|info| info.stated_max_range_m);
        let scan = Scan2 {
            angle_min_rad,
            angle_increment_rad,
            max_range_m: self.no_return_range_m(raw.kind, stated_max),
            ranges: raw.ranges_m,
            intensities: raw.remissions,
        };
        scan.validate().map_err(|e| {
            Error::malformed(
                &self.name,
                Location::Line(raw.line),
                format!("{} message: {e}", raw.kind.tag()),
            )
        })?;
        Ok(LaserMessage {
            kind: raw.kind,
            scan,
            world_from_laser: raw.world_from_laser,
            world_from_robot: raw.world_from_robot,
            velocities: raw.velocities,
            robot_laser: raw.robot_laser,
            ipc_timestamp_secs: raw.ipc_timestamp_secs,
            hostname: raw.hostname,
            logger_timestamp_secs: raw.logger_timestamp_secs,
            line: raw.line,
        })
    }
}

impl CarmenReader {
    /// The laser messages of the front (or only) laser in file order, skipping odometry and
    /// rear-laser records; errors pass through. The usual input of 2-D mapping and
    /// localization.
    pub fn front_lasers(self) -> impl Iterator<Item = Result<LaserMessage>> {
        self.filter_map(|record| match record {
            Ok(Record::Laser(m)) if m.kind != LaserKind::Rear => Some(Ok(m)),
            Ok(_) => None,
            Err(e) => Some(Err(e)),
        })
    }
}

impl Iterator for CarmenReader {
    type Item = Result<Record>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let (line, parsed, terminated) = match self.pending.pop_front() {
                Some(item) => item,
                None if self.done => return None,
                None => {
                    let line = self.lines.line_number() + 1;
                    match self.lines.next_line() {
                        Ok(Some(text)) => {
                            let parsed = parse_line(text, &self.name, line);
                            (line, parsed, self.lines.line_terminated())
                        }
                        Ok(None) => {
                            self.done = true;
                            return None;
                        }
                        Err(e) => {
                            self.done = matches!(e, Error::Io { .. });
                            return Some(Err(e));
                        }
                    }
                }
            };
            match parsed.and_then(|p| self.finish(line, p)) {
                Ok(None) => {}
                Ok(Some(record)) => return Some(Ok(record)),
                Err(e) if !terminated && !self.config.strict => {
                    // The file ends mid-line: keep what came before, say what was dropped.
                    self.warnings.push(format!(
                        "{}: line {line}: the file ends mid-line; this last line was skipped \
                         ({e}); the complete records before it were read (strict reading \
                         refuses the log)",
                        self.name.display()
                    ));
                    self.done = true;
                    self.pending.clear();
                }
                Err(e) => return Some(Err(e)),
            }
        }
    }
}
