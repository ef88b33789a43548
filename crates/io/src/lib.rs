//! # raypath-io
//!
//! Readers for the files lidar users have — CARMEN logs, KITTI and NCLT sequences, ROS 2 bags
//! (rosbag2 with MCAP storage), PCD point clouds, OctoMap trees and scan graphs, SegComp range
//! images, plain `x y z` text — and writers where round trips matter (PCD, OctoMap, CARMEN,
//! KITTI, rosbag2), plus Foxglove recordings of results.
//!
//! * **One way in.** [`sequence`] is how every command and evaluation reads a log or a
//!   sequence: timestamped planar scans with odometry and reference poses
//!   ([`sequence::open_planar`]: CARMEN logs, bags with `sensor_msgs/msg/LaserScan`) and
//!   timestamped 3-D sweeps with sensor poses ([`sequence::SweepSequence`]: KITTI, NCLT, bags
//!   with `sensor_msgs/msg/PointCloud2`). Raw-to-corrected log pairing lives there too.
//! * **ROS 2 and Foxglove.** [`rosbag`] reads and writes rosbag2 MCAP bags with no ROS
//!   installation (own CDR decoder; the message types and what is ignored are listed there);
//!   [`foxglove`] writes results as an MCAP that Foxglove opens with no plugin; [`convert`]
//!   turns CARMEN logs, KITTI sequences and PCD files into bags and back.
//! * **Images.** [`images`] lists the PNG/JPEG files of a folder in name order and decodes
//!   them as 8-bit grey, one at a time (camera place recognition).
//! * **Ouster.** [`ouster`] decodes Ouster lidar packets from pcap/pcapng captures with the
//!   sensor's metadata JSON into organized range images and point clouds with reflectivity.
//!
//! * **Streaming.** Logs and packet streams are read record by record through iterators;
//!   a 100 MB log never sits in memory whole. gzip and bzip2 are recognized by their first
//!   bytes and decompressed on the fly; Unix `compress` (`.Z`, the SegComp packaging) is
//!   decompressed into memory on opening.
//! * **Typed records** in raypath's geometry types: [`raypath_geometry::Scan2`] and
//!   [`raypath_geometry::Pose2`] for 2-D logs, [`raypath_geometry::PointCloud`] and
//!   [`raypath_geometry::Pose3`] for 3-D data, in REP-103 frames, metres, radians and seconds.
//! * **Errors name the place.** Malformed, truncated or mutated input gives an [`Error`] that
//!   prints as `file:line: reason` or `file: byte N: reason`. No reader panics on any input;
//!   property tests feed each one thousands of truncated and mutated files, and
//!   `cargo xtask fuzz` 10⁵ more per reader, all starting from the small valid files of
//!   [`samples`] (usable in your own tests too).
//!
//! ## Conventions
//!
//! Besides `open(path)`/`read_*(path)`, every reader has an in-memory entry point that takes
//! the data first (a byte slice, or any `impl BufRead + Send + 'static` / `impl Read`, no boxing
//! needed), then the name used in error messages, then options — as in
//! [`kitti::parse_velodyne`]`(bytes, name)` and
//! [`carmen::CarmenReader::with_config`]`(reader, name, config)`; writers likewise take the sink,
//! the data, the name, then options. Errors print as `name:line: reason` for text and
//! `name: byte N: reason` for binary data.
//!
//! ## Usage
//!
//! ```no_run
//! use raypath_io::{Format, summarize};
//! let path = std::path::Path::new("datasets/carmen/corrected/intel-corrected.log.gz");
//! assert_eq!(Format::detect(path)?, Format::Carmen);
//! let summary = summarize(path)?;
//! println!("{} scans of {:?} beams", summary.scans.unwrap_or(0), summary.beams);
//! # Ok::<(), raypath_io::Error>(())
//! ```

mod detect;
mod error;
mod numbered_files;
mod summary;

pub mod carmen;
pub mod convert;
pub mod data;
pub mod foxglove;
pub mod images;
pub mod kitti;
pub mod lzw;
pub mod nclt;
pub mod octomap;
pub mod ouster;
pub mod pcd;
pub mod point_csv;
pub mod poles_csv;
pub mod relations;
pub mod rosbag;
pub mod samples;
pub mod segcomp;
pub mod sequence;
pub mod source;
pub mod tum;
pub mod xyz;

pub use detect::{Format, read_cloud, summarize, summarize_as};
pub use error::{Error, Location, Result};
pub use summary::{BoundingBox, Summary, TimeSpan};
