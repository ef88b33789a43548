//! Sequences of timestamped planar scans with odometry and optional reference poses.

use std::fmt;
use std::path::{Path, PathBuf};

use raypath_geometry::{Pose2, Scan2};

use crate::carmen::{CarmenConfig, CarmenReader, LaserKind, LaserMessage, Record};
use crate::error::{Error, Result};
use crate::sequence::Topics;

/// Which laser of a CARMEN log to read.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LaserChoice {
    /// The front laser: `FLASER` lines, or `ROBOTLASER1` lines when the log has no `FLASER`
    /// (the usual input of mapping and localization).
    #[default]
    Front,
    /// The rear laser: `RLASER` lines.
    Rear,
    /// Every laser line (`FLASER`, `RLASER`, `ROBOTLASER1`) in file order.
    Any,
}

impl std::str::FromStr for LaserChoice {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "front" => Ok(LaserChoice::Front),
            "rear" => Ok(LaserChoice::Rear),
            "any" => Ok(LaserChoice::Any),
            other => Err(format!("{other:?}: expected front, rear or any")),
        }
    }
}

/// Where in its file a frame came from, for messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    /// A 1-based line of a text log.
    Line(u64),
    /// A message of a recording, by its log time in nanoseconds.
    LogTimeNs(u64),
}

impl fmt::Display for Origin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Origin::Line(line) => write!(f, "line {line}"),
            Origin::LogTimeNs(ns) => write!(f, "log time {:.9} s", *ns as f64 * 1e-9),
        }
    }
}

/// One timestamped planar scan with the poses logged with it.
///
/// "World" is the frame the log's poses are in: the odometry frame in raw logs and bags, the
/// SLAM-corrected map frame in the `*-corrected` CARMEN logs.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanarFrame {
    /// Time of the scan, seconds (the CARMEN logger timestamp; the header stamp in a bag).
    pub stamp_secs: f64,
    /// The CARMEN ipc time stamp (when the message was sent), seconds: the SLAM benchmark's
    /// relation files ([`crate::relations`]) name scans by it. `None` where the source has
    /// none (bags).
    pub ipc_stamp_secs: Option<f64>,
    /// The scan in the laser frame (REP-103; no-returns as ranges ≥ `max_range_m`).
    pub scan: Scan2,
    /// The robot's logged pose: odometry in raw logs and bags.
    pub world_from_robot: Pose2,
    /// The laser's logged pose (`world_from_robot · robot_from_laser`).
    pub world_from_laser: Pose2,
    /// A reference (ground-truth or corrected) `world_from_laser`, when the source has one
    /// (a bag's reference-pose topic, or a corrected log paired with [`pair_reference`]).
    ///
    /// [`pair_reference`]: crate::sequence::pair_reference
    pub reference: Option<Pose2>,
    /// Where the frame came from.
    pub origin: Origin,
}

impl PlanarFrame {
    /// The time the sensor took the scan, seconds: the one benchmark tools and `evo` join
    /// trajectories on. The CARMEN ipc time stamp where the source has one (set by the laser
    /// driver when it sent the scan; the SLAM benchmark's relation files name scans by it),
    /// else [`Self::stamp_secs`] (a bag's header stamp). The CARMEN logger time in
    /// [`Self::stamp_secs`] is when the logger received the message, counted from its start.
    pub fn sensor_stamp_secs(&self) -> f64 {
        self.ipc_stamp_secs
            .filter(|t| t.is_finite())
            .unwrap_or(self.stamp_secs)
    }

    /// The laser's mounting `robot_from_laser`.
    pub fn robot_from_laser(&self) -> Pose2 {
        self.world_from_robot.inverse() * self.world_from_laser
    }

    fn from_carmen(m: LaserMessage) -> Self {
        Self {
            stamp_secs: m.logger_timestamp_secs,
            ipc_stamp_secs: Some(m.ipc_timestamp_secs),
            scan: m.scan,
            world_from_robot: m.world_from_robot,
            world_from_laser: m.world_from_laser,
            reference: None,
            origin: Origin::Line(m.line),
        }
    }
}

/// A source of planar frames: an iterator in time order with a name for messages.
///
/// Implemented for CARMEN logs ([`CarmenScans`]) and rosbag2 recordings; implement it to feed
/// your own logs to every planar command.
pub trait PlanarSource: Iterator<Item = Result<PlanarFrame>> + Send {
    /// The file (and topic) the frames come from, for messages.
    fn name(&self) -> &Path;

    /// The warnings met so far (lines or messages skipped, truncation, missing poses): the
    /// reader does not print them; each is also emitted through the `log` facade as it
    /// occurs, which the `raypath` program and `cargo xtask` print as `warning: …`.
    fn warnings(&self) -> &[String] {
        &[]
    }
}

