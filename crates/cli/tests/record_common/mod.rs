//! Helpers of the `--record` tests: a synthetic CARMEN log, a command run with `--record`, and
//! its recording read back with the `mcap` crate (summary and every message, decoded as JSON).
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used)] // not every test uses all

use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::ops::Index;
use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::common::{json_of, raypath};

/// The path as a `&str` for the command line.
pub fn s(path: &Path) -> &str {
    path.to_str().expect("UTF-8 path")
}

/// First stamp of the synthetic log, seconds.
pub const T0: f64 = 1000.0;
/// Scans of the synthetic log.
pub const SCANS: usize = 24;

/// The synthetic log's robot (= laser) pose of scan `k`: two laps of an ellipse in the room,
/// heading along the path.
pub fn room_pose(k: usize) -> [f64; 3] {
    let phi = 2.0 * PI * k as f64 / (SCANS as f64 / 2.0);
    [1.0 + phi.cos(), 0.3 + 0.8 * phi.sin(), phi + PI / 2.0]
}

/// Range from `(x, y)` along `angle` to the walls of the room `[−3, 5] × [−2.5, 3]` m.
fn room_range(x: f64, y: f64, angle: f64) -> f64 {
    let (c, s) = (angle.cos(), angle.sin());
    let tx = if c > 1e-12 {
        (5.0 - x) / c
    } else if c < -1e-12 {
        (-3.0 - x) / c
    } else {
        f64::INFINITY
    };
    let ty = if s > 1e-12 {
        (3.0 - y) / s
    } else if s < -1e-12 {
        (-2.5 - y) / s
    } else {
        f64::INFINITY
    };
    tx.min(ty)
}

/// A CARMEN log of [`SCANS`] FLASER scans (181 beams over 180°, 0.1 s apart from [`T0`]) of
/// the room, at the poses of [`room_pose`] (laser = robot, odometry = the true poses).
pub fn room_log(dir: &Path) -> PathBuf {
    let mut text = String::from("# synthetic room\nPARAM robot_front_laser_max 20.0\n");
    for k in 0..SCANS {
        let [x, y, theta] = room_pose(k);
        let ranges: Vec<String> = (0..181)
            .map(|i| {
                let a = theta - PI / 2.0 + i as f64 * PI / 180.0;
                format!("{:.4}", room_range(x, y, a))
            })
            .collect();
        let t = T0 + 0.1 * k as f64;
        writeln!(
            text,
            "FLASER 181 {} {x} {y} {theta} {x} {y} {theta} {t} host {t}",
            ranges.join(" ")
        )
        .unwrap();
    }
    let path = dir.join("room.log");
    std::fs::write(&path, text).unwrap();
    path
}

/// One topic of a recording.
#[derive(Debug)]
pub struct Topic {
    /// The schema name (`foxglove.…`).
    pub schema: String,
    /// Its messages `(log time ns, JSON)`, in log-time order.
    pub messages: Vec<(u64, Value)>,
}

/// A recording read back: its path and its topics by name (`recording["/tf"]`).
#[derive(Debug)]
pub struct Recording {
    /// The `.mcap` file.
    pub path: PathBuf,
    /// Every topic by name.
    pub topics: BTreeMap<String, Topic>,
}

impl Index<&str> for Recording {
    type Output = Topic;

    fn index(&self, topic: &str) -> &Topic {
        &self.topics[topic]
    }
}

/// Runs `raypath ARGS --record MCAP --json`: the command's JSON document and its recording
/// read back with [`read_recording`].
pub fn record(args: &[&str], mcap: PathBuf) -> (Value, Recording) {
    let mut all = args.to_vec();
    all.extend(["--record", s(&mcap), "--json"]);
    let doc = json_of(&raypath(&all));
    (doc, read_recording(mcap))
}

/// Reads a recording and checks what every Foxglove recording must be: a summary whose message
/// counts match the messages read, schemas named `foxglove.*` with encoding `jsonschema` and a
/// JSON Schema text titled with the name, channels of encoding `json`, and each message's log
/// time equal to its `timestamp`.
pub fn read_recording(path: PathBuf) -> Recording {
    let bytes = std::fs::read(&path).expect("the recording exists");
    let summary = mcap::Summary::read(&bytes)
        .expect("a readable summary")
        .expect("a summary");
    let stats = summary.stats.as_ref().expect("statistics");
    for schema in summary.schemas.values() {
        assert!(schema.name.starts_with("foxglove."), "{}", schema.name);
        assert_eq!(schema.encoding, "jsonschema", "{}", schema.name);
        let text: Value = serde_json::from_slice(&schema.data).expect("a JSON schema");
        assert_eq!(text["title"], schema.name.as_str());
    }
    let mut topics: BTreeMap<String, Topic> = BTreeMap::new();
    for message in mcap::MessageStream::new(&bytes).expect("a readable file") {
        let message = message.expect("a readable message");
        let channel = &message.channel;
        assert_eq!(channel.message_encoding, "json", "{}", channel.topic);
        let schema = channel.schema.as_ref().expect("a schema");
        let value: Value = serde_json::from_slice(&message.data).expect("a JSON message");
        if let Some(nanos) = stamp_nanos(&value) {
            assert_eq!(nanos, message.log_time, "{}", channel.topic);
        }
        topics
            .entry(channel.topic.clone())
            .or_insert_with(|| Topic {
                schema: schema.name.clone(),
                messages: Vec::new(),
            })
            .messages
            .push((message.log_time, value));
    }
    for channel in summary.channels.values() {
        let counted = stats
            .channel_message_counts
            .get(&channel.id)
            .copied()
            .unwrap_or(0);
        let read = topics.get(&channel.topic).map_or(0, |t| t.messages.len());
        assert_eq!(counted, read as u64, "{}", channel.topic);
    }
    for topic in topics.values_mut() {
        topic.messages.sort_by_key(|(t, _)| *t);
    }
    Recording { path, topics }
}

