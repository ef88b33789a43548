//! `--record out.mcap`: the inputs and results of a command written as a Foxglove recording
//! through [`raypath_io::foxglove::Recorder`] (an MCAP file of Foxglove's well-known schemas,
//! JSON-encoded; open it in Foxglove with File → Open).
//!
//! Every command that produces maps, trajectories or features flattens [`RecordArgs`] into its
//! arguments, opens a [`Recording`] with [`Recording::open`] (nothing when `--record` is not
//! given), writes through the helpers below and ends with [`finish`]: with `--json` it adds
//! `"record": {"path", "messages": {topic: count}}` to the command's JSON document (all other
//! keys unchanged), else it prints one line naming the file and the messages per topic.
//!
//! Topics and frames are those of [`raypath_io::foxglove::topic`] and
//! [`raypath_io::foxglove::frame`]. Planar scans are drawn through `/tf`:
//! `map → base_link` per scan at the scan's stamp, and the `/scan` LaserScan in `base_link`
//! with the laser's mounting as its pose; 3-D sweeps the same way, their points on `/points` in
//! `base_link`, thinned to keep recordings of long drives small ([`sweep_points`]: at most
//! [`MAX_SWEEP_POINTS`] a sweep and about [`SWEEP_POINT_BUDGET`] in all; a point costs about
//! 16 bytes, 21 as base64). Results computed once (maps, trajectories, features) are stamped with the last time
//! written before them ([`Recording::end_stamp`]), so Foxglove shows them when the playhead
//! reaches the end of the run; inputs that hold for the whole run (the map of `localize`) are
//! stamped with its first time.

mod scene;

use std::collections::BTreeMap;
use std::path::PathBuf;

use raypath_geometry::{Grid2, PointCloud, Pose2, Pose3, Scan2};
use raypath_io::foxglove::{Entity, GridLayer, GridValues, Recorder, Rgba, frame, topic};
use serde_json::Value;

use super::Failure;

pub use scene::{
    cube_entities, label_color, loop_lines, plane_entity, pole_entities, polyline_entities,
};

/// Most points of one sweep on `/points` (every k-th valid point of larger sweeps).
pub const MAX_SWEEP_POINTS: usize = 10_000;
/// Fewest points a sweep is thinned to.
pub const MIN_SWEEP_POINTS: usize = 1_000;
/// About how many sweep points a recording holds in all.
pub const SWEEP_POINT_BUDGET: usize = 5_000_000;

/// The most points recorded per sweep of a run of `sweeps` sweeps: the budget shared out,
/// between [`MIN_SWEEP_POINTS`] and [`MAX_SWEEP_POINTS`].
pub fn sweep_points(sweeps: usize) -> usize {
    (SWEEP_POINT_BUDGET / sweeps.max(1)).clamp(MIN_SWEEP_POINTS, MAX_SWEEP_POINTS)
}

/// `--record`: write a Foxglove recording of the run.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct RecordArgs {
    /// Write a Foxglove recording (MCAP) of the inputs and results: open it in Foxglove with
    /// File → Open.
    #[arg(long, value_name = "OUT.mcap")]
    pub record: Option<PathBuf>,
}

/// A recording being written: a [`Recorder`] whose errors become [`Failure`]s (exit code 1),
/// and the latest stamp written.
pub struct Recording {
    recorder: Recorder,
    end_stamp: f64,
}

