//! Writing a simulated drive in the KITTI odometry layout: HDL-64E scans, camera poses, times,
//! calibration, SemanticKITTI-style labels and the pole ground truth.
//!
//! ```text
//! <out>/sequences/NN/velodyne/FFFFFF.bin   f32 x y z reflectance (velodyne frame, REP-103)
//! <out>/sequences/NN/labels/FFFFFF.label   u32 per point: SemanticKITTI class | instance << 16
//! <out>/sequences/NN/times.txt             seconds from the first scan
//! <out>/sequences/NN/calib.txt             P0–P3 and Tr (velo → cam0) of KITTI sequences 00–02
//! <out>/sequences/NN/poles.csv             x,y,w,h,kind,id in the world frame (below)
//! <out>/poses/NN.txt                       world_from_cam0, camera axes, first pose = identity
//! ```
//!
//! **World frame** of `poles.csv` and of the poses read back: the velodyne frame of the first
//! scan (REP-103, x forward, y left, z up), so `(x, y)` of a pole ≈ `(z, −x)` of the camera
//! poses up to the lidar–camera offset — the frame of the real pole maps in
//! `RAYPATH_DATA/kitti-poles`. The velodyne poses are recovered exactly from the camera poses
//! by [`raypath_io::kitti::velodyne_poses_from_cam0`].

use std::sync::atomic::{AtomicU64, Ordering};

use nalgebra::Matrix3x4;
use rayon::prelude::*;
use raypath_geometry::Pose3;
use raypath_io::kitti::{self, KittiCalib, KittiLayout};

use super::output::{ScanStats, create_dir, encode_labels, remove_stale, write_bytes};
use crate::error::Result;
use crate::lidar3::{Lidar3, SimScan};
use crate::scene3::Scene3;
use crate::{Progress, SimError};

/// Scan period of the KITTI recordings (10 Hz), seconds.
pub const KITTI_PERIOD_S: f64 = 0.1;

/// Height of the HDL-64E above the road on the KITTI car, metres.
pub const KITTI_VELODYNE_HEIGHT_M: f64 = 1.73;

/// The calibration of KITTI odometry sequences 00–02: projections `P0`–`P3` and `Tr`
/// (velodyne → cam0).
pub fn kitti_calibration() -> KittiCalib {
    let projection = |tx: f64, ty: f64, tz: f64| {
        Matrix3x4::new(
            718.856, 0.0, 607.1928, tx, 0.0, 718.856, 185.2157, ty, 0.0, 0.0, 1.0, tz,
        )
    };
    KittiCalib::odometry(
        &[
            projection(0.0, 0.0, 0.0),
            projection(-386.1448, 0.0, 0.0),
            projection(45.38225, -0.1130887, 3.779761e-3),
            projection(-337.2877, 2.369057, 4.915215e-3),
        ],
        &kitti_cam0_from_velo(),
    )
}

/// `Tr` of KITTI odometry sequences 00–02: the velodyne → cam0 transform.
pub fn kitti_cam0_from_velo() -> Pose3 {
    Pose3::from_matrix3x4(&Matrix3x4::new(
        4.276802385584e-04,
        -9.999672484946e-01,
        -8.084491683471e-03,
        -1.198459927713e-02,
        -7.210626507497e-03,
        8.081198471645e-03,
        -9.999413164504e-01,
        -5.403984729748e-02,
        9.999738645903e-01,
        4.859485810390e-04,
        -7.206933692422e-03,
        -2.921968648686e-01,
    ))
}

/// What to write besides the scans.
pub(crate) struct KittiSequenceFiles<'a> {
    /// Where.
    pub layout: &'a KittiLayout,
    /// `world_from_velo` in the output world frame (the velodyne frame of the first scan).
    pub world_from_velo: &'a [Pose3],
    /// Seconds, one per scan.
    pub times_s: &'a [f64],
    /// Also write SemanticKITTI labels.
    pub labels: bool,
}

/// Writes the poses, times and calibration, then scans `scene` from `scene_from_velo` (one
/// pose per scan, in the scene's frame) in parallel and writes every scan. Stale scans of an
/// earlier run into the same directory are deleted first.
pub(crate) fn write_sequence(
    files: &KittiSequenceFiles<'_>,
    scene: &Scene3,
    lidar: &Lidar3,
    scene_from_velo: &[Pose3],
    seed: u64,
    progress: Progress,
) -> Result<ScanStats> {
    if scene_from_velo.len() != files.world_from_velo.len() {
        return Err(SimError::InvalidParameter {
            name: "poses",
            reason: "one scene pose, world pose and time per scan".into(),
        });
    }
    let scan = |i: usize| -> Result<SimScan> {
        let pose = scene_from_velo
            .get(i)
            .ok_or_else(|| SimError::InvalidParameter {
                name: "scan",
                reason: format!("no scan {i}"),
            })?;
        lidar.scan(scene, pose, seed, i as u64)
    };
    write_sequence_with(files, &scan, progress)
}

/// Writes the poses, times and calibration, then simulates scan `i` with `scan(i)` for every
/// `i` of `files.world_from_velo` in parallel and writes it. Stale scans of an earlier run
/// into the same directory are deleted first.
pub(crate) fn write_sequence_with(
    files: &KittiSequenceFiles<'_>,
    scan: &(dyn Fn(usize) -> Result<SimScan> + Sync),
    progress: Progress,
) -> Result<ScanStats> {
    let layout = files.layout;
    if files.times_s.len() != files.world_from_velo.len() {
        return Err(SimError::InvalidParameter {
            name: "poses",
            reason: "one scene pose, world pose and time per scan".into(),
        });
    }
    layout.create_dirs()?;
    remove_stale(&layout.velodyne_dir(), "bin")?;
    let labels_dir = layout.sequence_dir().join("labels");
    if files.labels {
        create_dir(&labels_dir)?;
        remove_stale(&labels_dir, "label")?;
    }
    let calib = kitti_calibration();
    let cam0_from_velo = kitti_cam0_from_velo();
    kitti::write_calib(&layout.calib_path(), &calib)?;
    kitti::write_times(&layout.times_path(), files.times_s)?;
    let camera_poses = kitti::cam0_poses_from_velodyne(files.world_from_velo, &cam0_from_velo);
    kitti::write_poses(&layout.poses_path(), &camera_poses)?;

    let total = files.world_from_velo.len() as u64;
    let done = AtomicU64::new(0);
    progress(0, total);
    let stats = (0..files.world_from_velo.len())
        .into_par_iter()
        .map(|i| -> Result<ScanStats> {
            let scan = scan(i)?;
            let frame = i as u64;
            kitti::write_velodyne(&layout.scan_path(frame), &scan.cloud)?;
            if files.labels {
                let path = labels_dir.join(format!("{frame:06}.label"));
                write_bytes(&path, &encode_labels(&scan.cloud))?;
            }
            let mut stats = ScanStats::default();
            stats.add(&scan.cloud);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            Ok(stats)
        })
        .try_reduce(ScanStats::default, |mut a, b| {
            a.merge(&b);
            Ok(a)
        })?;
    Ok(stats)
}
