//! `raypath map --record`: the scans at their poses, the trajectory and the map.

use nalgebra::Point3;
use raypath_geometry::{PointCloud, Pose3};
use raypath_io::foxglove::{GridValues, frame, topic};
use raypath_sensor_models::export::{
    MapFile, MapPicture, StoredStats, picture_value, picture_values,
};
use raypath_sensor_models::{DenseStats2, DenseStats3};

use super::input::Input;
use crate::commands::Failure;
use crate::commands::record::{Recording, sweep_points};

/// Most occupied voxels recorded as `/map_points`; larger maps keep every k-th (in grid order).
pub const MAX_VOXELS: usize = 1_000_000;

/// The name of the Grid field a picture fills.
fn field(picture: MapPicture) -> &'static str {
    match picture {
        MapPicture::Reflection => "reflection",
        MapPicture::DecayRate => "hit_probability",
        MapPicture::Occupancy => "occupancy",
    }
}

/// Writes the input and the map: per scan (2-D) `/tf` and `/scan`, per sweep (3-D) `/tf` and
/// `/points` (thinned); the trajectory; the picture values of the map (3-D: of its column
/// sums) as `/map`, and for 3-D maps the occupied voxels as `/map_points`.
pub fn record(
    recording: &mut Recording,
    input: &Input,
    file: &MapFile,
    picture: MapPicture,
) -> Result<(), Failure> {
    match input {
        Input::Planar { scans, frames, .. } => {
            let mut robots = Vec::with_capacity(scans.len());
            for ((world_from_laser, scan), (stamp, robot_from_laser)) in scans.iter().zip(frames) {
                let world_from_robot = *world_from_laser * robot_from_laser.inverse();
                recording.planar_scan(*stamp, &world_from_robot, robot_from_laser, scan)?;
                robots.push(world_from_robot);
            }
            let end = recording.end_stamp();
            recording.planar_trajectory(topic::TRAJECTORY, end, &robots)?;
        }
        Input::Spatial { sweeps, stamps, .. } => {
            let max_points = sweep_points(sweeps.len());
            for (sweep, stamp) in sweeps.iter().zip(stamps) {
                recording.sweep(*stamp, &sweep.pose, &sweep.cloud, max_points)?;
            }
            let poses: Vec<Pose3> = sweeps.iter().map(|s| s.pose).collect();
            let end = recording.end_stamp();
            recording.trajectory(topic::TRAJECTORY, end, &poses)?;
        }
    }
    let end = recording.end_stamp();
    match &file.stats {
        StoredStats::Planar(stats) => grid(recording, end, stats, picture),
        StoredStats::Spatial(stats) => {
            grid(recording, end, &stats.project_z(), picture)?;
            let voxels = occupied_voxels(stats, picture);
            recording.points(topic::MAP_POINTS, end, frame::MAP, &voxels, None)
        }
    }
}

/// `/map`: the picture values as `FLOAT32`, NaN for unknown cells.
pub(crate) fn grid(
    recording: &mut Recording,
    stamp: f64,
    stats: &DenseStats2,
    picture: MapPicture,
) -> Result<(), Failure> {
    let values: Vec<f32> = picture_values(stats, picture)
        .into_iter()
        .map(|v| v.map_or(f32::NAN, |v| v as f32))
        .collect();
    recording.grid(
        topic::MAP,
        stamp,
        stats.grid(),
        field(picture),
        GridValues::F32(&values),
    )
}

/// The centres of the voxels with hits whose value is above one half, with the value as
/// intensity; at most [`MAX_VOXELS`] (every k-th when there are more).
fn occupied_voxels(stats: &DenseStats3, picture: MapPicture) -> PointCloud {
    let grid = stats.grid();
    let cell_m = grid.cell_size();
    let occupied: Vec<(usize, f64)> = stats
        .cells()
        .iter()
        .enumerate()
        .filter(|(_, c)| c.hits() > 0)
        .filter_map(|(i, c)| picture_value(c, picture, cell_m).map(|v| (i, v)))
        .filter(|(_, v)| *v > 0.5)
        .collect();
    let step = occupied.len().div_ceil(MAX_VOXELS).max(1);
    if step > 1 {
        crate::commands::console::note(format!(
            "--record: {} occupied voxels; recording every {step}-th",
            occupied.len()
        ));
    }
    let mut points = Vec::with_capacity(occupied.len() / step + 1);
    let mut intensity = Vec::with_capacity(points.capacity());
    for &(i, v) in occupied.iter().step_by(step) {
        let c: Point3<f64> = grid.cell_center(grid.cell_from_linear(i));
        points.push(Point3::new(c.x as f32, c.y as f32, c.z as f32));
        intensity.push(v as f32);
    }
    let mut cloud = PointCloud::from_points(points);
    cloud.intensity = Some(intensity);
    cloud
}