impl Recording {
    /// Creates the recording `--record` names (and its directory); `None` without
    /// `--record`. `json` is the command's `--json` (for the failure report).
    pub fn open(args: &RecordArgs) -> Result<Option<Recording>, Failure> {
        let Some(path) = &args.record else {
            return Ok(None);
        };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| {
                Failure::internal(format!(
                    "{}: cannot create the directory: {e}",
                    dir.display()
                ))
            })?;
        }
        let recorder = Recorder::create(path).map_err(Failure::internal)?;
        Ok(Some(Recording {
            recorder,
            end_stamp: 0.0,
        }))
    }

    /// The latest stamp written so far (0 before any message): the time at which results of
    /// the whole run are recorded.
    pub fn end_stamp(&self) -> f64 {
        self.end_stamp
    }

    fn stamped(&mut self, stamp_secs: f64, result: raypath_io::Result<()>) -> Result<(), Failure> {
        result.map_err(Failure::internal)?;
        if stamp_secs > self.end_stamp {
            self.end_stamp = stamp_secs;
        }
        Ok(())
    }

    /// `/tf` `map → base_link` at `stamp_secs`: where the robot is.
    pub fn robot_pose(&mut self, stamp_secs: f64, map_from_robot: &Pose3) -> Result<(), Failure> {
        let result =
            self.recorder
                .transform(stamp_secs, frame::MAP, frame::BASE_LINK, map_from_robot);
        self.stamped(stamp_secs, result)
    }

    /// A planar scan where it was taken: `/tf` `map → base_link` (`map_from_robot`) and the
    /// `/scan` LaserScan in `base_link` with the laser's mounting `robot_from_laser` as its
    /// pose, both at `stamp_secs`.
    pub fn planar_scan(
        &mut self,
        stamp_secs: f64,
        map_from_robot: &Pose2,
        robot_from_laser: &Pose2,
        scan: &Scan2,
    ) -> Result<(), Failure> {
        self.robot_pose(stamp_secs, &map_from_robot.to_pose3())?;
        let result = self.recorder.laser_scan(
            topic::SCAN,
            stamp_secs,
            frame::BASE_LINK,
            scan,
            &robot_from_laser.to_pose3(),
        );
        self.stamped(stamp_secs, result)
    }

    /// A 3-D sweep where it was taken: `/tf` `map → base_link` (`map_from_sensor`) and the
    /// sweep's points (sensor frame) on `/points` in `base_link`, thinned to at most
    /// `max_points` (every k-th valid point, attributes kept; see [`sweep_points`]), both at
    /// `stamp_secs`.
    pub fn sweep(
        &mut self,
        stamp_secs: f64,
        map_from_sensor: &Pose3,
        cloud: &PointCloud,
        max_points: usize,
    ) -> Result<(), Failure> {
        self.robot_pose(stamp_secs, map_from_sensor)?;
        let thinned = thin(cloud, max_points);
        let cloud = thinned.as_ref().unwrap_or(cloud);
        self.points(topic::POINTS, stamp_secs, frame::BASE_LINK, cloud, None)
    }

    /// A trajectory in `map` as one `foxglove.PosesInFrame` on `topic` (e.g.
    /// [`topic::TRAJECTORY`], [`topic::GROUND_TRUTH`]).
    pub fn trajectory(
        &mut self,
        topic: &str,
        stamp_secs: f64,
        poses: &[Pose3],
    ) -> Result<(), Failure> {
        let result = self.recorder.poses(topic, stamp_secs, frame::MAP, poses);
        self.stamped(stamp_secs, result)
    }

    /// A planar trajectory in `map` (the `z = 0` plane), see [`Recording::trajectory`].
    pub fn planar_trajectory(
        &mut self,
        topic: &str,
        stamp_secs: f64,
        poses: &[Pose2],
    ) -> Result<(), Failure> {
        let result = self
            .recorder
            .planar_poses(topic, stamp_secs, frame::MAP, poses);
        self.stamped(stamp_secs, result)
    }

    /// Every planar frame at its estimated laser pose (`/tf` `map → base_link` with the
    /// logged mounting, `/scan` in `base_link`) and the robot's trajectory (`/trajectory`, at
    /// the end): the track of a 2-D estimate (`scan-match`, `slam`).
    pub fn planar_track(
        &mut self,
        frames: &[raypath_io::sequence::PlanarFrame],
        world_from_laser: &[Pose2],
    ) -> Result<(), Failure> {
        let mut robots = Vec::with_capacity(world_from_laser.len());
        for (frame, pose) in frames.iter().zip(world_from_laser) {
            let robot_from_laser = frame.robot_from_laser();
            let world_from_robot = *pose * robot_from_laser.inverse();
            self.planar_scan(
                frame.sensor_stamp_secs(),
                &world_from_robot,
                &robot_from_laser,
                &frame.scan,
            )?;
            robots.push(world_from_robot);
        }
        let end = self.end_stamp();
        self.planar_trajectory(topic::TRAJECTORY, end, &robots)
    }

    /// A 2-D map over `grid` (in `map`, the `z = 0` plane) as `foxglove.Grid`: one field
    /// `field` of `values` in [`Grid2::linear_index`] order.
    pub fn grid(
        &mut self,
        topic: &str,
        stamp_secs: f64,
        grid: &Grid2,
        field: &str,
        values: GridValues<'_>,
    ) -> Result<(), Failure> {
        let layer = GridLayer::from_grid2(grid, frame::MAP, field, values);
        self.grid_layer(topic, stamp_secs, &layer)
    }

    /// A 2-D map layer as `foxglove.Grid` (for grids that are not a [`Grid2`]).
    pub fn grid_layer(
        &mut self,
        topic: &str,
        stamp_secs: f64,
        layer: &GridLayer<'_>,
    ) -> Result<(), Failure> {
        let result = self.recorder.grid(topic, stamp_secs, layer);
        self.stamped(stamp_secs, result)
    }

    /// A point cloud given in `frame_id` as `foxglove.PointCloud` (see
    /// [`Recorder::point_cloud`] for the fields).
    pub fn points(
        &mut self,
        topic: &str,
        stamp_secs: f64,
        frame_id: &str,
        cloud: &PointCloud,
        colors: Option<&[Rgba]>,
    ) -> Result<(), Failure> {
        let result = self
            .recorder
            .point_cloud(topic, stamp_secs, frame_id, cloud, colors);
        self.stamped(stamp_secs, result)
    }

    /// Scene entities given in `frame_id` as one `foxglove.SceneUpdate` (builders:
    /// [`pole_entities`], [`polyline_entities`], [`plane_entity`], [`cube_entities`],
    /// [`loop_lines`]).
    pub fn scene(
        &mut self,
        topic: &str,
        stamp_secs: f64,
        frame_id: &str,
        entities: &[Entity],
    ) -> Result<(), Failure> {
        let result = self.recorder.scene(topic, stamp_secs, frame_id, entities);
        self.stamped(stamp_secs, result)
    }
}

