//! The input options of every command that reads a log or a sequence, and the few steps from
//! a source of [`raypath_io::sequence`] to what the commands use.
//!
//! Every such command flattens [`SourceArgs`] into its arguments and opens its input through
//! [`raypath_io::sequence`]: planar scans with [`SourceArgs::open_planar`] (a CARMEN log or a
//! rosbag2 bag's `sensor_msgs/msg/LaserScan` topic), 3-D sweeps with
//! [`SourceArgs::open_sweeps`] (a KITTI sequence, an NCLT session or a bag's
//! `sensor_msgs/msg/PointCloud2` topic), and a bag that could be either with
//! [`SourceArgs::open_bag`].

use std::path::Path;

use raypath_geometry::{Pose2, Pose3};
use raypath_io::carmen::CarmenConfig;
use raypath_io::sequence::{
    LaserChoice, Origin, PlanarFrame, PlanarOptions, PlanarSource, SweepOptions, SweepSequence,
    Topics,
};

/// `--laser`: which laser of a CARMEN log to read.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Laser {
    /// `FLASER` lines, or `ROBOTLASER1` lines when the log has no `FLASER`.
    #[default]
    Front,
    /// `RLASER` lines.
    Rear,
    /// Every laser line (`FLASER`, `RLASER`, `ROBOTLASER1`) in file order.
    Any,
}

impl From<Laser> for LaserChoice {
    fn from(laser: Laser) -> Self {
        match laser {
            Laser::Front => LaserChoice::Front,
            Laser::Rear => LaserChoice::Rear,
            Laser::Any => LaserChoice::Any,
        }
    }
}

/// How to read a log or a sequence: the laser of a CARMEN log, and the topics and frame of a
/// rosbag2 bag (a directory with `metadata.yaml`, or an `.mcap` file). Topics left out are
/// chosen automatically when the bag has one of the type.
#[derive(clap::Args, Clone, Debug, Default)]
#[command(next_help_heading = "Input (CARMEN logs, rosbag2 bags)")]
pub struct SourceArgs {
    /// CARMEN logs: the laser to read.
    #[arg(long, value_enum, default_value_t = Laser::Front, value_name = "LASER")]
    pub laser: Laser,
    /// Bags: the sensor_msgs/msg/LaserScan topic (default: the bag's only one).
    #[arg(long, value_name = "TOPIC")]
    pub scan_topic: Option<String>,
    /// Bags: the sensor_msgs/msg/PointCloud2 topic (default: the bag's only one).
    #[arg(long, value_name = "TOPIC")]
    pub cloud_topic: Option<String>,
    /// Bags: the nav_msgs/msg/Odometry topic (default: the bag's only one, if any).
    #[arg(long, value_name = "TOPIC")]
    pub odom_topic: Option<String>,
    /// Bags: the geometry_msgs/msg/PoseStamped topic of reference (ground-truth) poses
    /// (default: the bag's only one, if any).
    #[arg(long, value_name = "TOPIC")]
    pub reference_topic: Option<String>,
    /// Bags: the fixed frame of the sensor poses (default: the odometry's frame_id, else the
    /// root of the tf tree).
    #[arg(long, value_name = "FRAME")]
    pub frame: Option<String>,
    /// CARMEN logs: refuse a log that ends mid-line (by default its last, incomplete line is
    /// skipped with a warning naming the line, and the complete records are read).
    #[arg(long)]
    pub strict: bool,
}

/// A bag opened as planar scans or as 3-D sweeps (see [`SourceArgs::open_bag`]).
pub enum BagSource {
    /// Its `sensor_msgs/msg/LaserScan` topic.
    Planar(Box<dyn PlanarSource>),
    /// Its `sensor_msgs/msg/PointCloud2` topic.
    Sweeps(Box<SweepSequence>),
}

impl SourceArgs {
    /// The bag topics and frame.
    pub fn topics(&self) -> Topics {
        Topics {
            scan: self.scan_topic.clone(),
            cloud: self.cloud_topic.clone(),
            odom: self.odom_topic.clone(),
            reference: self.reference_topic.clone(),
            frame: self.frame.clone(),
        }
    }

