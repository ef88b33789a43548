//! Loading the data sets of the evaluation: corrected CARMEN logs (real and simulated) and
//! a section of a simulated KITTI-layout urban drive.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use nalgebra::Point3;
use raypath_geometry::{Pose2, Pose3, Ray3, Scan2};
use raypath_io::sequence::{LaserChoice, PlanarOptions, SweepOptions, SweepSequence, read_planar};

/// The front-laser scans of a CARMEN log (or a bag) with their logged (reference) poses.
pub fn carmen_scans(path: &Path) -> Result<Vec<(Pose2, Scan2)>> {
    let options = PlanarOptions {
        laser: LaserChoice::Front,
        ..PlanarOptions::default()
    };
    let frames = read_planar(path, &options)?;
    Ok(frames
        .into_iter()
        .map(|f| (f.world_from_laser, f.scan))
        .collect())
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

/// One 3-D scan: `world_from_velodyne` (the REP-103 world of [`SweepSequence`]: the
/// velodyne frame of the first scan) and its rays in the sensor frame (every
/// `ray_step`-th valid point).
pub struct Scan3 {
    /// `world_from_velodyne` in a z-up world frame.
    pub pose: Pose3,
    /// Rays from the sensor origin to the points, sensor frame.
    pub rays: Vec<Ray3>,
}

/// Sweeps `0..frames` of KITTI sequence `dir` (a `sequences/XX` directory) with their
/// reference poses; sweep `f` keeps every `ray_step(f)`-th point as a ray.
pub fn kitti_scans(
    dir: &Path,
    frames: usize,
    ray_step: impl Fn(usize) -> usize,
    mut progress: impl FnMut(),
) -> Result<Vec<Scan3>> {
    let sequence = SweepSequence::open(dir, &SweepOptions::default())?;
    let poses = sequence.require_reference()?;
    let mut scans = Vec::new();
    for (frame, pose) in poses.iter().enumerate().take(frames) {
        let cloud = sequence
            .sweep(frame)
            .with_context(|| format!("frame {frame}"))?;
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
