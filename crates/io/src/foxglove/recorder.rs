//! [`Recorder`]: an MCAP file of Foxglove messages, one channel per topic.

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use mcap::records::MessageHeader;
use raypath_geometry::{PointCloud, Pose2, Pose3, Scan2};
use serde_json::Value;

use super::messages::{self, GridLayer, Rgba, Stamp};
use super::scene::{self, Entity};
use super::schemas::Schema;
use crate::{Error, Location, Result};

/// The topic of [`Recorder::transform`] messages.
pub const TF_TOPIC: &str = "/tf";

/// A channel: its id, the schema it was registered with, its next sequence number and count.
struct Channel {
    id: u16,
    schema: Schema,
    sequence: u32,
}

/// Writes a Foxglove recording: an MCAP file (zstd-compressed chunks, indexed, with summary)
/// whose channels carry Foxglove well-known schemas as JSON (schema encoding `jsonschema`,
/// message encoding `json`).
///
/// Each topic gets its channel the first time it is written, with the schema of that first
/// message; writing another kind of message to it later is an error. Every message's MCAP log
/// and publish time is its `stamp_secs` (rounded to the nanosecond), which is also its
/// `timestamp` field. Call [`Recorder::finish`] at the end: it writes the summary and reports
/// errors that dropping the recorder would swallow.
pub struct Recorder {
    writer: mcap::Writer<BufWriter<File>>,
    path: PathBuf,
    schemas: HashMap<Schema, u16>,
    channels: BTreeMap<String, Channel>,
    counts: BTreeMap<String, u64>,
    buffer: Vec<u8>,
}

impl std::fmt::Debug for Recorder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recorder")
            .field("path", &self.path)
            .field("counts", &self.counts)
            .finish_non_exhaustive()
    }
}