    /// The options of [`raypath_io::sequence::open_planar`].
    pub fn planar_options(&self) -> PlanarOptions {
        PlanarOptions {
            laser: self.laser.into(),
            carmen: CarmenConfig {
                strict: self.strict,
                ..CarmenConfig::default()
            },
            topics: self.topics(),
        }
    }

    /// The options of [`SweepSequence::open`].
    pub fn sweep_options(&self) -> SweepOptions {
        SweepOptions {
            topics: self.topics(),
        }
    }

    /// Opens planar scans: a CARMEN log (plain, gzip or bzip2) or a bag.
    pub fn open_planar(&self, path: &Path) -> raypath_io::Result<Box<dyn PlanarSource>> {
        raypath_io::sequence::open_planar(path, &self.planar_options())
    }

    /// Reads every frame of a planar source; an empty list when it has none (the commands
    /// say what they missed, see [`SourceArgs::laser_lines`]).
    pub fn read_frames(&self, path: &Path) -> raypath_io::Result<Vec<PlanarFrame>> {
        self.open_planar(path)?.collect()
    }

    /// Opens 3-D sweeps: a KITTI sequence, an NCLT session or a bag.
    pub fn open_sweeps(&self, path: &Path) -> raypath_io::Result<SweepSequence> {
        SweepSequence::open(path, &self.sweep_options())
    }

    /// Opens a bag as planar scans or as 3-D sweeps: sweeps with `--cloud-topic`, scans with
    /// `--scan-topic`; otherwise its LaserScan topic, else its PointCloud2 topic. Errors name
    /// the bag (and, when neither opens, both reasons).
    pub fn open_bag(&self, path: &Path) -> Result<BagSource, String> {
        if self.cloud_topic.is_some() && self.scan_topic.is_none() {
            return self
                .open_sweeps(path)
                .map(|s| BagSource::Sweeps(Box::new(s)))
                .map_err(|e| e.to_string());
        }
        let planar = match self.open_planar(path) {
            Ok(source) => return Ok(BagSource::Planar(source)),
            Err(e) if self.scan_topic.is_some() => return Err(e.to_string()),
            Err(e) => e.to_string(),
        };
        match self.open_sweeps(path) {
            Ok(sweeps) => Ok(BagSource::Sweeps(Box::new(sweeps))),
            Err(e) if e.to_string() == planar => Err(planar),
            Err(e) => Err(format!("{planar}; as point clouds: {e}")),
        }
    }

    /// The laser lines `--laser` reads, for messages.
    pub fn laser_lines(&self) -> &'static str {
        match self.laser {
            Laser::Front => "FLASER or ROBOTLASER1",
            Laser::Rear => "RLASER",
            Laser::Any => "FLASER, RLASER or ROBOTLASER1",
        }
    }
}

/// True when `path` is a rosbag2 bag; an unreadable path is not (its reader says why).
pub fn is_bag(path: &Path) -> bool {
    raypath_io::rosbag::is_bag(path).unwrap_or(false)
}

/// `file:line` or `file: log time …` of a frame, for messages.
pub fn place(name: &Path, origin: Origin) -> String {
    match origin {
        Origin::Line(line) => format!("{}:{line}", name.display()),
        Origin::LogTimeNs(_) => format!("{}: {origin}", name.display()),
    }
}

/// The `world_from_laser` poses a planar source gives as the truth, per frame: its reference
/// poses when any frame has one (a bag's reference topic, a paired corrected log; frames
/// without one get `None`), else the logged poses (the poses of a `*-corrected` CARMEN log are
/// its reference).
pub fn reference_track(frames: &[PlanarFrame]) -> Vec<Option<Pose2>> {
    if frames.iter().any(|f| f.reference.is_some()) {
        frames.iter().map(|f| f.reference).collect()
    } else {
        frames.iter().map(|f| Some(f.world_from_laser)).collect()
    }
}

/// The `world_from_sensor` poses of a sweep sequence: the reference poses, else the odometry
/// (`None` when it has neither). The second value is true for the odometry.
pub fn sweep_poses(sequence: &SweepSequence) -> Option<(&[Pose3], bool)> {
    match (&sequence.reference, &sequence.odometry) {
        (Some(reference), _) => Some((reference, false)),
        (None, Some(odometry)) => Some((odometry, true)),
        (None, None) => None,
    }
}
