//! Message types, topic choice and the first pass over a bag (odometry, tf, reference poses
//! and, for point clouds, where each cloud is).

use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::sync::Arc;

use super::bag::BagFiles;
use super::msgs::{self, Stamp};
use super::reader::{ChannelInfo, Classify, McapReader, MessageLoc};
use super::tf::{TfTree, Track};
use crate::error::{Error, Location, Result};

/// `sensor_msgs/msg/LaserScan`.
pub const LASER_SCAN: &str = "sensor_msgs/msg/LaserScan";
/// `sensor_msgs/msg/PointCloud2`.
pub const POINT_CLOUD2: &str = "sensor_msgs/msg/PointCloud2";
/// `nav_msgs/msg/Odometry`.
pub const ODOMETRY: &str = "nav_msgs/msg/Odometry";
/// `tf2_msgs/msg/TFMessage`.
pub const TF_MESSAGE: &str = "tf2_msgs/msg/TFMessage";
/// `geometry_msgs/msg/PoseStamped`.
pub const POSE_STAMPED: &str = "geometry_msgs/msg/PoseStamped";

/// Roles of channels.
pub const ROLE_SCAN: u8 = 1;
/// Point clouds.
pub const ROLE_CLOUD: u8 = 2;
/// Odometry.
pub const ROLE_ODOM: u8 = 3;
/// `/tf`.
pub const ROLE_TF: u8 = 4;
/// `/tf_static`.
pub const ROLE_TF_STATIC: u8 = 5;
/// Reference poses.
pub const ROLE_POSE: u8 = 6;

/// `pkg/Type` → `pkg/msg/Type`; other names as they are.
pub fn normalize_type(name: &str) -> String {
    match name.split('/').collect::<Vec<_>>().as_slice() {
        [pkg, ty] => format!("{pkg}/msg/{ty}"),
        _ => name.to_string(),
    }
}

/// True for channels raypath can decode: CDR messages with a ROS 2 schema.
pub fn is_ros2(c: &ChannelInfo) -> bool {
    c.message_encoding == "cdr" && matches!(c.schema_encoding.as_str(), "ros2msg" | "ros2idl" | "")
}

fn is_tf_static(topic: &str) -> bool {
    topic.ends_with("tf_static")
}

/// The role of a channel for the first pass (odometry, tf, poses; clouds when asked).
pub fn first_pass_role(c: &ChannelInfo, clouds: bool) -> Option<u8> {
    if !is_ros2(c) {
        return None;
    }
    match normalize_type(&c.schema_name).as_str() {
        ODOMETRY => Some(ROLE_ODOM),
        TF_MESSAGE if is_tf_static(&c.topic) => Some(ROLE_TF_STATIC),
        TF_MESSAGE => Some(ROLE_TF),
        POSE_STAMPED => Some(ROLE_POSE),
        POINT_CLOUD2 if clouds => Some(ROLE_CLOUD),
        _ => None,
    }
}

/// An error about a message: file, its record, topic and log time.
pub fn message_error(
    file: &Path,
    loc: MessageLoc,
    topic: &str,
    log_time: u64,
    reason: impl std::fmt::Display,
) -> Error {
    Error::malformed(
        file,
        Location::Byte(loc.record_offset),
        format!(
            "{topic} at log time {:.9} s: {reason}",
            log_time as f64 * 1e-9
        ),
    )
}

/// An odometry topic's poses.
#[derive(Clone, Debug, Default)]
pub struct OdomTrack {
    /// `header.frame_id` of the first message.
    pub frame_id: String,
    /// `child_frame_id` of the first message.
    pub child_frame_id: String,
    /// `frame_id_from_child` in time.
    pub track: Track,
}

/// Where a point cloud is.
#[derive(Clone, Debug)]
pub struct CloudRef {
    /// Header stamp.
    pub stamp: Stamp,
    /// Header frame.
    pub frame_id: Arc<str>,
    /// Log time, nanoseconds.
    pub log_time: u64,
    /// Place in the file.
    pub loc: MessageLoc,
}

/// What the first pass found.
#[derive(Debug, Default)]
pub struct FirstPass {
    /// Topic → (normalized type, message count, message encoding) of every channel.
    pub topics: BTreeMap<String, (String, u64, String)>,
    /// The header profiles of the files.
    pub profiles: Vec<String>,
    /// Odometry per topic.
    pub odom: BTreeMap<String, OdomTrack>,
    /// Reference poses per topic: (frame id, track).
    pub poses: BTreeMap<String, (String, Track)>,
    /// The tf tree of every `TFMessage` topic.
    pub tf: TfTree,
    /// Clouds per topic, in file order.
    pub clouds: BTreeMap<String, Vec<CloudRef>>,
    /// Warnings of the readers.
    pub warnings: Vec<String>,
}

