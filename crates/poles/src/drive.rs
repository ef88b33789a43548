//! A recorded drive: scan times, ground-truth and odometry sensor poses per scan, and the
//! scans themselves (read one at a time), on top of [`raypath_io::sequence::SweepSequence`],
//! which reads the layouts:
//!
//! * **KITTI** (`…/sequences/NN/` or a directory with `velodyne/`, `poses.txt`, `times.txt`,
//!   `calib.txt`): sensor poses `world_from_velo = velo_from_cam0 · world_from_cam0 ·
//!   cam0_from_velo` (the velodyne frame of the first scan is the world frame, as the
//!   semi-synthetic pole maps). KITTI has no odometry: the odometry track is the ground truth
//!   (evaluations corrupt its increments).
//! * **NCLT** (a session directory): scans from `velodyne_sync/` turned to REP-103 axes, the
//!   ground truth and the integrated odometry (`odometry_mu_100hz.csv`) interpolated at the
//!   scan times, in REP-103 frames (`NcltPose::world_from_body`; the body frame is the
//!   velodyne frame in the simulated sessions; like the reference implementation, no
//!   lidar-to-body extrinsic is applied).
//! * **rosbag2** (a bag directory or `.mcap` file, `sensor_msgs/msg/PointCloud2`; open with
//!   [`Drive::open_with`] to choose topics): the reference-pose topic is the ground truth;
//!   without an odometry topic the odometry track is the reference, as for KITTI. A bag
//!   drive follows KITTI's conventions ([`DriveFormat::Kitti`]; [`Drive::sweep_format`] tells
//!   it apart).
//! * **In memory** ([`Drive::from_fn`]): times and poses given by the caller, scans produced
//!   on demand by a function (e.g. simulated, `raypath_sim::semi_kitti::SemiKittiDrive`), so
//!   an evaluation streams a drive without writing its scans to disk.

use std::path::{Path, PathBuf};

use raypath_geometry::{PointCloud, Pose3};
use raypath_io::sequence::{SweepFormat, SweepOptions, SweepSequence};

use crate::error::{PoleError, Result};
#[cfg(doc)]
use crate::sweep::SweepMotion;
use crate::sweep::SweepTiming;

/// The layout a drive was read from, as far as presets and odometry noise go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DriveFormat {
    /// KITTI odometry layout (and rosbag2 recordings, which follow its conventions).
    Kitti,
    /// NCLT session layout.
    Nclt,
}

impl DriveFormat {
    /// The drive conventions of a sweep layout: a bag follows KITTI's (no recorded odometry
    /// covariance; the odometry falls back to the reference poses).
    pub fn of(format: SweepFormat) -> Self {
        match format {
            SweepFormat::Nclt => DriveFormat::Nclt,
            SweepFormat::Kitti | SweepFormat::Bag | SweepFormat::Ouster => DriveFormat::Kitti,
        }
    }

    fn sweep_format(self) -> SweepFormat {
        match self {
            DriveFormat::Kitti => SweepFormat::Kitti,
            DriveFormat::Nclt => SweepFormat::Nclt,
        }
    }
}

/// The error a scan function of an in-memory drive may return.
pub type ScanError = raypath_io::sequence::SweepError;

/// A scan source of an in-memory drive: scan `index` → points in the sensor frame.
pub type ScanFn = raypath_io::sequence::SweepFn;

/// A drive: per scan a time, a ground-truth sensor pose (when known) and an odometry pose.
pub struct Drive {
    /// The directory (for an in-memory drive: its name), used in errors.
    pub dir: PathBuf,
    /// The layout.
    pub format: DriveFormat,
    /// Scan times, seconds (strictly increasing).
    pub stamps_secs: Vec<f64>,
    /// Ground-truth `world_from_sensor` per scan, when the drive has ground truth.
    pub ground_truth: Option<Vec<Pose3>>,
    /// Odometry `odom_from_sensor` per scan.
    pub odometry: Vec<Pose3>,
    /// Per scan: standard deviations `[x m, y m, yaw rad]` of the odometry increment from the
    /// previous scan, when the drive states them (NCLT `odometry_cov.csv`).
    pub odometry_std: Option<Vec<[f64; 3]>>,
    /// When the scans are de-skewed sweeps of a moving sensor, their timing: local maps then
    /// trace every ray from where the sensor was when it measured the point
    /// ([`SweepMotion::from_poses`] along the registration track). `None` (the default of
    /// every constructor): rays from each scan's origin, right for scans measured from one
    /// pose such as the simulated ones; set `Some(SweepTiming::kitti())` for real KITTI
    /// sweeps.
    pub sweep_timing: Option<SweepTiming>,
    sweeps: SweepSequence,
}

