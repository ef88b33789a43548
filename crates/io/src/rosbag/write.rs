//! Writing rosbag2 recordings: MCAP with the `ros2` profile, `ros2msg` schemas and CDR
//! messages, chunked and compressed; optionally as a bag directory with `metadata.yaml`.

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use raypath_geometry::{PointCloud, Pose3, Scan2};

use super::cdr::CdrWriter;
use super::cloud::encode_cloud;
use super::msgs::{self, Stamp, Transform};
use super::schemas::definition;
use super::select::{LASER_SCAN, ODOMETRY, POINT_CLOUD2, POSE_STAMPED, TF_MESSAGE};
use crate::error::{Error, Location, Result};
use crate::sequence::{PlanarFrame, SweepSequence};

/// Chunk compression of a written bag.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BagCompression {
    /// zstd (rosbag2's default for compressed MCAP).
    #[default]
    Zstd,
    /// LZ4 frames.
    Lz4,
    /// Uncompressed chunks.
    None,
}

/// Options of [`BagWriter`].
#[derive(Clone, Debug)]
pub struct BagWriteOptions {
    /// Chunk compression.
    pub compression: BagCompression,
    /// Target uncompressed chunk size, bytes.
    pub chunk_size_bytes: u64,
}

impl Default for BagWriteOptions {
    fn default() -> Self {
        Self {
            compression: BagCompression::Zstd,
            chunk_size_bytes: 1 << 20,
        }
    }
}

struct Channel {
    id: u16,
    type_name: &'static str,
    count: u64,
    sequence: u32,
}

/// Writes a rosbag2 recording message by message.
///
/// A `path` ending in `.mcap` gives that one file; any other path is a bag directory
/// (created) holding `<name>_0.mcap` and a rosbag2 `metadata.yaml`.
pub struct BagWriter {
    writer: Option<mcap::Writer<BufWriter<File>>>,
    path: PathBuf,
    file: PathBuf,
    directory: bool,
    schemas: HashMap<&'static str, u16>,
    channels: BTreeMap<String, Channel>,
    cdr: CdrWriter,
    first_ns: u64,
    last_ns: u64,
}

fn log_time(path: &Path, stamp_secs: f64) -> Result<(Stamp, u64)> {
    match Stamp::from_secs(stamp_secs) {
        Some(s) if s.nanos() >= 0 => Ok((s, s.nanos() as u64)),
        _ => Err(Error::Unwritable {
            path: path.to_path_buf(),
            reason: format!(
                "time {stamp_secs} s is not a ROS time (non-negative, before 2038 in int32 \
                 seconds)"
            ),
        }),
    }
}

impl BagWriter {
    /// Creates the file (or bag directory) at `path`.
    pub fn create(path: &Path, options: &BagWriteOptions) -> Result<Self> {
        let directory = path.extension().is_none_or(|e| e != "mcap");
        let file = if directory {
            std::fs::create_dir_all(path).map_err(|e| Error::io(path, Location::File, e))?;
            let stem = path
                .file_name()
                .map_or("bag".into(), |n| n.to_string_lossy().into_owned());
            path.join(format!("{stem}_0.mcap"))
        } else {
            path.to_path_buf()
        };
        let out = File::create(&file).map_err(|e| Error::io(&file, Location::File, e))?;
        let compression = match options.compression {
            BagCompression::Zstd => Some(mcap::Compression::Zstd),
            BagCompression::Lz4 => Some(mcap::Compression::Lz4),
            BagCompression::None => None,
        };
        let writer = mcap::WriteOptions::new()
            .profile("ros2")
            .library(format!("raypath-io {}", env!("CARGO_PKG_VERSION")))
            .compression(compression)
            .chunk_size(Some(options.chunk_size_bytes.max(1024)))
            .create(BufWriter::with_capacity(1 << 20, out))
            .map_err(|e| Error::Unwritable {
                path: file.clone(),
                reason: e.to_string(),
            })?;
        Ok(Self {
            writer: Some(writer),
            path: path.to_path_buf(),
            file,
            directory,
            schemas: HashMap::new(),
            channels: BTreeMap::new(),
            cdr: CdrWriter::new(),
            first_ns: u64::MAX,
            last_ns: 0,
        })
    }