/// How to open a planar sequence.
#[derive(Clone, Debug, Default)]
pub struct PlanarOptions {
    /// Which laser of a CARMEN log.
    pub laser: LaserChoice,
    /// CARMEN reader options (fan convention, no-return threshold).
    pub carmen: CarmenConfig,
    /// Topic and frame choice for bags.
    pub topics: Topics,
}

/// The scans of one laser of a CARMEN log, in file order.
pub struct CarmenScans {
    reader: Option<CarmenReader>,
    name: PathBuf,
    laser: LaserChoice,
    /// Front choice: `ROBOTLASER1` scans kept until the first `FLASER` shows up.
    robot_lasers: Vec<LaserMessage>,
    seen_flaser: bool,
    drained: std::vec::IntoIter<LaserMessage>,
    warnings: Vec<String>,
}

impl CarmenScans {
    /// Opens `path` (plain, gzip or bzip2).
    pub fn open(path: &Path, laser: LaserChoice, config: CarmenConfig) -> Result<Self> {
        Ok(Self::new(CarmenReader::open_with(path, config)?, laser))
    }

    /// The scans of an open reader.
    pub fn new(reader: CarmenReader, laser: LaserChoice) -> Self {
        let name = reader.path().to_path_buf();
        Self {
            reader: Some(reader),
            name,
            laser,
            robot_lasers: Vec::new(),
            seen_flaser: false,
            drained: Vec::new().into_iter(),
            warnings: Vec::new(),
        }
    }

    fn wanted(&mut self, m: LaserMessage) -> Option<LaserMessage> {
        match (self.laser, m.kind) {
            (LaserChoice::Any, _) => Some(m),
            (LaserChoice::Rear, LaserKind::Rear) => Some(m),
            (LaserChoice::Rear, _) => None,
            (LaserChoice::Front, LaserKind::Front) => {
                self.seen_flaser = true;
                self.robot_lasers.clear();
                Some(m)
            }
            (LaserChoice::Front, LaserKind::RobotLaser1) => {
                if !self.seen_flaser {
                    self.robot_lasers.push(m);
                }
                None
            }
            (LaserChoice::Front, LaserKind::Rear) => None,
        }
    }
}

impl Iterator for CarmenScans {
    type Item = Result<PlanarFrame>;

    fn next(&mut self) -> Option<Self::Item> {
        if let Some(m) = self.drained.next() {
            return Some(Ok(PlanarFrame::from_carmen(m)));
        }
        loop {
            let reader = self.reader.as_mut()?;
            let record = reader.next();
            for warning in reader.take_warnings() {
                log::warn!("{warning}");
                self.warnings.push(warning);
            }
            match record {
                Some(Ok(Record::Laser(m))) => {
                    if let Some(m) = self.wanted(m) {
                        return Some(Ok(PlanarFrame::from_carmen(m)));
                    }
                }
                Some(Ok(_)) => {}
                Some(Err(e)) => return Some(Err(e)),
                None => {
                    self.reader = None;
                    // A front-laser log without FLASER: its ROBOTLASER1 scans.
                    self.drained = std::mem::take(&mut self.robot_lasers).into_iter();
                    return self.drained.next().map(|m| Ok(PlanarFrame::from_carmen(m)));
                }
            }
        }
    }
}

impl PlanarSource for CarmenScans {
    fn name(&self) -> &Path {
        &self.name
    }

    fn warnings(&self) -> &[String] {
        &self.warnings
    }
}

/// Opens a planar sequence: a rosbag2 recording (its directory with `metadata.yaml`, or its
/// `.mcap` file) or a CARMEN log (plain, gzip or bzip2).
pub fn open_planar(path: &Path, options: &PlanarOptions) -> Result<Box<dyn PlanarSource>> {
    if crate::rosbag::is_bag(path)? {
        return crate::rosbag::open_planar(path, &options.topics);
    }
    Ok(Box::new(CarmenScans::open(
        path,
        options.laser,
        options.carmen,
    )?))
}

/// Reads every frame of a planar sequence; fails when there is none.
pub fn read_planar(path: &Path, options: &PlanarOptions) -> Result<Vec<PlanarFrame>> {
    let source = open_planar(path, options)?;
    let name = source.name().to_path_buf();
    let frames = source.collect::<Result<Vec<_>>>()?;
    if frames.is_empty() {
        return Err(Error::UnknownFormat {
            path: name,
            reason: match options.laser {
                LaserChoice::Front => "no front-laser scans (FLASER or ROBOTLASER1)".into(),
                LaserChoice::Rear => "no rear-laser scans (RLASER)".into(),
                LaserChoice::Any => "no laser scans".into(),
            },
        });
    }
    Ok(frames)
}
