//! Reading the input of `raypath map`: a CARMEN log (2-D) or a KITTI / NCLT directory (3-D),
//! into posed scans and the box the map must cover.

use std::path::Path;

use nalgebra::{Point2, Point3};
use raypath_geometry::{Aabb2, Aabb3, PointCloud, Pose2, Pose3, Ray3, Scan2};
use raypath_io::carmen::{CarmenReader, Record};
use raypath_io::kitti::{self, KittiSequence};
use raypath_io::nclt::{self, NcltSession};
use raypath_sensor_models::MappingConfig;

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
        /// Sensor positions and returns within r_max, padded.
        bounds: Aabb2,
    },
    /// 3-D sweeps.
    Spatial {
        /// Sweeps with poses.
        sweeps: Vec<Sweep3>,
        /// Sensor positions and returns within r_max, padded.
        bounds: Aabb3,
    },
}

impl Input {
    /// Reads `path`: a directory is a KITTI sequence or an NCLT session, a file a CARMEN
    /// log. Errors name the file and the place.
    pub fn read(path: &Path, step: usize, config: &MappingConfig) -> Result<Self, String> {
        let metadata =
            std::fs::metadata(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
        let input = if metadata.is_dir() {
            let kitti_like = path.join("velodyne").is_dir() || path.join("poses.txt").is_file();
            if kitti_like {
                read_kitti(path, step, config)?
            } else {
                read_nclt(path, step, config)?
            }
        } else {
            read_carmen(path, config)?
        };
        Ok(input)
    }
}

fn read_carmen(path: &Path, config: &MappingConfig) -> Result<Input, String> {
    let reader = CarmenReader::open(path).map_err(|e| e.to_string())?;
    let max_range = config.range.max_range_m;
    let mut scans = Vec::new();
    let mut bounds = Aabb2::empty();
    for record in reader {
        let Record::Laser(laser) = record.map_err(|e| e.to_string())? else {
            continue;
        };
        let pose = laser.world_from_laser;
        if !pose.is_finite() {
            return Err(format!(
                "{}:{}: the laser pose is not finite",
                path.display(),
                laser.line
            ));
        }
        bounds.extend(&Point2::new(pose.x(), pose.y()));
        for ray in laser.scan.rays(pose) {
            if let Some(t) = ray.range.hit().filter(|&t| t < max_range) {
                bounds.extend(&ray.at(t));
            }
        }
        scans.push((pose, laser.scan));
    }
    if scans.is_empty() {
        return Err(format!(
            "{}: no laser messages (FLASER, RLASER or ROBOTLASER1) in the log",
            path.display()
        ));
    }
    Ok(Input::Planar { scans, bounds })
}

fn read_kitti(dir: &Path, step: usize, config: &MappingConfig) -> Result<Input, String> {
    let sequence = KittiSequence::open(dir).map_err(|e| e.to_string())?;
    let cam_poses = sequence.poses().map_err(|e| e.to_string())?;
    if cam_poses.is_empty() {
        return Err(format!(
            "{}: the KITTI sequence has no poses.txt (or ../../poses/NN.txt): map building needs \
             ground-truth poses",
            dir.display()
        ));
    }
    let calib = sequence.calib().map_err(|e| e.to_string())?;
    let poses = match calib.and_then(|c| c.cam0_from_velo()) {
        Some(cam0_from_velo) => kitti::velodyne_poses_from_cam0(&cam_poses, &cam0_from_velo),
        None => cam_poses,
    };
    let mut sweeps = Vec::new();
    for scan in sequence.scans() {
        let scan = scan.map_err(|e| e.to_string())?;
        let pose = usize::try_from(scan.frame)
            .ok()
            .and_then(|i| poses.get(i))
            .copied()
            .ok_or_else(|| {
                format!(
                    "{}: scan {} has no pose ({} poses)",
                    dir.display(),
                    scan.frame,
                    poses.len()
                )
            })?;
        sweeps.push(Sweep3 {
            pose,
            cloud: scan.points,
            step,
        });
    }
    spatial(dir, sweeps, config)
}

fn read_nclt(dir: &Path, step: usize, config: &MappingConfig) -> Result<Input, String> {
    let session = NcltSession::open(dir).map_err(|e| e.to_string())?;
    let truth = session.ground_truth().map_err(|e| e.to_string())?;
    if truth.poses.is_empty() {
        return Err(format!(
            "{}: the NCLT session has no ground truth (groundtruth_<date>.csv): map building \
             needs poses",
            dir.display()
        ));
    }
    let mut sweeps = Vec::new();
    for scan in session.scans() {
        let mut scan = scan.map_err(|e| e.to_string())?;
        let nearest = truth
            .poses
            .partition_point(|p| p.utime < scan.utime)
            .min(truth.poses.len() - 1);
        let before = nearest.saturating_sub(1);
        let pick = [before, nearest]
            .into_iter()
            .filter_map(|i| truth.poses.get(i))
            .min_by_key(|p| p.utime.abs_diff(scan.utime));
        let Some(pose) = pick else { continue };
        nclt::flu_from_frd(&mut scan.points);
        sweeps.push(Sweep3 {
            pose: pose.world_from_body(),
            cloud: scan.points,
            step,
        });
    }
    spatial(dir, sweeps, config)
}

fn spatial(dir: &Path, sweeps: Vec<Sweep3>, config: &MappingConfig) -> Result<Input, String> {
    if sweeps.is_empty() {
        return Err(format!(
            "{}: no velodyne scans to map (velodyne/*.bin or velodyne_sync/*.bin)",
            dir.display()
        ));
    }
    let max_range = config.range.max_range_m;
    let mut bounds = Aabb3::empty();
    for sweep in &sweeps {
        if !sweep.pose.is_finite() {
            return Err(format!("{}: a scan pose is not finite", dir.display()));
        }
        bounds.extend(&sweep.pose.transform_point(&Point3::origin()));
        sweep.for_each_ray(&mut |ray| {
            if let Some(t) = ray.range.hit().filter(|&t| t < max_range) {
                bounds.extend(&ray.at(t));
            }
        });
    }
    Ok(Input::Spatial { sweeps, bounds })
}
