//! A drive for pole mapping and localization: a [`SweepSequence`] of `raypath-io` (KITTI
//! sequences, NCLT sessions, rosbag2 recordings, Ouster captures or sweeps produced in
//! memory, read by `raypath-io`) with an odometry track for every scan
//! ([`SweepSequence::with_odometry_or_reference`]), plus what the pole pipeline adds: the
//! layout's conventions for presets and odometry noise ([`DriveFormat`]) and, for de-skewed
//! sweeps, their timing ([`Drive::sweep_timing`]).

use std::path::Path;

use raypath_geometry::Pose3;
use raypath_io::sequence::{SweepFormat, SweepOptions, SweepSequence};

use crate::error::Result;
#[cfg(doc)]
use crate::sweep::SweepMotion;
use crate::sweep::SweepTiming;

/// The layout a drive was read from, as far as presets and odometry noise go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DriveFormat {
    /// KITTI odometry layout (and rosbag2 recordings and Ouster captures, which follow its
    /// conventions).
    Kitti,
    /// NCLT session layout.
    Nclt,
}

impl DriveFormat {
    /// The drive conventions of a sweep layout: a bag or an Ouster capture follows KITTI's (no
    /// recorded odometry covariance; the odometry falls back to the reference poses).
    pub fn of(format: SweepFormat) -> Self {
        match format {
            SweepFormat::Nclt => DriveFormat::Nclt,
            SweepFormat::Kitti | SweepFormat::Bag | SweepFormat::Ouster => DriveFormat::Kitti,
        }
    }
}

/// A drive: per scan a time, a ground-truth sensor pose (the sequence's reference, when
/// known) and an odometry pose, and the scans, read on demand.
pub struct Drive {
    /// The scans and their times, reference (ground-truth) `world_from_sensor` poses, odometry
    /// `odom_from_sensor` poses (present for every scan: the constructors make sure) and
    /// stated odometry standard deviations.
    pub sweeps: SweepSequence,
    /// When the scans are de-skewed sweeps of a moving sensor, their timing: local maps then
    /// trace every ray from where the sensor was when it measured the point
    /// ([`SweepMotion::from_poses`] along the registration track). `None` (the default of
    /// every constructor): rays from each scan's origin, right for scans measured from one
    /// pose such as the simulated ones; set `Some(SweepTiming::kitti())` for real KITTI
    /// sweeps.
    pub sweep_timing: Option<SweepTiming>,
}

impl Drive {
    /// A drive over a sweep sequence; its odometry is the recorded one or, where the layout
    /// records none, the reference ([`SweepSequence::with_odometry_or_reference`]: fails
    /// for an NCLT session without odometry covering every scan time, and for a KITTI
    /// sequence, bag or capture without a pose for every scan).
    pub fn new(sweeps: SweepSequence) -> Result<Self> {
        Ok(Self {
            sweeps: sweeps.with_odometry_or_reference()?,
            sweep_timing: None,
        })
    }

    /// Opens a KITTI sequence, an NCLT session, a rosbag2 recording (topics chosen
    /// automatically) or an Ouster capture ([`SweepSequence::open`]) as a drive.
    pub fn open(path: &Path) -> Result<Self> {
        Self::new(SweepSequence::open(path, &SweepOptions::default())?)
    }

    /// The drive conventions of the layout.
    pub fn format(&self) -> DriveFormat {
        DriveFormat::of(self.sweeps.format)
    }

    /// Number of scans.
    pub fn len(&self) -> usize {
        self.sweeps.len()
    }

    /// True when the drive has no scans.
    pub fn is_empty(&self) -> bool {
        self.sweeps.is_empty()
    }

    /// The odometry `odom_from_sensor` per scan (empty only if the caller removed it from
    /// [`Drive::sweeps`]).
    pub fn odometry(&self) -> &[Pose3] {
        self.sweeps.odometry.as_deref().unwrap_or_default()
    }

    /// The ground truth (the sequence's reference poses), or an error naming the drive.
    pub fn require_ground_truth(&self) -> Result<&[Pose3]> {
        Ok(self.sweeps.require_reference()?)
    }
}

#[cfg(test)]
mod tests {
    use raypath_geometry::PointCloud;

    use super::*;

    fn sequence(format: SweepFormat, reference: Option<Vec<Pose3>>) -> SweepSequence {
        SweepSequence::from_fn(
            "drive",
            format,
            vec![0.0, 0.1],
            reference,
            None,
            Box::new(|_| Ok(PointCloud::from_points(Vec::new()))),
        )
        .unwrap()
    }

    #[test]
    fn bags_and_captures_follow_kitti_and_fall_back_to_the_reference() {
        let reference: Vec<Pose3> = (0..2)
            .map(|i| Pose3::from_xyz_rpy(i as f64, 0.0, 0.0, 0.0, 0.0, 0.0))
            .collect();
        for format in [SweepFormat::Kitti, SweepFormat::Bag, SweepFormat::Ouster] {
            let drive = Drive::new(sequence(format, Some(reference.clone()))).unwrap();
            assert_eq!(drive.format(), DriveFormat::Kitti);
            assert_eq!(drive.sweeps.format, format);
            assert_eq!(drive.odometry(), reference.as_slice());
            assert_eq!(drive.require_ground_truth().unwrap(), reference.as_slice());
            assert_eq!(drive.sweep_timing, None);
        }
        let error = Drive::new(sequence(SweepFormat::Bag, None))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(error.starts_with("drive: "), "{error}");
        assert!(Drive::new(sequence(SweepFormat::Nclt, Some(reference))).is_err());
    }

    #[test]
    fn a_drive_without_ground_truth_says_so() {
        let odometry = vec![Pose3::identity(); 2];
        let sweeps = SweepSequence::from_fn(
            "memory 00",
            SweepFormat::Nclt,
            vec![0.0, 1.0],
            None,
            Some(odometry.clone()),
            Box::new(|_| Ok(PointCloud::from_points(Vec::new()))),
        )
        .unwrap();
        let drive = Drive::new(sweeps).unwrap();
        assert_eq!(drive.format(), DriveFormat::Nclt);
        assert_eq!((drive.len(), drive.odometry()), (2, odometry.as_slice()));
        let error = drive.require_ground_truth().unwrap_err().to_string();
        assert!(error.contains("memory 00"), "{error}");
    }
}
