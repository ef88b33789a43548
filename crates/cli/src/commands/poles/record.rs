//! `raypath poles … --record`: the sensor poses, the trajectory, the poles as cylinders and
//! the ground truth.

use raypath_geometry::{Pose2, Pose3};
use raypath_io::foxglove::{frame, topic};
use raypath_localizer::PoseTrack;
use raypath_poles::{Drive, Pole};

use crate::commands::Failure;
use crate::commands::record::{Recording, pole_entities, sweep_points};

/// `extract` and `map`: each scan of `scans` at its pose on the mapping `track` (`/tf`
/// `map → base_link`, `/points` thinned), the track over them as `/trajectory`, and `poles` as
/// `/poles` (cylinders) at the last scan's time.
pub fn mapping(
    recording: &mut Recording,
    drive: &Drive,
    track: &[Pose3],
    scans: &[usize],
    poles: &[Pole],
) -> Result<(), Failure> {
    let mut poses = Vec::new();
    let max_points = sweep_points(scans.len());
    for &i in scans {
        if let (Some(pose), Some(stamp)) = (track.get(i), drive.sweeps.stamps_secs.get(i)) {
            let cloud = drive.sweeps.sweep(i).map_err(Failure::input)?;
            recording.sweep(*stamp, pose, &cloud, max_points)?;
            poses.push(*pose);
        }
    }
    let end = recording.end_stamp();
    recording.trajectory(topic::TRAJECTORY, end, &poses)?;
    recording.scene(topic::POLES, end, frame::MAP, &pole_entities(poles, "pole"))
}

/// `localize`: the map's poles as `/poles` at the first scan's time, each scan at its estimate
/// in `estimate` (the first run; `/tf`, `/points` thinned), the estimates as `/trajectory` and
/// the ground truth over `range` as `/ground_truth`.
pub fn localization(
    recording: &mut Recording,
    drive: &Drive,
    range: std::ops::Range<usize>,
    map: &[Pole],
    estimate: &PoseTrack<Pose2>,
) -> Result<(), Failure> {
    let start = drive
        .sweeps
        .stamps_secs
        .get(range.start)
        .copied()
        .unwrap_or(0.0);
    recording.scene(topic::POLES, start, frame::MAP, &pole_entities(map, "pole"))?;
    let max_points = sweep_points(estimate.len());
    for (i, sample) in range.clone().zip(estimate.iter()) {
        let cloud = drive.sweeps.sweep(i).map_err(Failure::input)?;
        recording.sweep(
            sample.stamp_secs,
            &sample.pose.to_pose3(),
            &cloud,
            max_points,
        )?;
    }
    let end = recording.end_stamp();
    recording.planar_trajectory(topic::TRAJECTORY, end, estimate.poses())?;
    if let Some(truth) = &drive.sweeps.reference {
        let truth = truth.get(range).unwrap_or_default();
        recording.trajectory(topic::GROUND_TRUTH, end, truth)?;
    }
    Ok(())
}
