//! A recorded drive in KITTI or NCLT layout: scan times, ground-truth and odometry sensor
//! poses per scan, and the scans themselves (read one at a time).
//!
//! * **KITTI** (`…/sequences/NN/` or a directory with `velodyne/`, `poses.txt`, `times.txt`,
//!   `calib.txt`): sensor poses `world_from_velo = velo_from_cam0 · world_from_cam0 ·
//!   cam0_from_velo` (the velodyne frame of the first scan is the world frame, as the
//!   semi-synthetic pole maps). KITTI has no odometry: the odometry track is the ground truth
//!   (evaluations corrupt its increments).
//! * **NCLT** (a session directory): scans from `velodyne_sync/` turned to REP-103 axes, the
//!   ground truth and the integrated odometry (`odometry_mu_100hz.csv`) interpolated at the
//!   scan times, in REP-103 frames (`NcltPose::world_from_body`; the body frame is the
//!   velodyne frame in the simulated sessions — spec errata 24: no extrinsic applied).
//! * **In memory** ([`Drive::from_fn`]): times and poses given by the caller, scans produced
//!   on demand by a function (e.g. simulated, `raypath_sim::semi_kitti::SemiKittiDrive`), so
//!   an evaluation streams a drive without writing its scans to disk.

use std::path::{Path, PathBuf};

use raypath_geometry::{PointCloud, Pose3};
use raypath_io::kitti::{self, KittiSequence};
use raypath_io::nclt::{self, NcltPose, NcltSession};
use raypath_localizer::PoseTrack;

use crate::error::{PoleError, Result};

/// The layout a drive was read from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DriveFormat {
    /// KITTI odometry layout.
    Kitti,
    /// NCLT session layout.
    Nclt,
}

/// The error a scan function of an in-memory drive may return.
pub type ScanError = Box<dyn std::error::Error + Send + Sync>;

/// A scan source of an in-memory drive: scan `index` → points in the sensor frame.
pub type ScanFn = Box<dyn Fn(usize) -> std::result::Result<PointCloud, ScanError> + Send + Sync>;

enum Source {
    Kitti { sequence: KittiSequence },
    Nclt { session: NcltSession },
    Memory { scan: ScanFn },
}

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
    source: Source,
}

impl Drive {
    /// Opens a KITTI sequence or an NCLT session (detected from the directory contents).
    /// A KITTI dataset root (`sequences/NN/`, `poses/NN.txt`) holding exactly one sequence
    /// opens that sequence.
    pub fn open(dir: &Path) -> Result<Self> {
        let has = |p: &str| dir.join(p).exists();
        if has("sequences") && !has("velodyne") {
            let mut sequences: Vec<PathBuf> = std::fs::read_dir(dir.join("sequences"))
                .map(|it| it.filter_map(|e| e.ok().map(|e| e.path())).collect())
                .unwrap_or_default();
            sequences.retain(|p| p.is_dir());
            sequences.sort();
            return match sequences.as_slice() {
                [one] => Self::open(one),
                _ => Err(PoleError::Sequence {
                    path: dir.to_path_buf(),
                    reason: format!(
                        "a KITTI root with {} sequences under sequences/: name one (e.g. {})",
                        sequences.len(),
                        dir.join("sequences/00").display()
                    ),
                }),
            };
        }
        if has("velodyne") || has("poses.txt") || has("calib.txt") || has("times.txt") {
            return Self::open_kitti(dir);
        }
        Self::open_nclt(dir)
    }

