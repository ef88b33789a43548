//! Foxglove recordings: results written as an MCAP file that Foxglove opens with no plugin.
//!
//! A [`Recorder`] writes maps, scans, point clouds, trajectories, transforms and map features
//! as messages of Foxglove's *well-known schemas* (<https://docs.foxglove.dev>, "Message
//! schemas"; field definitions from the foxglove-sdk repository, `schemas/jsonschema`):
//!
//! | schema | written by | what |
//! | --- | --- | --- |
//! | `foxglove.Grid` | [`Recorder::grid`] | 2-D maps (occupancy, reflection probability, intensity): one `UINT8` or `FLOAT32` field per cell |
//! | `foxglove.LaserScan` | [`Recorder::laser_scan`] | planar scans ([`raypath_geometry::Scan2`]) |
//! | `foxglove.PointCloud` | [`Recorder::point_cloud`] | 3-D scans and maps: `x y z` (`FLOAT32`), `intensity`, `label`, `red green blue alpha` |
//! | `foxglove.PosesInFrame` | [`Recorder::poses`], [`Recorder::planar_poses`] | trajectories |
//! | `foxglove.FrameTransform` | [`Recorder::transform`] | the tf tree (`map → base_link` per stamp) |
//! | `foxglove.SceneUpdate` | [`Recorder::scene`] | poles (cylinders), polylines (line strips/lists), planes (triangle lists, outlines), octree leaves (cubes) |
//!
//! ## Why JSON schema encoding
//!
//! Each channel's schema has encoding `jsonschema` and its messages encoding `json`. Foxglove
//! recognises a channel by the schema *name* (`foxglove.Grid` …) whatever the encoding, and
//! reads JSON natively; byte fields (`Grid.data`, `PointCloud.data`) are base64 strings marked
//! `"contentEncoding": "base64"` in the schema, as Foxglove's documentation asks. The schema
//! texts are written by us ([`Schema::json_schema`]) with Foxglove's field names and types.
//! The alternatives were heavier: the `foxglove` crate brings a WebSocket server, tokio and
//! protobuf tooling we do not need, and protobuf encoding needs a `FileDescriptorSet` per
//! schema and `prost`. JSON costs size — a base64 point cloud is 4/3 of its bytes, and zstd
//! chunk compression recovers much of that — and is readable by any MCAP tool
//! (`mcap cat --json`, the Python `mcap` reader) and checkable by any JSON Schema validator.
//!
//! ## Viewing a recording
//!
//! In Foxglove: *File → Open local file…* (or drag the `.mcap` onto the window), add a *3D*
//! panel, and tick the topics in its settings. Set the panel's *Display frame* to `map`; frames
//! are joined through the `/tf` transforms, so a scan in `base_link` is drawn where the robot
//! was. Results stamped with the run's last time show once the playhead reaches the end; a
//! *Raw Messages* panel shows any message's fields.
//!
//! ## What is written how
//!
//! * Every message's MCAP log time is its `timestamp` (seconds rounded to the nanosecond);
//!   negative or non-finite times, NaN coordinates and mismatched lengths are errors naming
//!   the file, topic and time, and nothing is written for them.
//! * `foxglove.LaserScan` has no range limits and JSON no infinities: no-returns (see
//!   [`raypath_geometry::Scan2::range`]) are written as range 0, drawn at the sensor.
//! * Grids keep NaN cells of `FLOAT32` layers (bytes, not JSON numbers).
//! * Large octrees are better written as a point cloud of leaf centres than as one cube per
//!   leaf (a cube is about 200 bytes of JSON).
//!
//! ## Topics and frames
//!
//! The raypath commands use these names (constants in [`topic`] and [`frame`]):
//!
//! | topic | schema | content |
//! | --- | --- | --- |
//! | `/map` | Grid | the 2-D map (one message at the end, or one per update) |
//! | `/scan` | LaserScan | the scans, in `base_link` (or the laser's frame) at their stamps |
//! | `/points` | PointCloud | 3-D scans, planes coloured by label |
//! | `/trajectory` | PosesInFrame | the estimated trajectory in `map` |
//! | `/tf` | FrameTransform | `map → base_link` per scan |
//! | `/poles` | SceneUpdate | poles as cylinders |
//! | `/polylines` | SceneUpdate | polylines as line strips |
//! | `/planes` | SceneUpdate | planes as triangle lists and outlines |
//! | `/octree` | SceneUpdate | occupied octree leaves as cubes |
//! | `/map_points` | PointCloud | occupied cells of 3-D maps and octrees |
//! | `/ground_truth` | PosesInFrame | the reference trajectory |
//! | `/loops` | SceneUpdate | loop closures as a line list |
//! | `/reflectivity` | Grid | the reflectivity map of scan matching |
//! | `/baseline` | Grid | the grid baseline beside a DCT map |
//!
//! Frames follow REP-103 and REP-105: `map` (the world), `base_link` (the robot); a
//! transform's pose is `parent_from_child` (where the child frame is in the parent frame).
//!
//! ## Example
//!
//! ```
//! use raypath_geometry::{Pose2, Scan2};
//! use raypath_io::foxglove::{Entity, Cylinder, GridLayer, GridValues, Recorder, frame, topic};
//! # let dir = tempfile::tempdir()?;
//! # let path = dir.path().join("run.mcap");
//! let mut recorder = Recorder::create(&path)?;
//! let scan = Scan2 {
//!     angle_min_rad: -1.0, angle_increment_rad: 0.5, max_range_m: 30.0,
//!     ranges: vec![2.0, 2.5, 3.0, 2.5, 2.0], intensities: None,
//! };
//! let robot = Pose2::new(1.0, 2.0, 0.3).to_pose3();
//! recorder.transform(10.0, frame::MAP, frame::BASE_LINK, &robot)?;
//! recorder.laser_scan(topic::SCAN, 10.0, frame::BASE_LINK, &scan, &Default::default())?;
//! let cells = vec![0u8, 100, 50, 255];
//! let layer = GridLayer {
//!     frame_id: frame::MAP, origin: Pose2::new(-1.0, -1.0, 0.0).to_pose3(),
//!     cell_size_m: 1.0, columns: 2, rows: 2, field: "occupancy",
//!     values: GridValues::U8(&cells),
//! };
//! recorder.grid(topic::MAP, 10.0, &layer)?;
//! let mut pole = Entity::new("pole 0");
//! pole.cylinders.push(Cylinder {
//!     base: [3.0, 1.0, 0.0].into(), diameter_m: 0.2, height_m: 2.0, color: [0.9, 0.2, 0.1, 1.0],
//! });
//! recorder.scene(topic::POLES, 10.0, frame::MAP, &[pole])?;
//! let counts = recorder.finish()?;
//! assert_eq!(counts[topic::TF], 1);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod base64;
mod messages;
mod recorder;
mod scene;
mod schemas;