impl Recorder {
    /// Creates (or truncates) the recording at `path`.
    pub fn create(path: &Path) -> Result<Recorder> {
        let file = File::create(path).map_err(|e| Error::io(path, Location::File, e))?;
        let options = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .profile("")
            .library(concat!("raypath-io ", env!("CARGO_PKG_VERSION")));
        let writer = options
            .create(BufWriter::new(file))
            .map_err(|e| mcap_error(path, "starting the recording", e))?;
        Ok(Recorder {
            writer,
            path: path.to_path_buf(),
            schemas: HashMap::new(),
            channels: BTreeMap::new(),
            counts: BTreeMap::new(),
            buffer: Vec::new(),
        })
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Messages written so far, per topic.
    pub fn message_counts(&self) -> &BTreeMap<String, u64> {
        &self.counts
    }

    /// Writes a 2-D map layer as `foxglove.Grid` (suggested topic `/map`).
    pub fn grid(&mut self, topic: &str, stamp_secs: f64, layer: &GridLayer<'_>) -> Result<()> {
        let stamp = self.stamp(topic, stamp_secs)?;
        let message = messages::grid_message(stamp, layer);
        self.write(topic, Schema::Grid, (stamp_secs, stamp), message)
    }

    /// Writes the finite points of `cloud`, given in `frame_id`, as `foxglove.PointCloud`
    /// (suggested topic `/points`). Missing points (non-finite coordinates, as in organized
    /// clouds) are left out. Fields: `x y z` (`FLOAT32`), then `intensity` (`FLOAT32`) and
    /// `label` (`UINT32`) when the cloud has them, then `red green blue alpha` (`UINT8`, the
    /// fields Foxglove's "RGBA (separate fields)" colour mode uses) from `colors` — one per
    /// point of the cloud, channels in `0..=1` — or else from the cloud's `rgb` (alpha 255).
    pub fn point_cloud(
        &mut self,
        topic: &str,
        stamp_secs: f64,
        frame_id: &str,
        cloud: &PointCloud,
        colors: Option<&[Rgba]>,
    ) -> Result<()> {
        let stamp = self.stamp(topic, stamp_secs)?;
        let message = messages::point_cloud_message(stamp, frame_id, cloud, colors);
        self.write(topic, Schema::PointCloud, (stamp_secs, stamp), message)
    }

    /// Writes a trajectory as `foxglove.PosesInFrame` (suggested topic `/trajectory`).
    pub fn poses(
        &mut self,
        topic: &str,
        stamp_secs: f64,
        frame_id: &str,
        poses: &[Pose3],
    ) -> Result<()> {
        let stamp = self.stamp(topic, stamp_secs)?;
        let message = Ok(messages::poses_message(stamp, frame_id, poses));
        self.write(topic, Schema::PosesInFrame, (stamp_secs, stamp), message)
    }

    /// Writes a planar trajectory (poses in the `z = 0` plane) as `foxglove.PosesInFrame`.
    pub fn planar_poses(
        &mut self,
        topic: &str,
        stamp_secs: f64,
        frame_id: &str,
        poses: &[Pose2],
    ) -> Result<()> {
        let poses: Vec<Pose3> = poses.iter().map(Pose2::to_pose3).collect();
        self.poses(topic, stamp_secs, frame_id, &poses)
    }

    /// Writes the transform `parent_from_child` as `foxglove.FrameTransform` on [`TF_TOPIC`]:
    /// where frame `child` is in frame `parent` at `stamp_secs`.
    pub fn transform(
        &mut self,
        stamp_secs: f64,
        parent: &str,
        child: &str,
        parent_from_child: &Pose3,
    ) -> Result<()> {
        let stamp = self.stamp(TF_TOPIC, stamp_secs)?;
        let message = Ok(messages::transform_message(
            stamp,
            parent,
            child,
            parent_from_child,
        ));
        self.write(
            TF_TOPIC,
            Schema::FrameTransform,
            (stamp_secs, stamp),
            message,
        )
    }

    /// Writes `entities`, given in `frame_id`, as one `foxglove.SceneUpdate` (suggested topics
    /// `/poles`, `/polylines`, `/planes`, `/octree`). Entities stay until an entity of the same
    /// id replaces them.
    pub fn scene(
        &mut self,
        topic: &str,
        stamp_secs: f64,
        frame_id: &str,
        entities: &[Entity],
    ) -> Result<()> {
        let stamp = self.stamp(topic, stamp_secs)?;
        let message = scene::scene_message(stamp, frame_id, entities);
        self.write(topic, Schema::SceneUpdate, (stamp_secs, stamp), message)
    }

    /// Writes `scan`, taken from `frame_from_sensor` in `frame_id`, as `foxglove.LaserScan`
    /// (suggested topic `/scan`; pass the identity and the sensor's frame to draw it through
    /// `/tf`, or the scan pose and `map` to draw it in place).
    pub fn laser_scan(
        &mut self,
        topic: &str,
        stamp_secs: f64,
        frame_id: &str,
        scan: &Scan2,
        frame_from_sensor: &Pose3,
    ) -> Result<()> {
        let stamp = self.stamp(topic, stamp_secs)?;
        let message = messages::laser_scan_message(stamp, frame_id, scan, frame_from_sensor);
        self.write(topic, Schema::LaserScan, (stamp_secs, stamp), message)
    }

    /// Finishes the file (last chunk, indexes, statistics, summary) and returns the number of
    /// messages per topic.
    pub fn finish(mut self) -> Result<BTreeMap<String, u64>> {
        self.writer
            .finish()
            .map_err(|e| mcap_error(&self.path, "finishing the recording", e))?;
        let counts = std::mem::take(&mut self.counts);
        let path = self.path.clone();
        self.writer
            .into_inner()
            .flush()
            .map_err(|e| Error::io(&path, Location::File, e))?;
        Ok(counts)
    }

    fn stamp(&self, topic: &str, stamp_secs: f64) -> Result<Stamp> {
        Stamp::from_secs(stamp_secs).map_err(|reason| self.unwritable(topic, stamp_secs, &reason))
    }

    fn unwritable(&self, topic: &str, stamp_secs: f64, reason: &str) -> Error {
        Error::Unwritable {
            path: self.path.clone(),
            reason: format!("topic {topic} at {stamp_secs} s: {reason}"),
        }
    }

    /// Checks `message` (built by `messages`), registers the channel if new, and writes it.
    fn write(
        &mut self,
        topic: &str,
        schema: Schema,
        (secs, stamp): (f64, Stamp),
        message: Result<Value, String>,
    ) -> Result<()> {
        let message = message.map_err(|reason| self.unwritable(topic, secs, &reason))?;
        if let Some(place) = messages::first_null(&message) {
            let reason = format!("{} field {} is not finite", schema.name(), &place[1..]);
            return Err(self.unwritable(topic, secs, &reason));
        }
        let channel_id = self.channel(topic, schema, secs)?;
        self.buffer.clear();
        serde_json::to_writer(&mut self.buffer, &message)
            .map_err(|e| self.unwritable(topic, secs, &e.to_string()))?;
        let channel = self
            .channels
            .get_mut(topic)
            .ok_or_else(|| Error::Unwritable {
                path: self.path.clone(),
                reason: format!("topic {topic} has no channel"),
            })?;
        let header = MessageHeader {
            channel_id,
            sequence: channel.sequence,
            log_time: stamp.nanos(),
            publish_time: stamp.nanos(),
        };
        channel.sequence = channel.sequence.wrapping_add(1);
        let what = format!("writing topic {topic} at {secs} s");
        self.writer
            .write_to_known_channel(&header, &self.buffer)
            .map_err(|e| mcap_error(&self.path, &what, e))?;
        *self.counts.entry(topic.to_owned()).or_insert(0) += 1;
        Ok(())
    }

    /// The channel of `topic`, registered with `schema` on first use.
    fn channel(&mut self, topic: &str, schema: Schema, secs: f64) -> Result<u16> {
        if let Some(channel) = self.channels.get(topic) {
            if channel.schema != schema {
                let reason = format!(
                    "the topic carries {}, not {}",
                    channel.schema.name(),
                    schema.name()
                );
                return Err(self.unwritable(topic, secs, &reason));
            }
            return Ok(channel.id);
        }
        let what = format!("adding topic {topic}");
        let schema_id = match self.schemas.get(&schema) {
            Some(&id) => id,
            None => {
                let id = self
                    .writer
                    .add_schema(schema.name(), "jsonschema", schema.text().as_bytes())
                    .map_err(|e| mcap_error(&self.path, &what, e))?;
                self.schemas.insert(schema, id);
                id
            }
        };
        let id = self
            .writer
            .add_channel(schema_id, topic, "json", &BTreeMap::new())
            .map_err(|e| mcap_error(&self.path, &what, e))?;
        self.channels.insert(
            topic.to_owned(),
            Channel {
                id,
                schema,
                sequence: 0,
            },
        );
        Ok(id)
    }
}

/// An MCAP writer error as this crate's error: I/O errors keep their source.
fn mcap_error(path: &Path, what: &str, error: mcap::McapError) -> Error {
    match error {
        mcap::McapError::Io(source) => Error::io(path, Location::File, source),
        other => Error::Unwritable {
            path: path.to_path_buf(),
            reason: format!("{what}: {other}"),
        },
    }
}
