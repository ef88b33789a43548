//! Reading the input of `raypath map` through the sources of `raypath_io::sequence`: planar
//! scans (a CARMEN log, a bag's LaserScan topic) → 2-D, or 3-D sweeps (a KITTI sequence, an
//! NCLT session, a bag's PointCloud2 topic) → 3-D, into posed scans and the box the map must
//! cover.

use std::path::Path;

use nalgebra::{Point2, Point3};
use raypath_geometry::{Aabb2, Aabb3, PointCloud, Pose2, Pose3, Ray3, Scan2};
use raypath_io::sequence::{PlanarFrame, PlanarSource, SweepSequence};
use raypath_sensor_models::MappingConfig;

use crate::commands::source_args::{
    BagSource, SourceArgs, is_bag, place, reference_track, sweep_poses,
};

/// One 3-D sweep: the points (sensor frame) with the sensor's pose.
pub struct Sweep3 {
    /// `world_from_sensor`.
    pub pose: Pose3,
    /// The points, sensor frame.
    pub cloud: PointCloud,
    /// Use every `step`-th valid point.
    pub step: usize,
}

impl Sweep3 {
    /// Calls `sink` with the ray to every `step`-th valid point, in the map frame.
    pub fn for_each_ray(&self, sink: &mut dyn FnMut(&Ray3)) {
        let origin = self.pose.transform_point(&Point3::origin());
        for i in (0..self.cloud.len()).step_by(self.step) {
            if !self.cloud.is_valid(i) {
                continue;
            }
            let point = self.pose.transform_point(&self.cloud.point_f64(i));
            if let Some(ray) = Ray3::between(origin, point) {
                sink(&ray);
            }
        }
    }
}

/// The data to map.
pub enum Input {
    /// 2-D scans with `world_from_laser` poses.
    Planar {
        /// Scans and poses.
        scans: Vec<(Pose2, Scan2)>,
        /// Per scan: its stamp (seconds) and the laser's mounting `robot_from_laser`.
        frames: Vec<(f64, Pose2)>,
        /// Sensor positions and returns within r_max, padded.
        bounds: Aabb2,
    },
    /// 3-D sweeps.
    Spatial {
        /// Sweeps with poses.
        sweeps: Vec<Sweep3>,
        /// Per sweep: its stamp, seconds.
        stamps: Vec<f64>,
        /// Sensor positions and returns within r_max, padded.
        bounds: Aabb3,
    },
}

impl Input {
    /// Reads `path`: a bag (its LaserScan or PointCloud2 topic), a directory (a KITTI
    /// sequence or an NCLT session) or a CARMEN log. Errors name the file and the place.
    pub fn read(
        path: &Path,
        source: &SourceArgs,
        step: usize,
        config: &MappingConfig,
    ) -> Result<Self, String> {
        if is_bag(path) {
            return match source.open_bag(path)? {
                BagSource::Planar(frames) => read_planar(frames, "laser scans", config),
                BagSource::Sweeps(sequence) => read_sweeps(&sequence, step, config),
            };
        }
        let metadata =
            std::fs::metadata(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
        if metadata.is_dir() {
            let sequence = source.open_sweeps(path).map_err(|e| e.to_string())?;
            read_sweeps(&sequence, step, config)
        } else {
            let frames = source.open_planar(path).map_err(|e| e.to_string())?;
            let what = format!("laser messages ({}) in the log", source.laser_lines());
            read_planar(frames, &what, config)
        }
    }
}

/// The scans with their reference poses (see `reference_track`); `what` names the scans
/// for the message when there are none.
fn read_planar(
    source: Box<dyn PlanarSource>,
    what: &str,
    config: &MappingConfig,
) -> Result<Input, String> {
    let name = source.name().to_path_buf();
    let frames: Vec<PlanarFrame> = source
        .collect::<raypath_io::Result<_>>()
        .map_err(|e| e.to_string())?;
    if frames.is_empty() {
        return Err(format!("{}: no {what}", name.display()));
    }
    let max_range = config.range.max_range_m;
    let mut scans = Vec::with_capacity(frames.len());
    let mut stamps = Vec::with_capacity(frames.len());
    let mut bounds = Aabb2::empty();
    let track = reference_track(&frames);
    for (frame, pose) in frames.into_iter().zip(track) {
        let Some(pose) = pose else { continue };
        if !pose.is_finite() {
            return Err(format!(
                "{}: the laser pose is not finite",
                place(&name, frame.origin)
            ));
        }
        bounds.extend(&Point2::new(pose.x(), pose.y()));
        for ray in frame.scan.rays(pose) {
            if let Some(t) = ray.range.hit().filter(|&t| t < max_range) {
                bounds.extend(&ray.at(t));
            }
        }
        stamps.push((frame.stamp_secs, frame.robot_from_laser()));
        scans.push((pose, frame.scan));
    }
    Ok(Input::Planar {
        scans,
        frames: stamps,
        bounds,
    })
}

/// The sweeps at their reference poses (the odometry, with a warning, when the sequence has
/// no reference poses).
fn read_sweeps(
    sequence: &SweepSequence,
    step: usize,
    config: &MappingConfig,
) -> Result<Input, String> {
    let name = sequence.name.display();
    if sequence.is_empty() {
        return Err(format!(
            "{name}: no velodyne scans to map (velodyne/*.bin or velodyne_sync/*.bin)"
        ));
    }
    let Some((poses, odometry)) = sweep_poses(sequence) else {
        return Err(format!(
            "{name}: no sensor poses (KITTI poses.txt, NCLT ground truth or odometry, a bag's \
             reference or odometry poses): map building needs them"
        ));
    };
    if odometry {
        crate::commands::console::warn(format!(
            "{name}: no reference poses; mapping with the odometry poses"
        ));
    }
    let mut sweeps = Vec::with_capacity(poses.len());
    for (i, pose) in poses.iter().enumerate() {
        let cloud = sequence.sweep(i).map_err(|e| e.to_string())?;
        sweeps.push(Sweep3 {
            pose: *pose,
            cloud,
            step,
        });
    }
    let max_range = config.range.max_range_m;
    let mut bounds = Aabb3::empty();
    for (i, sweep) in sweeps.iter().enumerate() {
        if !sweep.pose.is_finite() {
            return Err(format!("{name}: the pose of sweep {i} is not finite"));
        }
        bounds.extend(&sweep.pose.transform_point(&Point3::origin()));
        sweep.for_each_ray(&mut |ray| {
            if let Some(t) = ray.range.hit().filter(|&t| t < max_range) {
                bounds.extend(&ray.at(t));
            }
        });
    }
    let stamps = sequence
        .stamps_secs
        .iter()
        .take(sweeps.len())
        .copied()
        .collect();
    Ok(Input::Spatial {
        sweeps,
        stamps,
        bounds,
    })
}