    fn fail(&self, e: impl std::fmt::Display) -> Error {
        Error::Unwritable {
            path: self.file.clone(),
            reason: e.to_string(),
        }
    }

    fn channel(&mut self, topic: &str, type_name: &'static str) -> Result<u16> {
        if let Some(c) = self.channels.get(topic) {
            if c.type_name != type_name {
                return Err(self.fail(format!(
                    "topic {topic} has type {}, not {type_name}",
                    c.type_name
                )));
            }
            return Ok(c.id);
        }
        let Some(writer) = self.writer.as_mut() else {
            return Err(self.fail("the writer has finished"));
        };
        let schema_id = match self.schemas.get(type_name) {
            Some(&id) => id,
            None => {
                let text = definition(type_name).unwrap_or_default();
                let id = writer
                    .add_schema(type_name, "ros2msg", text.as_bytes())
                    .map_err(|e| Error::Unwritable {
                        path: self.file.clone(),
                        reason: e.to_string(),
                    })?;
                self.schemas.insert(type_name, id);
                id
            }
        };
        let id = writer
            .add_channel(schema_id, topic, "cdr", &BTreeMap::new())
            .map_err(|e| Error::Unwritable {
                path: self.file.clone(),
                reason: e.to_string(),
            })?;
        self.channels.insert(
            topic.to_string(),
            Channel {
                id,
                type_name,
                count: 0,
                sequence: 0,
            },
        );
        Ok(id)
    }

    /// Writes the message serialized in `self.cdr`.
    fn emit(&mut self, topic: &str, type_name: &'static str, log_time_ns: u64) -> Result<()> {
        let id = self.channel(topic, type_name)?;
        let sequence = match self.channels.get_mut(topic) {
            Some(c) => {
                c.count += 1;
                c.sequence = c.sequence.wrapping_add(1);
                c.sequence
            }
            None => 0,
        };
        self.first_ns = self.first_ns.min(log_time_ns);
        self.last_ns = self.last_ns.max(log_time_ns);
        let header = mcap::records::MessageHeader {
            channel_id: id,
            sequence,
            log_time: log_time_ns,
            publish_time: log_time_ns,
        };
        let Some(writer) = self.writer.as_mut() else {
            return Err(self.fail("the writer has finished"));
        };
        writer
            .write_to_known_channel(&header, self.cdr.bytes())
            .map_err(|e| Error::Unwritable {
                path: self.file.clone(),
                reason: e.to_string(),
            })
    }

    /// Writes a `sensor_msgs/msg/LaserScan` (see [`super::msgs::encode_scan`]).
    pub fn write_scan(
        &mut self,
        topic: &str,
        stamp_secs: f64,
        frame_id: &str,
        scan: &Scan2,
    ) -> Result<()> {
        let (stamp, ns) = log_time(&self.file, stamp_secs)?;
        self.cdr.reset();
        msgs::encode_scan(&mut self.cdr, stamp, frame_id, scan);
        self.emit(topic, LASER_SCAN, ns)
    }

    /// Writes a `nav_msgs/msg/Odometry` with pose `frame_id_from_child` (zero covariance and
    /// twist).
    pub fn write_odometry(
        &mut self,
        topic: &str,
        stamp_secs: f64,
        frame_id: &str,
        child_frame_id: &str,
        pose: &Pose3,
    ) -> Result<()> {
        let (stamp, ns) = log_time(&self.file, stamp_secs)?;
        self.cdr.reset();
        msgs::encode_odometry(&mut self.cdr, stamp, frame_id, child_frame_id, pose);
        self.emit(topic, ODOMETRY, ns)
    }

    /// Writes a `tf2_msgs/msg/TFMessage` logged at `log_time_secs`.
    pub fn write_tf(
        &mut self,
        topic: &str,
        log_time_secs: f64,
        transforms: &[Transform],
    ) -> Result<()> {
        let (_, ns) = log_time(&self.file, log_time_secs)?;
        self.cdr.reset();
        msgs::encode_tf(&mut self.cdr, transforms);
        self.emit(topic, TF_MESSAGE, ns)
    }

