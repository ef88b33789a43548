//! Sources: the one way every command and evaluation reads a log or a sequence.
//!
//! * **Planar** — a sequence of timestamped planar scans with odometry and optional reference
//!   poses ([`PlanarFrame`], [`PlanarSource`]): CARMEN logs ([`CarmenScans`], with an explicit
//!   [`LaserChoice`]) and rosbag2 recordings (`sensor_msgs/msg/LaserScan`). [`open_planar`]
//!   picks the reader from the file; [`pair_reference`] joins a raw log to the reference
//!   poses of its corrected copy.
//! * **Spatial** — a sequence of timestamped 3-D sweeps with sensor poses
//!   ([`SweepSequence`]): KITTI sequences, NCLT sessions, rosbag2 recordings
//!   (`sensor_msgs/msg/PointCloud2`), or sweeps produced in memory ([`SweepSequence::from_fn`]).
//! * Trajectories ([`crate::tum`]) and pole maps ([`crate::poles_csv`]) are plain tables.
//!
//! ```no_run
//! use raypath_io::sequence::{PlanarOptions, read_planar};
//! let frames = read_planar("intel.mcap".as_ref(), &PlanarOptions::default())?;
//! println!("{} scans, first at {} s", frames.len(), frames[0].stamp_secs);
//! # Ok::<(), raypath_io::Error>(())
//! ```

mod pairing;
mod planar;
mod sweeps;
mod time_pairing;

pub use pairing::{pair_by_ranges, pair_reference};
pub use planar::{
    CarmenScans, LaserChoice, Origin, PlanarFrame, PlanarOptions, PlanarSource, open_planar,
    read_planar,
};
pub(crate) use sweeps::interpolate;
pub use sweeps::{SweepError, SweepFn, SweepFormat, SweepOptions, SweepSequence};
pub use time_pairing::{MATCH_TOLERANCE_SECS, MAX_GAP_SECS, poses_at_times};

/// Which topics and frames of a bag to read. Each `None` is chosen automatically when the bag
/// leaves one choice (one topic of the type), and is an error naming the candidates otherwise.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Topics {
    /// The `sensor_msgs/msg/LaserScan` topic (`--scan-topic`).
    pub scan: Option<String>,
    /// The `sensor_msgs/msg/PointCloud2` topic (`--cloud-topic`).
    pub cloud: Option<String>,
    /// The `nav_msgs/msg/Odometry` topic (`--odom-topic`).
    pub odom: Option<String>,
    /// The `geometry_msgs/msg/PoseStamped` topic with reference poses (`--reference-topic`).
    pub reference: Option<String>,
    /// The fixed (odometry) frame of the tf tree the sensor poses are expressed in
    /// (`--frame`); by default the odometry's `header.frame_id`, else the tf tree's root.
    pub frame: Option<String>,
}