/// The `"record"` object a command's `--json` document gets.
#[derive(serde::Serialize)]
struct RecordSummary {
    path: String,
    messages: BTreeMap<String, u64>,
}

/// Finishes the recording, if there is one. With `doc` (the command's `--json` document, an
/// object) adds `"record": {"path", "messages": {topic: count}}` and prints nothing; without,
/// prints `recorded PATH: N messages (topic n, …)`.
pub fn finish(recording: Option<Recording>, doc: Option<&mut Value>) -> Result<(), Failure> {
    let Some(recording) = recording else {
        return Ok(());
    };
    let path = recording.recorder.path().to_path_buf();
    let counts: BTreeMap<String, u64> = recording.recorder.finish().map_err(Failure::internal)?;
    match doc.and_then(Value::as_object_mut) {
        Some(object) => {
            let summary = RecordSummary {
                path: path.display().to_string(),
                messages: counts,
            };
            object.insert("record".into(), super::to_json(&summary)?);
        }
        None => {
            let total: u64 = counts.values().sum();
            let topics: Vec<String> = counts.iter().map(|(t, n)| format!("{t} {n}")).collect();
            println!(
                "recorded {}: {total} messages ({})",
                path.display(),
                topics.join(", ")
            );
        }
    }
    Ok(())
}

/// Every k-th valid point of `cloud` (with its attributes), k the smallest that keeps at most
/// `max` points; `None` when `cloud` has no more than `max` valid points.
fn thin(cloud: &PointCloud, max: usize) -> Option<PointCloud> {
    let valid = cloud.num_valid();
    if valid <= max {
        return None;
    }
    let step = valid.div_ceil(max.max(1));
    let kept: Vec<usize> = (0..cloud.len())
        .filter(|&i| cloud.is_valid(i))
        .step_by(step)
        .collect();
    fn pick<T: Copy>(values: &Option<Vec<T>>, kept: &[usize]) -> Option<Vec<T>> {
        let values = values.as_ref()?;
        Some(
            kept.iter()
                .filter_map(|&i| values.get(i).copied())
                .collect(),
        )
    }
    let points = kept.iter().filter_map(|&i| cloud.points.get(i).copied());
    let mut out = PointCloud::from_points(points.collect());
    out.intensity = pick(&cloud.intensity, &kept);
    out.label = pick(&cloud.label, &kept);
    out.rgb = pick(&cloud.rgb, &kept);
    Some(out)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use nalgebra::Point3;

    use super::*;

    #[test]
    fn thinning_keeps_every_kth_valid_point_with_its_attributes() {
        let mut points: Vec<Point3<f32>> =
            (0..10).map(|i| Point3::new(i as f32, 0.0, 0.0)).collect();
        points[1] = Point3::new(f32::NAN, f32::NAN, f32::NAN);
        let mut cloud = PointCloud::from_points(points);
        cloud.intensity = Some((0..10).map(|i| i as f32 * 10.0).collect());
        assert!(thin(&cloud, 9).is_none());
        // Nine valid points, at most four: every third valid one.
        let thinned = thin(&cloud, 4).unwrap();
        let xs: Vec<f32> = thinned.points.iter().map(|p| p.x).collect();
        assert_eq!(xs, [0.0, 4.0, 7.0]);
        assert_eq!(thinned.intensity.unwrap(), [0.0, 40.0, 70.0]);
        assert!(thinned.label.is_none());
    }

    #[test]
    fn the_sweep_budget_is_shared_within_bounds() {
        assert_eq!(sweep_points(0), MAX_SWEEP_POINTS);
        assert_eq!(sweep_points(12), MAX_SWEEP_POINTS);
        assert_eq!(sweep_points(1000), 5000);
        assert_eq!(sweep_points(4541), 1101);
        assert_eq!(sweep_points(1_000_000), MIN_SWEEP_POINTS);
    }
}