    /// Writes a `geometry_msgs/msg/PoseStamped`.
    pub fn write_pose(
        &mut self,
        topic: &str,
        stamp_secs: f64,
        frame_id: &str,
        pose: &Pose3,
    ) -> Result<()> {
        let (stamp, ns) = log_time(&self.file, stamp_secs)?;
        self.cdr.reset();
        msgs::encode_pose_stamped(&mut self.cdr, stamp, frame_id, pose);
        self.emit(topic, POSE_STAMPED, ns)
    }

    /// Writes a `sensor_msgs/msg/PointCloud2` (see [`super::cloud::encode_cloud`]).
    pub fn write_cloud(
        &mut self,
        topic: &str,
        stamp_secs: f64,
        frame_id: &str,
        cloud: &PointCloud,
    ) -> Result<()> {
        let (stamp, ns) = log_time(&self.file, stamp_secs)?;
        self.cdr.reset();
        encode_cloud(&mut self.cdr, stamp, frame_id, cloud);
        self.emit(topic, POINT_CLOUD2, ns)
    }

    /// Writes the summary (and `metadata.yaml` for a bag directory); returns the path.
    pub fn finish(mut self) -> Result<PathBuf> {
        let Some(mut writer) = self.writer.take() else {
            return Err(self.fail("the writer has finished"));
        };
        writer.finish().map_err(|e| self.fail(e))?;
        let mut out = writer.into_inner();
        out.flush()
            .map_err(|e| Error::io(&self.file, Location::File, e))?;
        if self.directory {
            let yaml = self.metadata_yaml();
            let meta = self.path.join("metadata.yaml");
            std::fs::write(&meta, yaml).map_err(|e| Error::io(&meta, Location::File, e))?;
        }
        Ok(self.path.clone())
    }

    fn metadata_yaml(&self) -> String {
        let (start, duration) = if self.first_ns == u64::MAX {
            (0, 0)
        } else {
            (self.first_ns, self.last_ns - self.first_ns)
        };
        let total: u64 = self.channels.values().map(|c| c.count).sum();
        let name = self
            .file
            .file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned());
        let mut y = String::from("rosbag2_bagfile_information:\n  version: 5\n");
        y += "  storage_identifier: mcap\n";
        y += &format!("  duration:\n    nanoseconds: {duration}\n");
        y += &format!("  starting_time:\n    nanoseconds_since_epoch: {start}\n");
        y += &format!("  message_count: {total}\n  topics_with_message_count:\n");
        for (topic, c) in &self.channels {
            y += &format!(
                "    - topic_metadata:\n        name: {topic}\n        type: {}\n        \
                 serialization_format: cdr\n        offered_qos_profiles: \"\"\n      \
                 message_count: {}\n",
                c.type_name, c.count
            );
        }
        y += "  compression_format: \"\"\n  compression_mode: \"\"\n";
        y += &format!("  relative_file_paths:\n    - {name}\n");
        y += &format!(
            "  files:\n    - path: {name}\n      starting_time:\n        \
             nanoseconds_since_epoch: {start}\n      duration:\n        nanoseconds: \
             {duration}\n      message_count: {total}\n"
        );
        y
    }
}

/// Frame and topic names used by [`write_planar`] and [`write_sweeps`].
pub mod names {
    /// Odometry frame.
    pub const ODOM_FRAME: &str = "odom";
    /// Robot frame.
    pub const ROBOT_FRAME: &str = "base_link";
    /// Laser frame.
    pub const LASER_FRAME: &str = "laser";
    /// 3-D sensor frame.
    pub const LIDAR_FRAME: &str = "lidar";
    /// Frame of reference poses.
    pub const MAP_FRAME: &str = "map";
    /// Scans.
    pub const SCAN_TOPIC: &str = "/scan";
    /// Point clouds.
    pub const CLOUD_TOPIC: &str = "/points";
    /// Odometry.
    pub const ODOM_TOPIC: &str = "/odom";
    /// Dynamic transforms.
    pub const TF_TOPIC: &str = "/tf";
    /// Static transforms.
    pub const TF_STATIC_TOPIC: &str = "/tf_static";
    /// Reference poses.
    pub const REFERENCE_TOPIC: &str = "/reference";
}