fn stamp_nanos(message: &Value) -> Option<u64> {
    let stamp = message
        .get("timestamp")
        .or_else(|| message.pointer("/entities/0/timestamp"))?;
    Some(stamp["sec"].as_u64()? * 1_000_000_000 + stamp["nsec"].as_u64()?)
}

/// The topics of a recording along a trajectory: `n` transforms and `n` messages of `sensor`,
/// the trajectory, and one message of `result`.
pub fn along(sensor: &'static str, n: usize, result: &'static str) -> Vec<(&'static str, usize)> {
    vec![("/tf", n), (sensor, n), ("/trajectory", 1), (result, 1)]
}

/// The Foxglove schema (`foxglove.` left off) the commands record each topic with.
fn schema_of(topic: &str) -> &'static str {
    match topic {
        "/tf" => "FrameTransform",
        "/scan" => "LaserScan",
        "/points" | "/map_points" => "PointCloud",
        "/trajectory" | "/ground_truth" => "PosesInFrame",
        "/map" | "/baseline" => "Grid",
        "/polylines" | "/loops" | "/poles" | "/octree" | "/planes" => "SceneUpdate",
        other => panic!("no schema known for {other}"),
    }
}

impl Recording {
    /// Checks the topics and their message counts exactly, each topic's schema against
    /// [`schema_of`], and that the command's JSON `record` key names this file and the same
    /// counts.
    pub fn expect_topics(&self, doc: &Value, expected: &[(&str, usize)]) {
        let got: Vec<(String, String, usize)> = self
            .topics
            .iter()
            .map(|(t, topic)| (t.clone(), topic.schema.clone(), topic.messages.len()))
            .collect();
        let mut want: Vec<(String, String, usize)> = expected
            .iter()
            .map(|(t, n)| (t.to_string(), format!("foxglove.{}", schema_of(t)), *n))
            .collect();
        want.sort();
        assert_eq!(got, want);
        let record = &doc["record"];
        assert_eq!(record["path"], s(&self.path), "{doc}");
        let counts: BTreeMap<String, usize> =
            serde_json::from_value(record["messages"].clone()).unwrap();
        let want: BTreeMap<String, usize> =
            expected.iter().map(|(t, n)| (t.to_string(), *n)).collect();
        assert_eq!(counts, want);
    }

    /// The first message of `topic`.
    pub fn first(&self, topic: &str) -> &Value {
        &self[topic].messages[0].1
    }
}

/// Decodes standard base64 (with padding).
pub fn base64(text: &str) -> Vec<u8> {
    let value = |c: u8| -> u32 {
        match c {
            b'A'..=b'Z' => u32::from(c - b'A'),
            b'a'..=b'z' => u32::from(c - b'a') + 26,
            b'0'..=b'9' => u32::from(c - b'0') + 52,
            b'+' => 62,
            b'/' => 63,
            _ => panic!("not base64: {c}"),
        }
    };
    let mut out = Vec::with_capacity(text.len() / 4 * 3);
    for chunk in text.as_bytes().chunks(4) {
        let pad = chunk.iter().filter(|&&c| c == b'=').count();
        let n = chunk.iter().fold(0u32, |n, &c| {
            (n << 6) | if c == b'=' { 0 } else { value(c) }
        });
        let bytes = n.to_be_bytes();
        out.extend_from_slice(&bytes[1..4 - pad]);
    }
    out
}

/// The `FLOAT32` cells of a `foxglove.Grid` message (its first field), with its column and
/// row counts.
pub fn grid_cells(grid: &Value) -> (usize, usize, Vec<f32>) {
    let data = base64(grid["data"].as_str().unwrap());
    assert_eq!(grid["fields"][0]["type"], 7, "FLOAT32");
    assert_eq!(grid["cell_stride"], 4);
    let columns = grid["column_count"].as_u64().unwrap() as usize;
    let row_stride = grid["row_stride"].as_u64().unwrap() as usize;
    assert_eq!(row_stride, 4 * columns);
    assert_eq!(data.len() % row_stride, 0);
    let cells = data
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    (columns, data.len() / row_stride, cells)
}

/// The points of a `foxglove.PointCloud` message: per point, each field by name as `f64`.
pub fn cloud_points(cloud: &Value) -> Vec<BTreeMap<String, f64>> {
    let data = base64(cloud["data"].as_str().unwrap());
    let stride = cloud["point_stride"].as_u64().unwrap() as usize;
    assert_eq!(data.len() % stride, 0);
    let fields = cloud["fields"].as_array().unwrap();
    data.chunks_exact(stride)
        .map(|p| {
            fields
                .iter()
                .map(|f| {
                    let at = f["offset"].as_u64().unwrap() as usize;
                    let v = match f["type"].as_u64().unwrap() {
                        1 => f64::from(p[at]),
                        5 => f64::from(u32::from_le_bytes(p[at..at + 4].try_into().unwrap())),
                        7 => f64::from(f32::from_le_bytes(p[at..at + 4].try_into().unwrap())),
                        other => panic!("numeric type {other}"),
                    };
                    (f["name"].as_str().unwrap().to_owned(), v)
                })
                .collect()
        })
        .collect()
}

/// `(x, y)` of a JSON `position`/`translation`.
pub fn xy(v: &Value) -> (f64, f64) {
    (v["x"].as_f64().unwrap(), v["y"].as_f64().unwrap())
}