impl Drive {
    /// Opens a KITTI sequence, an NCLT session (detected from the directory contents) or a
    /// rosbag2 recording (topics chosen automatically). A KITTI dataset root
    /// (`sequences/NN/`, `poses/NN.txt`) holding exactly one sequence opens that sequence.
    pub fn open(dir: &Path) -> Result<Self> {
        Self::open_with(dir, &SweepOptions::default())
    }

    /// Opens a drive like [`Drive::open`], with the topic choice of `options` for bags.
    ///
    /// Fails when the drive has no odometry: an NCLT session without odometry covering every
    /// scan time, a KITTI sequence or bag without a pose for every scan.
    pub fn open_with(path: &Path, options: &SweepOptions) -> Result<Self> {
        Self::from_sweeps(SweepSequence::open(path, options)?)
    }

    /// A drive over a sweep sequence: its reference poses are the ground truth; its odometry
    /// is the odometry track, or (KITTI, bags) the reference when the source has none.
    pub fn from_sweeps(mut sweeps: SweepSequence) -> Result<Self> {
        let missing = |what: &str| PoleError::Sequence {
            path: sweeps.name.clone(),
            reason: what.to_owned(),
        };
        let ground_truth = sweeps.reference.take();
        let odometry = match (sweeps.odometry.take(), sweeps.format) {
            (Some(odometry), _) => odometry,
            (None, SweepFormat::Nclt) => {
                return Err(missing(
                    "the NCLT session has no odometry covering every scan time \
                     (odometry_mu_100hz.csv)",
                ));
            }
            (None, SweepFormat::Kitti) => ground_truth.clone().ok_or_else(|| {
                missing(
                    "the KITTI sequence has no pose for every scan in poses.txt (KITTI \
                     odometry comes from the poses)",
                )
            })?,
            (None, SweepFormat::Bag) => ground_truth.clone().ok_or_else(|| {
                missing("the bag has neither odometry nor reference poses for every sweep")
            })?,
            (None, SweepFormat::Ouster) => ground_truth.clone().ok_or_else(|| {
                missing(
                    "the Ouster capture has no poses for its frames (<capture stem>_poses_kitti.txt \
                     beside the .pcap)",
                )
            })?,
        };
        Ok(Self {
            dir: sweeps.name.clone(),
            format: DriveFormat::of(sweeps.format),
            stamps_secs: sweeps.stamps_secs.clone(),
            ground_truth,
            odometry,
            odometry_std: sweeps.odometry_std.take(),
            sweep_timing: None,
            sweeps,
        })
    }

    /// A drive from parts held in memory: `name` (used in errors in place of a directory),
    /// the layout its conventions follow (`format` selects the preset and the odometry
    /// noise in the CLI), scan times (seconds, strictly increasing), the ground-truth
    /// `world_from_sensor` per scan when known, the odometry `odom_from_sensor` per scan,
    /// and `scan`, which returns scan `index` (points in the sensor frame, REP-103 axes,
    /// metres) for `index < stamps_secs.len()`. Errors of `scan` become errors naming the
    /// drive and the scan (sweep) index.
    ///
    /// Fails when the tracks do not have one pose per time or the times are not strictly
    /// increasing.
    pub fn from_fn(
        name: &str,
        format: DriveFormat,
        stamps_secs: Vec<f64>,
        ground_truth: Option<Vec<Pose3>>,
        odometry: Vec<Pose3>,
        scan: ScanFn,
    ) -> Result<Self> {
        let sweeps = SweepSequence::from_fn(
            name,
            format.sweep_format(),
            stamps_secs,
            ground_truth,
            Some(odometry),
            scan,
        )?;
        Self::from_sweeps(sweeps)
    }

    /// The layout the drive was read from, telling bags ([`SweepFormat::Bag`]) apart.
    pub fn sweep_format(&self) -> SweepFormat {
        self.sweeps.format
    }

