//! Ground truth of `raypath loop-closure`: poses from a KITTI pose file (12 numbers a line), a
//! TUM file (`t x y z qx qy qz qw`), or a source of `raypath_io::sequence` — a CARMEN
//! (corrected) log or a bag's LaserScan topic (its reference poses, else its logged poses, see
//! `reference_track`), or a bag's PointCloud2 topic (its reference poses) — paired with the
//! frames.
//!
//! Pairing: by index (by frame number for a KITTI sequence) when the file has no times (KITTI
//! poses) or as many poses as the input has frames (CARMEN: the laser scans); else by time —
//! the pose at a frame's time, interpolated between the two ground-truth poses around it when
//! they are at most `raypath_io::sequence::MAX_GAP_SECS` apart (`poses_at_times`). Frames that get no pose are left out of the
//! evaluation.

use std::path::Path;

use raypath_geometry::{Pose2, Pose3};
use raypath_io::sequence::{PlanarFrame, poses_at_times};
use raypath_place_recognition::{Exclusion, GroundTruth};

use super::super::Failure;
use super::super::source_args::{BagSource, SourceArgs, is_bag, reference_track};
use super::input::Input;

/// Poses read from a ground-truth file.
pub struct TruthPoses {
    /// The poses, in file order.
    pub poses: Vec<Pose3>,
    /// Their times, when the file has them.
    pub times: Option<Vec<f64>>,
}

/// How the ground truth is turned into revisits.
pub struct TruthParams {
    /// Radius of "the same place", metres.
    pub radius_m: f64,
    /// Field of view of a planar sensor, radians (`None`: the first scan's span).
    pub fov_rad: Option<f64>,
    /// The exclusion window.
    pub exclusion: Exclusion,
}

/// Reads the ground-truth file and builds the revisits of the input's frames; also returns
/// the ground-truth pose of each frame (`None` where none pairs with it).
pub fn ground_truth(
    path: &Path,
    source: &SourceArgs,
    input: &Input,
    params: &TruthParams,
) -> Result<(GroundTruth, Vec<Option<Pose3>>), Failure> {
    let truth = read_truth(path, source)?;
    let paired = pair(&truth, input);
    if paired.iter().all(Option::is_none) {
        return Err(Failure::input(format!(
            "{}: no pose pairs with a frame of {} ({} poses, {} frames{})",
            path.display(),
            input.path.display(),
            truth.poses.len(),
            input.total,
            if truth.times.is_some() && input.times.is_some() {
                ", no common times"
            } else {
                ", and no times to pair them by"
            }
        )));
    }
    let times = input.times.as_deref();
    let built = if input.is_planar() {
        let poses: Vec<Pose2> = paired
            .iter()
            .map(|p| p.map_or(Pose2::new(f64::NAN, f64::NAN, 0.0), |p| p.to_planar()))
            .collect();
        let fov = params
            .fov_rad
            .or(input.scan_fov_rad())
            .unwrap_or(std::f64::consts::TAU);
        GroundTruth::from_planar_poses(&poses, times, params.radius_m, fov, params.exclusion)
    } else {
        let positions: Vec<[f64; 3]> = paired
            .iter()
            .map(|p| p.map_or([f64::NAN; 3], |p| p.translation().into()))
            .collect();
        GroundTruth::from_positions(&positions, times, params.radius_m, params.exclusion)
    };
    let built = built.map_err(|e| Failure::input(format!("{}: {e}", path.display())))?;
    Ok((built, paired))
}

/// Reads a TUM or KITTI pose file, or else a bag or a CARMEN log (their reference poses and
/// times).
fn read_truth(path: &Path, source: &SourceArgs) -> Result<TruthPoses, Failure> {
    if is_bag(path) {
        return match source.open_bag(path).map_err(Failure::input)? {
            BagSource::Planar(frames) => {
                let frames = frames
                    .collect::<raypath_io::Result<Vec<_>>>()
                    .map_err(Failure::input)?;
                planar_truth(path, &frames)
            }
            BagSource::Sweeps(sequence) => {
                let poses = sequence
                    .require_reference()
                    .map_err(Failure::input)?
                    .to_vec();
                Ok(TruthPoses {
                    poses,
                    times: Some(sequence.stamps_secs.clone()),
                })
            }
        };
    }
    // Text pose files are plain UTF-8; CARMEN logs may be compressed.
    if let Ok(text) = std::fs::read_to_string(path) {
        let first = text
            .lines()
            .map(str::trim)
            .enumerate()
            .find(|(_, l)| !l.is_empty() && !l.starts_with('#'));
        let numbers = first.map(|(i, l)| {
            let fields: Vec<&str> = l.split_whitespace().collect();
            let numeric = fields.iter().all(|f| f.parse::<f64>().is_ok());
            (numeric, fields.len(), i + 1)
        });
        match numbers {
            Some((true, 12, _)) => {
                let poses = raypath_io::kitti::read_poses(path).map_err(Failure::input)?;
                return Ok(TruthPoses { poses, times: None });
            }
            Some((true, 8, _)) => return read_tum(path),
            Some((true, n, line)) => {
                return Err(Failure::input(format!(
                    "{}: line {line}: {n} numbers; expected 12 (KITTI poses) or 8 (TUM \
                         `t x y z qx qy qz qw`)",
                    path.display()
                )));
            }
            _ => {}
        }
    }
    let frames = source.read_frames(path).map_err(Failure::input)?;
    planar_truth(path, &frames)
}

/// The reference poses of planar frames and their times (frames without one are left out).
fn planar_truth(path: &Path, frames: &[PlanarFrame]) -> Result<TruthPoses, Failure> {
    let mut poses = Vec::new();
    let mut times = Vec::new();
    for (frame, pose) in frames.iter().zip(reference_track(frames)) {
        if let Some(pose) = pose {
            poses.push(pose.to_pose3());
            times.push(frame.stamp_secs);
        }
    }
    if poses.is_empty() {
        return Err(Failure::input(format!(
            "{}: no poses (neither a CARMEN log with laser scans, a bag, KITTI poses nor a \
                 TUM file)",
            path.display()
        )));
    }
    Ok(TruthPoses {
        poses,
        times: Some(times),
    })
}

/// Reads a TUM file `t x y z qx qy qz qw` through `raypath_io::tum`.
fn read_tum(path: &Path) -> Result<TruthPoses, Failure> {
    let stamped = raypath_io::tum::read_tum(path).map_err(Failure::input)?;
    Ok(TruthPoses {
        poses: stamped.iter().map(|p| p.pose).collect(),
        times: Some(stamped.iter().map(|p| p.time_s).collect()),
    })
}

/// The ground-truth pose of each frame (see the module documentation).
fn pair(truth: &TruthPoses, input: &Input) -> Vec<Option<Pose3>> {
    if truth.times.is_none() || truth.poses.len() == input.total {
        let by_number = input.numbered_by_frame();
        return (0..input.len())
            .map(|i| {
                let k = if by_number { input.labels[i] } else { i };
                truth.poses.get(k).copied()
            })
            .collect();
    }
    let (Some(truth_times), Some(frame_times)) = (&truth.times, &input.times) else {
        return vec![None; input.len()];
    };
    poses_at_times(&truth.poses, truth_times, frame_times)
}