#[cfg(test)]
mod tests;

pub use messages::{GridLayer, GridValues, Rgba, Stamp};
pub use recorder::{Recorder, TF_TOPIC};
pub use scene::{Cube, Cylinder, Entity, Line, LineKind, Triangles};
pub use schemas::Schema;

/// The topic names the raypath commands record to.
pub mod topic {
    /// 2-D maps (`foxglove.Grid`).
    pub const MAP: &str = "/map";
    /// Planar scans (`foxglove.LaserScan`).
    pub const SCAN: &str = "/scan";
    /// 3-D scans and maps (`foxglove.PointCloud`).
    pub const POINTS: &str = "/points";
    /// Trajectories (`foxglove.PosesInFrame`).
    pub const TRAJECTORY: &str = "/trajectory";
    /// Transforms (`foxglove.FrameTransform`), the topic of [`super::Recorder::transform`].
    pub const TF: &str = super::TF_TOPIC;
    /// Poles as cylinders (`foxglove.SceneUpdate`).
    pub const POLES: &str = "/poles";
    /// Polylines as line strips (`foxglove.SceneUpdate`).
    pub const POLYLINES: &str = "/polylines";
    /// Planes as triangle lists and outlines (`foxglove.SceneUpdate`).
    pub const PLANES: &str = "/planes";
    /// Occupied octree leaves as cubes (`foxglove.SceneUpdate`).
    pub const OCTREE: &str = "/octree";
    /// Occupied cells of 3-D maps and octrees as points (`foxglove.PointCloud`).
    pub const MAP_POINTS: &str = "/map_points";
    /// The reference trajectory (`foxglove.PosesInFrame`).
    pub const GROUND_TRUTH: &str = "/ground_truth";
    /// Detected loop closures as a line list between matched poses (`foxglove.SceneUpdate`).
    pub const LOOPS: &str = "/loops";
    /// The reflectivity map of scan matching (`foxglove.Grid`).
    pub const REFLECTIVITY: &str = "/reflectivity";
    /// The grid baseline beside a DCT map (`foxglove.Grid`).
    pub const BASELINE: &str = "/baseline";
}

/// The frame names the raypath commands record in (REP-105).
pub mod frame {
    /// The world frame of maps and trajectories.
    pub const MAP: &str = "map";
    /// The robot's body frame.
    pub const BASE_LINK: &str = "base_link";
}