/// Reads the odometry, tf and pose topics of every file (and the places of point clouds when
/// `clouds`), counting the messages of all topics.
pub fn first_pass(bag: &BagFiles, clouds: bool) -> Result<FirstPass> {
    let mut out = FirstPass::default();
    let mut frames: HashMap<String, Arc<str>> = HashMap::new();
    for (k, file) in bag.files.iter().enumerate() {
        let classify: Classify = Arc::new(move |c: &ChannelInfo| first_pass_role(c, clouds));
        let mut reader = McapReader::open(file, k as u32, classify)?;
        if clouds {
            // Only the header of a cloud is needed now.
            reader.set_prefix_only(ROLE_CLOUD);
        }
        out.profiles.push(reader.profile().to_string());
        if reader.profile() == "ros1" {
            return Err(not_ros2(&bag.path, "the MCAP profile is \"ros1\""));
        }
        while let Some(m) = reader.next_message()? {
            let topic = m.topic;
            let err = |e: super::cdr::CdrError| message_error(file, m.loc, topic, m.log_time, e);
            match m.role {
                ROLE_ODOM => {
                    let o = msgs::decode_odometry(m.data).map_err(err)?;
                    let track = out
                        .odom
                        .entry(topic.to_string())
                        .or_insert_with(|| OdomTrack {
                            frame_id: o.header.frame_id.to_string(),
                            child_frame_id: o.child_frame_id.to_string(),
                            track: Track::default(),
                        });
                    track.track.push(o.header.stamp.secs(), o.pose);
                }
                ROLE_TF | ROLE_TF_STATIC => {
                    for t in msgs::decode_tf(m.data).map_err(err)? {
                        out.tf.add(&t, m.role == ROLE_TF_STATIC);
                    }
                }
                ROLE_POSE => {
                    let (h, pose) = msgs::decode_pose_stamped(m.data).map_err(err)?;
                    let entry = out
                        .poses
                        .entry(topic.to_string())
                        .or_insert_with(|| (h.frame_id.to_string(), Track::default()));
                    entry.1.push(h.stamp.secs(), pose);
                }
                ROLE_CLOUD => {
                    let h = msgs::decode_header(m.data).map_err(err)?;
                    let frame_id = frames
                        .entry(h.frame_id.to_string())
                        .or_insert_with(|| Arc::from(h.frame_id))
                        .clone();
                    out.clouds
                        .entry(topic.to_string())
                        .or_default()
                        .push(CloudRef {
                            stamp: h.stamp,
                            frame_id,
                            log_time: m.log_time,
                            loc: m.loc,
                        });
                }
                _ => {}
            }
        }
        let stats = reader.channel_stats();
        for c in reader.channels() {
            let count = stats.get(&c.id).map_or(0, |s| s.count);
            let entry = out.topics.entry(c.topic.clone()).or_insert_with(|| {
                (
                    normalize_type(&c.schema_name),
                    0,
                    c.message_encoding.clone(),
                )
            });
            entry.1 += count;
        }
        out.warnings.extend(reader.take_warnings());
        if reader.unlisted_order_warnings() > 0 {
            out.warnings.push(format!(
                "{}: {} more messages out of order",
                file.display(),
                reader.unlisted_order_warnings()
            ));
        }
    }
    for o in out.odom.values_mut() {
        o.track.finish();
    }
    for (_, track) in out.poses.values_mut() {
        track.finish();
    }
    out.tf.finish();
    out.warnings.extend(out.tf.warnings.iter().cloned());
    Ok(out)
}

/// The "not a ROS 2 bag" error.
pub fn not_ros2(path: &Path, why: &str) -> Error {
    Error::UnknownFormat {
        path: path.to_path_buf(),
        reason: format!(
            "not a ROS 2 bag: {why} (raypath reads rosbag2 recordings: MCAP profile ros2, CDR \
             messages with ros2msg schemas)"
        ),
    }
}

impl FirstPass {
    /// The topics of type `ty` with CDR messages.
    pub fn topics_of(&self, ty: &str) -> Vec<&str> {
        self.topics
            .iter()
            .filter(|(_, (t, _, enc))| t == ty && enc == "cdr")
            .map(|(name, _)| name.as_str())
            .collect()
    }

    fn listing(&self) -> String {
        if self.topics.is_empty() {
            return "the bag has no topics".into();
        }
        let list: Vec<String> = self
            .topics
            .iter()
            .map(|(name, (ty, n, enc))| format!("{name} ({ty}, {enc}, {n} messages)"))
            .collect();
        format!("topics: {}", list.join(", "))
    }

    /// Picks the topic of type `ty`: `explicit` when given (it must exist with that type), else
    /// the only one; `None` when there is none and it is not `required`.
    pub fn choose(
        &self,
        path: &Path,
        ty: &str,
        explicit: Option<&str>,
        flag: &str,
        required: bool,
    ) -> Result<Option<String>> {
        let candidates = self.topics_of(ty);
        let bad = |reason: String| Error::UnknownFormat {
            path: path.to_path_buf(),
            reason,
        };
        if let Some(want) = explicit {
            if candidates.contains(&want) {
                return Ok(Some(want.to_string()));
            }
            return Err(bad(format!(
                "{flag} {want}: no {ty} topic of that name ({ty} topics: {}; {})",
                if candidates.is_empty() {
                    "none".into()
                } else {
                    candidates.join(", ")
                },
                self.listing()
            )));
        }
        match candidates.as_slice() {
            [one] => Ok(Some(one.to_string())),
            [] if !required => Ok(None),
            [] => {
                let any_ros2 = self.topics.values().any(|(_, _, enc)| enc == "cdr");
                if !any_ros2 && !self.topics.is_empty() {
                    return Err(not_ros2(
                        path,
                        &format!("no topic has CDR messages; {}", self.listing()),
                    ));
                }
                Err(bad(format!(
                    "no supported topics: no {ty} topic ({})",
                    self.listing()
                )))
            }
            several => Err(bad(format!(
                "{} {ty} topics ({}): choose one with {flag}",
                several.len(),
                several.join(", ")
            ))),
        }
    }
}