fn transform(stamp_secs: f64, parent: &str, child: &str, pose: Pose3) -> Transform {
    Transform {
        stamp: Stamp::from_secs(stamp_secs).unwrap_or_default(),
        parent: parent.into(),
        child: child.into(),
        parent_from_child: pose,
    }
}

/// Writes planar frames as a bag: `/scan` (LaserScan, frame `laser`), `/odom` (Odometry
/// `odom` → `base_link`, the `world_from_robot` poses), `/tf` (the same transform), the
/// mounting `base_link` → `laser` on `/tf_static` when it is the same in every frame (else on
/// `/tf` with each scan), and the reference poses, when frames have them, as the robot's
/// pose on `/reference` (PoseStamped in `map`).
pub fn write_planar(
    path: &Path,
    frames: &[PlanarFrame],
    options: &BagWriteOptions,
) -> Result<PathBuf> {
    use names::*;
    let mut w = BagWriter::create(path, options)?;
    let mounts: Vec<Pose3> = frames
        .iter()
        .map(|f| f.robot_from_laser().to_pose3())
        .collect();
    let fixed_mount = mounts.windows(2).all(|m| {
        (m[0].translation() - m[1].translation()).norm() < 1e-9
            && m[0].rotation().angle_to(&m[1].rotation()) < 1e-9
    });
    if let (true, Some(first), Some(mount)) = (fixed_mount, frames.first(), mounts.first()) {
        let t = transform(first.stamp_secs, ROBOT_FRAME, LASER_FRAME, *mount);
        w.write_tf(TF_STATIC_TOPIC, first.stamp_secs, &[t])?;
    }
    for (f, mount) in frames.iter().zip(&mounts) {
        let t = f.stamp_secs;
        let robot = f.world_from_robot.to_pose3();
        w.write_odometry(ODOM_TOPIC, t, ODOM_FRAME, ROBOT_FRAME, &robot)?;
        let mut tfs = vec![transform(t, ODOM_FRAME, ROBOT_FRAME, robot)];
        if !fixed_mount {
            tfs.push(transform(t, ROBOT_FRAME, LASER_FRAME, *mount));
        }
        w.write_tf(TF_TOPIC, t, &tfs)?;
        w.write_scan(SCAN_TOPIC, t, LASER_FRAME, &f.scan)?;
        if let Some(reference) = f.reference {
            let robot_ref = reference.to_pose3() * mount.inverse();
            w.write_pose(REFERENCE_TOPIC, t, MAP_FRAME, &robot_ref)?;
        }
    }
    w.finish()
}

/// Writes a sweep sequence as a bag: `/points` (PointCloud2, frame `lidar`), the odometry
/// poses as `/tf` `odom` → `lidar`, and the reference poses as `/reference` (PoseStamped in
/// `map`).
pub fn write_sweeps(
    path: &Path,
    sweeps: &SweepSequence,
    options: &BagWriteOptions,
) -> Result<PathBuf> {
    use names::*;
    let mut w = BagWriter::create(path, options)?;
    for (i, &t) in sweeps.stamps_secs.iter().enumerate() {
        if let Some(odom) = sweeps.odometry.as_ref().and_then(|o| o.get(i)) {
            w.write_tf(TF_TOPIC, t, &[transform(t, ODOM_FRAME, LIDAR_FRAME, *odom)])?;
        }
        let cloud = sweeps.sweep(i)?;
        w.write_cloud(CLOUD_TOPIC, t, LIDAR_FRAME, &cloud)?;
        if let Some(reference) = sweeps.reference.as_ref().and_then(|r| r.get(i)) {
            w.write_pose(REFERENCE_TOPIC, t, MAP_FRAME, reference)?;
        }
    }
    w.finish()
}
