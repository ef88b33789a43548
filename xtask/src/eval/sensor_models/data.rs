//! Loading the data sets of the evaluation: corrected CARMEN logs (real and simulated) and
//! a section of a simulated KITTI-layout urban drive.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use nalgebra::Point3;
use raypath_geometry::{Pose2, Pose3, Ray3, Scan2};
use raypath_io::carmen::{CarmenReader, Record};
use raypath_io::kitti::{KittiSequence, flu_from_camera, velodyne_poses};

/// The laser scans of a CARMEN log with their reference poses.
pub fn carmen_scans(path: &Path) -> Result<Vec<(Pose2, Scan2)>> {
    let mut scans = Vec::new();
    for record in CarmenReader::open(path)? {
        if let Record::Laser(laser) = record? {
            scans.push((laser.world_from_laser, laser.scan));
        }
    }
    Ok(scans)
}

/// Files in `dir` whose names end with `suffix`, sorted.
pub fn files_ending(dir: &Path, suffixes: &[&str]) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .flatten()
                .map(|e| e.path())
                .filter(|p| {
                    let name = p.to_string_lossy();
                    suffixes.iter().any(|s| name.ends_with(s))
                })
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}

/// A log's short name: the file name without `-corrected.log[.gz|.bz2]`.
pub fn log_name(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    name.split("-corrected").next().unwrap_or(&name).to_owned()
}

/// One 3-D scan: `world_from_velodyne` (REP-103 world: z up) and its rays in the sensor
/// frame (every `ray_step`-th valid point).
pub struct Scan3 {
    /// `world_from_velodyne` in a z-up world frame.
    pub pose: Pose3,
    /// Rays from the sensor origin to the points, sensor frame.
    pub rays: Vec<Ray3>,
}

/// Frames `0..frames` of KITTI sequence `dir` (a `sequences/XX` directory); frame `f`
/// keeps every `ray_step(f)`-th point as a ray.
pub fn kitti_scans(
    dir: &Path,
    frames: usize,
    ray_step: impl Fn(usize) -> usize,
    mut progress: impl FnMut(),
) -> Result<Vec<Scan3>> {
    let sequence = KittiSequence::open(dir)?;
    let cam_poses = sequence.poses()?;
    let Some(calib) = sequence.calib()? else {
        bail!("{}: no calib.txt", dir.display());
    };
    let Some(cam0_from_velo) = calib.cam0_from_velo() else {
        bail!("{}: calib.txt has no Tr entry", dir.display());
    };
    let flu = flu_from_camera();
    let poses: Vec<Pose3> = velodyne_poses(&cam_poses, &cam0_from_velo)
        .into_iter()
        .map(|p| flu * p)
        .collect();
    let mut scans = Vec::new();
    for (frame, pose) in poses.iter().enumerate().take(frames) {
        let Some(cloud) = sequence.scan(frame as u64) else {
            bail!("{}: no velodyne scan for frame {frame}", dir.display());
        };
        let cloud = cloud.with_context(|| format!("frame {frame}"))?;
        let rays = (0..cloud.len())
            .step_by(ray_step(frame).max(1))
            .filter(|&i| cloud.is_valid(i))
            .filter_map(|i| Ray3::between(Point3::origin(), cloud.point_f64(i)))
            .collect();
        scans.push(Scan3 { pose: *pose, rays });
        progress();
    }
    Ok(scans)
}