    /// Number of scans.
    pub fn len(&self) -> usize {
        self.stamps_secs.len()
    }

    /// True when the drive has no scans.
    pub fn is_empty(&self) -> bool {
        self.stamps_secs.is_empty()
    }

    /// Reads scan `index` (points in the sensor frame, REP-103 axes).
    pub fn scan(&self, index: usize) -> Result<PointCloud> {
        if index >= self.len() {
            return Err(PoleError::Sequence {
                path: self.dir.clone(),
                reason: format!("no scan {index}"),
            });
        }
        Ok(self.sweeps.sweep(index)?)
    }

    /// Total number of points of all scans (from file sizes where the layout allows; other
    /// drives produce every scan to count them).
    pub fn count_points(&self) -> Result<u64> {
        Ok(self.sweeps.count_points()?)
    }

    /// The ground truth, or an error naming the drive.
    pub fn require_ground_truth(&self) -> Result<&[Pose3]> {
        self.ground_truth
            .as_deref()
            .ok_or_else(|| PoleError::Sequence {
                path: self.dir.clone(),
                reason: "no ground-truth poses".into(),
            })
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Point3;

    use super::*;

    /// A drive of `n` scans 1 m apart; scan `i` holds `i + 1` points at x = i.
    fn memory_drive(n: usize) -> Result<Drive> {
        let poses: Vec<Pose3> = (0..n)
            .map(|i| Pose3::from_xyz_rpy(i as f64, 0.0, 0.0, 0.0, 0.0, 0.0))
            .collect();
        Drive::from_fn(
            "memory 00",
            DriveFormat::Kitti,
            (0..n).map(|i| i as f64 * 0.1).collect(),
            Some(poses.clone()),
            poses,
            Box::new(|i| {
                if i == 3 {
                    return Err("simulated failure".into());
                }
                Ok(PointCloud::from_points(vec![
                    Point3::new(i as f32, 0.0, 0.0);
                    i + 1
                ]))
            }),
        )
    }

    #[test]
    fn in_memory_drive_streams_scans_and_names_itself_in_errors() {
        let drive = memory_drive(5).unwrap();
        assert_eq!(drive.len(), 5);
        assert_eq!(drive.format, DriveFormat::Kitti);
        assert_eq!(drive.require_ground_truth().unwrap().len(), 5);
        let scan = drive.scan(2).unwrap();
        assert_eq!(scan.len(), 3);
        assert_eq!(scan.points[0].x, 2.0);
        let failed = drive.scan(3).unwrap_err().to_string();
        assert!(
            failed.contains("memory 00")
                && failed.contains("sweep 3")
                && failed.contains("simulated failure"),
            "{failed}"
        );
        let past = drive.scan(5).unwrap_err().to_string();
        assert!(
            past.contains("memory 00") && past.contains("no scan 5"),
            "{past}"
        );
        // Counting produces every scan: the failing one is reported.
        assert!(drive.count_points().is_err());
        let ok = memory_drive(3).unwrap();
        assert_eq!(ok.count_points().unwrap(), 1 + 2 + 3);
    }

    #[test]
    fn in_memory_drive_checks_its_parts() {
        let pose = Pose3::identity();
        let scans = || -> ScanFn { Box::new(|_| Ok(PointCloud::from_points(Vec::new()))) };
        let short_odometry = Drive::from_fn(
            "d",
            DriveFormat::Nclt,
            vec![0.0, 1.0],
            None,
            vec![pose],
            scans(),
        );
        assert!(short_odometry.is_err());
        let short_truth = Drive::from_fn(
            "d",
            DriveFormat::Nclt,
            vec![0.0, 1.0],
            Some(vec![pose; 3]),
            vec![pose; 2],
            scans(),
        );
        assert!(short_truth.is_err());
        let not_increasing = Drive::from_fn(
            "d",
            DriveFormat::Nclt,
            vec![1.0, 1.0],
            None,
            vec![pose; 2],
            scans(),
        )
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
        assert!(
            not_increasing.contains("not strictly increasing"),
            "{not_increasing}"
        );
        let drive = Drive::from_fn(
            "d",
            DriveFormat::Nclt,
            vec![0.0, 1.0],
            None,
            vec![pose; 2],
            scans(),
        )
        .unwrap();
        assert!(drive.require_ground_truth().is_err());
    }

    /// A KITTI sequence of three scans on disk, written with the raypath-io writers.
    fn kitti_on_disk(dir: &Path, with_poses: bool) -> Vec<Pose3> {
        use nalgebra::Matrix3x4;
        use raypath_io::kitti;
        std::fs::create_dir_all(dir.join("velodyne")).unwrap();
        let world_from_velo: Vec<Pose3> = (0..3)
            .map(|i| Pose3::from_xyz_rpy(i as f64, 0.5 * i as f64, 0.0, 0.0, 0.0, 0.1 * i as f64))
            .collect();
        for i in 0..3 {
            let cloud = PointCloud::from_points(vec![Point3::new(i as f32, 1.0, 2.0); i + 2]);
            kitti::write_velodyne(&dir.join(format!("velodyne/{i:06}.bin")), &cloud).unwrap();
        }
        let cam0_from_velo = Pose3::from_matrix3x4(&Matrix3x4::new(
            0.0, -1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0,
        ));
        if with_poses {
            let cam = kitti::cam0_poses_from_velodyne(&world_from_velo, &cam0_from_velo);
            kitti::write_poses(&dir.join("poses.txt"), &cam).unwrap();
        }
        kitti::write_times(&dir.join("times.txt"), &[0.0, 0.1, 0.2]).unwrap();
        let p = "7.0 0 6.0 0 0 7.0 1.8 0 0 0 1 0";
        std::fs::write(
            dir.join("calib.txt"),
            format!("P0: {p}\nP1: {p}\nP2: {p}\nP3: {p}\nTr: 0 -1 0 0 0 0 -1 0 1 0 0 0\n"),
        )
        .unwrap();
        world_from_velo
    }

    #[test]
    fn kitti_drive_reads_scans_and_velodyne_poses() {
        let tmp = tempfile::tempdir().unwrap();
        let seq = tmp.path().join("00");
        let truth = kitti_on_disk(&seq, true);
        let drive = Drive::open(&seq).unwrap();
        assert_eq!(drive.format, DriveFormat::Kitti);
        assert_eq!(drive.sweep_format(), SweepFormat::Kitti);
        assert_eq!(drive.stamps_secs, [0.0, 0.1, 0.2]);
        let gt = drive.require_ground_truth().unwrap();
        for (read, given) in gt.iter().zip(&truth) {
            assert!((read.translation() - given.translation()).norm() < 1e-6);
            assert!(read.rotation().angle_to(&given.rotation()) < 1e-6);
        }
        // KITTI has no odometry: the odometry track is the ground truth.
        assert_eq!(drive.odometry, gt);
        assert_eq!(drive.scan(1).unwrap().len(), 3);
        assert_eq!(drive.count_points().unwrap(), 2 + 3 + 4);
        assert!(drive.scan(3).unwrap_err().to_string().contains("no scan 3"));

        let bare = tmp.path().join("01");
        kitti_on_disk(&bare, false);
        let error = Drive::open(&bare)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            error.contains("01") && error.contains("poses.txt"),
            "{error}"
        );
    }

    #[test]
    fn bag_drives_follow_kitti_and_fall_back_to_the_reference() {
        let reference: Vec<Pose3> = (0..2)
            .map(|i| Pose3::from_xyz_rpy(i as f64, 0.0, 0.0, 0.0, 0.0, 0.0))
            .collect();
        let sweeps = |reference: Option<Vec<Pose3>>| {
            SweepSequence::from_fn(
                "bag.mcap",
                SweepFormat::Bag,
                vec![0.0, 0.1],
                reference,
                None,
                Box::new(|_| Ok(PointCloud::from_points(Vec::new()))),
            )
            .unwrap()
        };
        let drive = Drive::from_sweeps(sweeps(Some(reference.clone()))).unwrap();
        assert_eq!(drive.format, DriveFormat::Kitti);
        assert_eq!(drive.sweep_format(), SweepFormat::Bag);
        assert_eq!(drive.odometry, reference);
        assert_eq!(drive.ground_truth.as_deref(), Some(reference.as_slice()));
        let error = Drive::from_sweeps(sweeps(None))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(error.starts_with("bag.mcap: "), "{error}");
    }
}
