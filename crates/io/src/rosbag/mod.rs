//! rosbag2 recordings with MCAP storage: ROS 2 bags in, as planar scans or 3-D sweeps, and
//! written back out.
//!
//! A bag is given as its directory (with `metadata.yaml`, whose `relative_file_paths` name
//! the `.mcap` files and whose `storage_identifier` must be `mcap`) or as one `.mcap` file.
//! Files are streamed from disk (no memory map, never read whole): zstd and LZ4 chunks are
//! decompressed into reused buffers, several ahead on worker threads (one per core, at most
//! 4; LZ4 frames are decoded here), indexed and unindexed files are read by a linear scan, and a
//! file cut short (a recording that was not closed) gives a warning naming the place and the
//! last topic and log time read, after the messages before the cut. The header profile must
//! be `ros2` with CDR messages; a ROS 1 recording gives "not a ROS 2 bag", a bag without a
//! usable topic "no supported topics". No ROS installation is needed: CDR is decoded here
//! ([`cdr`]).
//!
//! # Message types
//!
//! | type | read as | what is ignored |
//! |---|---|---|
//! | `sensor_msgs/msg/LaserScan` | [`PlanarFrame::scan`](crate::sequence::PlanarFrame) (ranges, intensities and angles widened to `f64` by [`widen_decimal`] / [`widen_angle`]) | `angle_max` (implied by the count), `time_increment`, `scan_time` |
//! | `sensor_msgs/msg/PointCloud2` | sweeps of a [`SweepSequence`] (`x`, `y`, `z` as float32/float64; `intensity`, else `reflectivity`, of any numeric type; either byte order; any `point_step`/`row_step`) | every other field (`ring`, `time`, `rgb`, …), `is_dense` |
//! | `nav_msgs/msg/Odometry` | the robot's pose (`header.frame_id` → `child_frame_id`) | covariances, twist |
//! | `tf2_msgs/msg/TFMessage` | the tf tree (topics ending in `tf_static` are static) | — |
//! | `geometry_msgs/msg/PoseStamped` | reference poses of the robot | — |
//!
//! Other topics are counted by [`info`] and otherwise skipped without being decoded.
//!
//! **REP-117 ranges.** `+inf` (nothing within range) becomes `range_max`; `-inf` (too close),
//! NaN (invalid) and readings below `range_min` become NaN; the [`Scan2`](raypath_geometry::Scan2)
//! counts all of them, and finite readings at or above `range_max`, as no-returns
//! (`max_range_m` = `range_max`).
//!
//! **Point clouds.** Organized clouds (`height > 1`) keep their grid with NaN for missing
//! pixels; points of unorganized clouds with non-finite coordinates are dropped. Clouds are
//! ordered by header stamp; a second cloud with the same stamp is skipped with a warning.
//!
//! # Topics and frames
//!
//! * A type with exactly one topic is used; with several, the error lists them and names the
//!   option ([`Topics`](crate::sequence::Topics): `--scan-topic`, `--cloud-topic`,
//!   `--odom-topic`, `--reference-topic`). Odometry and reference topics are optional.
//! * **Robot pose** (`world_from_robot`): the odometry interpolated at the scan's header stamp
//!   (linear in position, slerp in rotation). Without an odometry topic, tf from the fixed
//!   frame to the robot frame (`base_link`, else `base_footprint`, else the sensor frame).
//!   The fixed frame is `--frame`, else the odometry's `header.frame_id`, else the root of the
//!   tf tree. Without odometry and tf, planar poses are the identity (with a warning) and
//!   sweeps have no odometry.
//! * **Sensor mounting** (`robot_from_sensor`): tf (`/tf_static` and `/tf`) from the robot
//!   frame (the odometry's `child_frame_id`) to the message's `header.frame_id`; the identity,
//!   with a warning, when tf does not connect them. `world_from_laser` = `world_from_robot ·
//!   robot_from_laser`.
//! * **Reference**: a `PoseStamped` topic holds the robot's reference pose; the reference
//!   sensor pose is it composed with the mounting.
//! * Poses are held up to 0.1 s beyond the first and last samples; messages further outside
//!   are skipped with a warning (as tf2 refuses to extrapolate). Messages whose log time goes
//!   backwards give a warning naming topic and log time; undecodable messages give an error
//!   naming file, topic and log time.
//!
//! Odometry, tf and reference poses are read in a first pass (they are small); scans are
//! streamed in a second pass and decoded on worker threads; clouds are read again on demand
//! ([`SweepSequence::sweep`]), the next ones decoded ahead. The first pass of
//! [`open_sweeps`] decompresses only the start of a chunk that ends with a cloud, so that
//! chunk's CRC is checked when the cloud is read.
//!
//! # Writing
//!
//! [`BagWriter`] writes MCAP with the `ros2` profile, `ros2msg` schemas (with dependent types
//! after `====…` / `MSG: pkg/Type` lines, as rosbag2 stores them) and CDR messages, in zstd
//! (default), LZ4 or uncompressed chunks, as one `.mcap` file or a bag directory with
//! `metadata.yaml`. [`write_planar`] and [`write_sweeps`] write whole sequences. Scans go
//! through `float32`; the reader widens a `float32` to the short decimal (at most four
//! fractional digits; for angles, degrees) that rounds to it when there is one
//! ([`widen_decimal`], [`widen_angle`]), so a CARMEN log written as a bag and read back gives
//! the same ranges and beam angles bit for bit, stamps to the nanosecond, and the same poses
//! to 1e-12 (headings pass through quaternions): `raypath map` of the bag writes the same
//! PGM as of the log, with cell statistics equal up to the last bits.
//!
//! ```no_run
//! use raypath_io::rosbag;
//! use raypath_io::sequence::Topics;
//! let path = std::path::Path::new("intel.mcap");
//! println!("{}", rosbag::info(path)?);
//! for frame in rosbag::open_planar(path, &Topics::default())? {
//!     let frame = frame?;
//!     println!("{} s: {} beams", frame.stamp_secs, frame.scan.len());
//! }
//! # Ok::<(), raypath_io::Error>(())
//! ```
//!
//! [`SweepSequence`]: crate::sequence::SweepSequence
//! [`SweepSequence::sweep`]: crate::sequence::SweepSequence::sweep

mod bag;
pub mod cdr;
mod chunk;
mod cloud;
mod info;
mod msgs;
mod planar;
mod poses;
mod reader;
mod schemas;
mod select;
mod sweeps;
mod tf;
mod write;

pub use bag::{BagFiles, MAGIC, Metadata, is_bag};
pub use cloud::{decode_cloud, encode_cloud};
pub use info::{BagInfo, TopicInfo, info};
pub use msgs::{
    Header, Odometry, Stamp, Transform, decode_odometry, decode_pose_stamped, decode_scan,
    decode_tf, encode_odometry, encode_pose_stamped, encode_scan, encode_tf, widen_angle,
    widen_decimal,
};
pub use planar::{BagScans, open_planar};
pub use sweeps::open_sweeps;
pub use write::{BagCompression, BagWriteOptions, BagWriter, names, write_planar, write_sweeps};