    /// A drive from parts held in memory: `name` (used in errors in place of a directory),
    /// the layout its conventions follow (`format` selects the preset and the odometry
    /// noise in the CLI), scan times (seconds, strictly increasing), the ground-truth
    /// `world_from_sensor` per scan when known, the odometry `odom_from_sensor` per scan,
    /// and `scan`, which returns scan `index` (points in the sensor frame, REP-103 axes,
    /// metres) for `index < stamps_secs.len()`. Errors of `scan` become
    /// [`PoleError::Sequence`] naming the drive and the scan index.
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
        let dir = PathBuf::from(name);
        let mismatch = |what: &str, n: usize| PoleError::Sequence {
            path: dir.clone(),
            reason: format!("{n} {what} for {} scan times", stamps_secs.len()),
        };
        if odometry.len() != stamps_secs.len() {
            return Err(mismatch("odometry poses", odometry.len()));
        }
        if let Some(gt) = &ground_truth
            && gt.len() != stamps_secs.len()
        {
            return Err(mismatch("ground-truth poses", gt.len()));
        }
        check_increasing(&dir, &stamps_secs)?;
        Ok(Self {
            dir,
            format,
            stamps_secs,
            ground_truth,
            odometry,
            odometry_std: None,
            source: Source::Memory { scan },
        })
    }

    fn open_kitti(dir: &Path) -> Result<Self> {
        let sequence = KittiSequence::open(dir)?;
        let missing = |what: &str| PoleError::Sequence {
            path: dir.to_path_buf(),
            reason: format!("the KITTI sequence has no {what}"),
        };
        if sequence.scan_files.is_empty() {
            return Err(missing("velodyne scans"));
        }
        let times = sequence.times()?;
        let cam0_from_velo = match sequence.calib()? {
            Some(calib) => calib
                .cam0_from_velo()
                .ok_or_else(|| missing("Tr in calib.txt"))?,
            None => return Err(missing("calib.txt")),
        };
        let poses = sequence.poses()?;
        let world_from_velo = kitti::velodyne_poses_from_cam0(&poses, &cam0_from_velo);
        let mut stamps = Vec::with_capacity(sequence.scan_files.len());
        let mut gt = Vec::with_capacity(sequence.scan_files.len());
        for file in &sequence.scan_files {
            let frame = file.frame as usize;
            let t = times
                .get(frame)
                .copied()
                .ok_or_else(|| missing(&format!("time for frame {frame} in times.txt")))?;
            stamps.push(t);
            if let Some(p) = world_from_velo.get(frame) {
                gt.push(*p);
            }
        }
        check_increasing(dir, &stamps)?;
        let ground_truth = (gt.len() == stamps.len()).then_some(gt);
        let odometry = ground_truth.clone().ok_or_else(|| {
            missing("pose for every scan in poses.txt (KITTI odometry comes from the poses)")
        })?;
        Ok(Self {
            dir: dir.to_path_buf(),
            format: DriveFormat::Kitti,
            stamps_secs: stamps,
            ground_truth,
            odometry,
            odometry_std: None,
            source: Source::Kitti { sequence },
        })
    }

    fn open_nclt(dir: &Path) -> Result<Self> {
        let session = NcltSession::open(dir)?;
        let missing = |what: &str| PoleError::Sequence {
            path: dir.to_path_buf(),
            reason: format!("the NCLT session has no {what}"),
        };
        if session.sync_files.is_empty() {
            return Err(missing("velodyne_sync scans"));
        }
        let stamps: Vec<f64> = session
            .sync_files
            .iter()
            .map(|f| nclt::utime_to_secs(f.utime))
            .collect();
        check_increasing(dir, &stamps)?;
        let track = |rows: &[NcltPose], what: &str| -> Result<PoseTrack<Pose3>> {
            let mut stamps_secs = Vec::with_capacity(rows.len());
            let mut poses = Vec::with_capacity(rows.len());
            for r in rows {
                let t = r.stamp_secs();
                if stamps_secs.last().is_some_and(|&last| t <= last) {
                    continue;
                }
                stamps_secs.push(t);
                poses.push(r.world_from_body());
            }
            PoseTrack::from_parts(stamps_secs, poses).map_err(|e| PoleError::Sequence {
                path: dir.to_path_buf(),
                reason: format!("{what}: {e}"),
            })
        };
        let sample = |track: &PoseTrack<Pose3>| -> Option<Vec<Pose3>> {
            stamps.iter().map(|&t| track.pose_at(t).ok()).collect()
        };
        let ground_truth = match session.ground_truth_path {
            Some(_) => sample(&track(&session.ground_truth()?.poses, "ground truth")?),
            None => None,
        };
        let odometry = match session.odometry_path {
            Some(_) => sample(&track(&session.odometry()?.poses, "odometry")?)
                .ok_or_else(|| missing("odometry covering every scan time"))?,
            None => return Err(missing("odometry_mu_100hz.csv")),
        };
        let odometry_std = match session.relative_odometry_cov_path {
            Some(_) => {
                let cov = session.relative_odometry_cov()?;
                let times: Vec<f64> = cov
                    .records
                    .iter()
                    .map(|r| nclt::utime_to_secs(r.utime))
                    .collect();
                (!cov.records.is_empty()).then(|| {
                    stamps
                        .iter()
                        .map(|&t| {
                            let k = times.partition_point(|&s| s < t).min(times.len() - 1);
                            let m = &cov.records[k].matrix;
                            [m[(0, 0)], m[(1, 1)], m[(5, 5)]].map(|v| v.max(0.0).sqrt())
                        })
                        .collect()
                })
            }
            None => None,
        };
        Ok(Self {
            dir: dir.to_path_buf(),
            format: DriveFormat::Nclt,
            stamps_secs: stamps,
            ground_truth,
            odometry,
            odometry_std,
            source: Source::Nclt { session },
        })
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
        let out_of_range = || PoleError::Sequence {
            path: self.dir.clone(),
            reason: format!("no scan {index}"),
        };
        match &self.source {
            Source::Kitti { sequence } => {
                let file = sequence.scan_files.get(index).ok_or_else(out_of_range)?;
                Ok(kitti::read_velodyne(&file.path)?)
            }
            Source::Nclt { session } => {
                let file = session.sync_files.get(index).ok_or_else(out_of_range)?;
                let mut cloud = nclt::read_velodyne_sync(&file.path)?;
                nclt::flu_from_frd(&mut cloud);
                Ok(cloud)
            }
            Source::Memory { scan } => {
                if index >= self.len() {
                    return Err(out_of_range());
                }
                scan(index).map_err(|e| PoleError::Sequence {
                    path: self.dir.clone(),
                    reason: format!("scan {index}: {e}"),
                })
            }
        }
    }

    /// Total number of points of all scans (from file sizes; an in-memory drive produces
    /// every scan to count them).
    pub fn count_points(&self) -> Result<u64> {
        Ok(match &self.source {
            Source::Kitti { sequence } => sequence.count_points()?,
            Source::Nclt { session } => session.count_points()?,
            Source::Memory { .. } => {
                let mut total = 0;
                for i in 0..self.len() {
                    total += self.scan(i)?.len() as u64;
                }
                total
            }
        })
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

fn check_increasing(dir: &Path, stamps: &[f64]) -> Result<()> {
    if let Some(k) = stamps
        .windows(2)
        .position(|w| !(w[0].is_finite() && w[1].is_finite() && w[1] > w[0]))
    {
        return Err(PoleError::Sequence {
            path: dir.to_path_buf(),
            reason: format!("scan times are not strictly increasing at scan {}", k + 1),
        });
    }
    Ok(())
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
                && failed.contains("scan 3")
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
}
