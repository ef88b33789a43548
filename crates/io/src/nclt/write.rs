//! Writing NCLT files: `velodyne_sync` revolutions, pose CSVs (ground truth, odometry) and
//! covariance CSVs, in the layout [`NcltSession::open`](super::NcltSession::open) discovers.
//!
//! * **Velodyne coordinates** are stored as `u16` with `metres = raw · 0.005 − 100`, so only
//!   `[−100, 227.675]` m is representable (rounded to the nearest 5 mm). A point outside that
//!   range is **refused** with an [`Error::Unwritable`] naming the point and the coordinate
//!   (no silent clamping: a clamped point would be a wrong return). Intensities (0–255) and
//!   laser ids (the cloud's `label`, 0–255) are rounded bytes; values outside are refused too.
//!   Points are written as given, in the stored velodyne frame (x forward, y right, z down):
//!   apply [`flu_from_frd`](super::flu_from_frd) (its own inverse) to a REP-103 cloud first.
//! * **CSV rows** have no header: `utime` as an integer, positions with 6 decimals (µm),
//!   angles with 9 decimals (nrad), covariance entries in C `%.9e` style. Values that round to
//!   zero are written without a sign (no `-0.000000`).
//!
//! [`NcltPose::from_world_from_body`] converts a REP-103 pose to the stored NED convention
//! (the exact inverse of [`NcltPose::world_from_body`]), and [`NcltPose::from_increment`] a
//! REP-103 body-frame increment to the stored x forward, y right, z down convention.

use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use raypath_geometry::{PointCloud, Pose3};

use super::csv::{CovarianceRecord, NcltPose};
use super::velodyne::{OFFSET_M, RECORD_BYTES, SCALE_M};
use crate::kitti::{push_exp, write_file};
use crate::{Error, Location, Result};

/// Decimals of positions in pose CSVs (micrometres).
const POSITION_DECIMALS: usize = 6;
/// Decimals of angles in pose CSVs (nanoradians).
const ANGLE_DECIMALS: usize = 9;
/// Digits after the point of covariance entries (`%.9e`).
const COVARIANCE_DIGITS: usize = 9;

/// The raw `u16` of a coordinate in metres (nearest of `raw · 0.005 − 100`), `None` outside
/// the representable `[−100, 227.675]` m or for non-finite input.
pub fn encode_coordinate(metres: f64) -> Option<u16> {
    let raw = ((metres - OFFSET_M) / SCALE_M).round();
    (raw.is_finite() && (0.0..=f64::from(u16::MAX)).contains(&raw)).then_some(raw as u16)
}

/// Encodes a revolution as the bytes of a `velodyne_sync` file: 8 bytes a point (three `u16`
/// coordinates, `u8` intensity, `u8` laser id). Points with non-finite coordinates (missing
/// pixels of an organized cloud) are left out; everything else must be representable.
pub fn encode_velodyne_sync(cloud: &PointCloud, name: &Path) -> Result<Vec<u8>> {
    let unwritable = |reason: String| Error::Unwritable {
        path: name.to_path_buf(),
        reason,
    };
    for (what, len) in [
        ("intensities", cloud.intensity.as_ref().map(Vec::len)),
        ("laser ids", cloud.label.as_ref().map(Vec::len)),
    ] {
        if let Some(len) = len.filter(|&l| l != cloud.len()) {
            return Err(unwritable(format!(
                "{len} {what} for {} points",
                cloud.len()
            )));
        }
    }
    let mut bytes = Vec::with_capacity(cloud.len() * RECORD_BYTES as usize);
    for (i, p) in cloud.points.iter().enumerate() {
        if !p.iter().all(|v| v.is_finite()) {
            continue;
        }
        for (axis, v) in ["x", "y", "z"].iter().zip(p.iter()) {
            let raw = encode_coordinate(f64::from(*v)).ok_or_else(|| {
                unwritable(format!(
                    "point {i}: {axis} = {v} m is outside the representable range \
                     [{OFFSET_M}, {}] m",
                    f64::from(u16::MAX) * SCALE_M + OFFSET_M
                ))
            })?;
            bytes.extend_from_slice(&raw.to_le_bytes());
        }
        let intensity = cloud
            .intensity
            .as_ref()
            .and_then(|v| v.get(i).copied())
            .unwrap_or(0.0)
            .round();
        if !(0.0..=255.0).contains(&intensity) {
            return Err(unwritable(format!(
                "point {i}: intensity {intensity} is not in 0–255"
            )));
        }
        let laser = cloud
            .label
            .as_ref()
            .and_then(|v| v.get(i).copied())
            .unwrap_or(0);
        let laser = u8::try_from(laser)
            .map_err(|_| unwritable(format!("point {i}: laser id {laser} is not in 0–255")))?;
        bytes.push(intensity as u8);
        bytes.push(laser);
    }
    Ok(bytes)
}

/// Writes a revolution to `path` ([`encode_velodyne_sync`]); returns the number of points
/// written.
pub fn write_velodyne_sync(path: &Path, cloud: &PointCloud) -> Result<u64> {
    let bytes = encode_velodyne_sync(cloud, path)?;
    std::fs::write(path, &bytes).map_err(|e| Error::io(path, Location::File, e))?;
    Ok(bytes.len() as u64 / RECORD_BYTES)
}

/// Writes pose rows `utime,x,y,z,roll,pitch,yaw` (ground truth or odometry) to `writer`;
/// `name` names the destination in errors. Values must be finite.
pub fn write_pose_csv_to(mut writer: impl Write, poses: &[NcltPose], name: &Path) -> Result<()> {
    let mut line = String::with_capacity(128);
    for (i, pose) in poses.iter().enumerate() {
        let values = pose.xyz.iter().chain(pose.rpy.iter());
        if let Some(bad) = values.clone().find(|v| !v.is_finite()) {
            return Err(Error::Unwritable {
                path: name.to_path_buf(),
                reason: format!("row {i} holds {bad}"),
            });
        }
        line.clear();
        let _ = write!(line, "{}", pose.utime);
        for (k, v) in values.enumerate() {
            let decimals = if k < 3 {
                POSITION_DECIMALS
            } else {
                ANGLE_DECIMALS
            };
            push_fixed(&mut line, *v, decimals);
        }
        line.push('\n');
        writer
            .write_all(line.as_bytes())
            .map_err(|e| Error::io(name, Location::File, e))?;
    }
    Ok(())
}

/// Appends `,` and `value` with `decimals` decimals; values that round to zero are written
/// without a sign.
fn push_fixed(line: &mut String, value: f64, decimals: usize) {
    let start = line.len() + 1;
    let _ = write!(line, ",{value:.decimals$}");
    let written = line.get(start..).unwrap_or_default();
    if written.starts_with('-') && written.bytes().all(|b| matches!(b, b'-' | b'0' | b'.')) {
        line.remove(start);
    }
}

/// Writes a pose CSV ([`write_pose_csv_to`]).
pub fn write_pose_csv(path: &Path, poses: &[NcltPose]) -> Result<()> {
    write_file(path, |w| write_pose_csv_to(w, poses, path))
}

/// Writes covariance rows: `utime` and the 21 upper-triangle entries of each 6×6 matrix, row
/// by row. Entries must be finite.
pub fn write_covariance_csv_to(
    mut writer: impl Write,
    records: &[CovarianceRecord],
    name: &Path,
) -> Result<()> {
    let mut line = String::with_capacity(400);
    for (i, record) in records.iter().enumerate() {
        line.clear();
        let _ = write!(line, "{}", record.utime);
        for r in 0..6 {
            for c in r..6 {
                let v = record.matrix[(r, c)];
                if !v.is_finite() {
                    return Err(Error::Unwritable {
                        path: name.to_path_buf(),
                        reason: format!("row {i}: entry ({r}, {c}) is {v}"),
                    });
                }
                line.push(',');
                push_exp(&mut line, v, COVARIANCE_DIGITS);
            }
        }
        line.push('\n');
        writer
            .write_all(line.as_bytes())
            .map_err(|e| Error::io(name, Location::File, e))?;
    }
    Ok(())
}

/// Writes a covariance CSV ([`write_covariance_csv_to`]).
pub fn write_covariance_csv(path: &Path, records: &[CovarianceRecord]) -> Result<()> {
    write_file(path, |w| write_covariance_csv_to(w, records, path))
}

/// x forward, y right, z down ↔ x forward, y left, z up (its own inverse).
fn frd_flu() -> Pose3 {
    Pose3::from_parts(
        Vector3::zeros(),
        UnitQuaternion::from_matrix(&Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0))),
    )
}

/// A pose row from a stored-convention pose (translation and roll, pitch, yaw).
fn row(utime: u64, pose: &Pose3) -> NcltPose {
    let t = pose.translation();
    let (roll, pitch, yaw) = pose.rpy();
    NcltPose {
        utime,
        xyz: [t.x, t.y, t.z],
        rpy: [roll, pitch, yaw],
    }
}

impl NcltPose {
    /// The stored row of a REP-103 pose (world x east, y north, z up; body x forward, y left,
    /// z up): `NED_FROM_ENU · world_from_body · FLU_FROM_FRD`, so that
    /// [`NcltPose::world_from_body`] gives `world_from_body` back.
    pub fn from_world_from_body(utime: u64, world_from_body: &Pose3) -> Self {
        // ENU_FROM_NED swaps x and y and negates z: it is its own inverse.
        let ned_from_enu = super::enu_from_ned();
        row(utime, &(ned_from_enu * *world_from_body * frd_flu()))
    }

    /// The stored row of a body-frame increment `previous_from_current` given in REP-103 body
    /// axes (x forward, y left, z up), expressed in the stored body axes (x forward, y right,
    /// z down) — as the relative odometry of `odometry_mu.csv`.
    pub fn from_increment(utime: u64, previous_from_current: &Pose3) -> Self {
        row(utime, &(frd_flu() * *previous_from_current * frd_flu()))
    }
}

/// Paths of one session in the data set's layout under `root` (`root/<date>/…`), which
/// [`NcltSession::open`](super::NcltSession::open) finds when given
/// [`NcltLayout::session_dir`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NcltLayout {
    /// The directory holding the session folders.
    pub root: PathBuf,
    /// The session date, `YYYY-MM-DD`.
    pub date: String,
}

impl NcltLayout {
    /// The layout of the session `date` under `root`.
    pub fn new(root: impl Into<PathBuf>, date: impl Into<String>) -> Self {
        Self {
            root: root.into(),
            date: date.into(),
        }
    }

    /// `root/<date>`.
    pub fn session_dir(&self) -> PathBuf {
        self.root.join(&self.date)
    }

    /// `root/<date>/velodyne_data/<date>_vel/velodyne_sync`.
    pub fn velodyne_sync_dir(&self) -> PathBuf {
        self.session_dir()
            .join("velodyne_data")
            .join(format!("{}_vel", self.date))
            .join("velodyne_sync")
    }

    /// `…/velodyne_sync/<utime>.bin`.
    pub fn scan_path(&self, utime: u64) -> PathBuf {
        self.velodyne_sync_dir().join(format!("{utime}.bin"))
    }

    /// `root/<date>/ground_truth/groundtruth_<date>.csv`.
    pub fn ground_truth_path(&self) -> PathBuf {
        self.session_dir()
            .join("ground_truth")
            .join(format!("groundtruth_{}.csv", self.date))
    }

    /// `root/<date>/ground_truth_cov/cov_<date>.csv`.
    pub fn ground_truth_cov_path(&self) -> PathBuf {
        self.session_dir()
            .join("ground_truth_cov")
            .join(format!("cov_{}.csv", self.date))
    }

    /// `root/<date>/sensor_data/<date>_sen`.
    pub fn sensor_dir(&self) -> PathBuf {
        self.session_dir()
            .join("sensor_data")
            .join(format!("{}_sen", self.date))
    }

    /// `…/<date>_sen/odometry_mu_100hz.csv` (integrated odometry).
    pub fn odometry_path(&self) -> PathBuf {
        self.sensor_dir().join("odometry_mu_100hz.csv")
    }

    /// `…/<date>_sen/odometry_cov_100hz.csv`.
    pub fn odometry_cov_path(&self) -> PathBuf {
        self.sensor_dir().join("odometry_cov_100hz.csv")
    }

    /// `…/<date>_sen/odometry_mu.csv` (relative increments).
    pub fn relative_odometry_path(&self) -> PathBuf {
        self.sensor_dir().join("odometry_mu.csv")
    }

    /// `…/<date>_sen/odometry_cov.csv` (covariances of the increments).
    pub fn relative_odometry_cov_path(&self) -> PathBuf {
        self.sensor_dir().join("odometry_cov.csv")
    }

    /// Creates the directories of all the files above.
    pub fn create_dirs(&self) -> Result<()> {
        let dirs = [
            self.velodyne_sync_dir(),
            self.session_dir().join("ground_truth"),
            self.session_dir().join("ground_truth_cov"),
            self.sensor_dir(),
        ];
        for dir in dirs {
            std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, Location::File, e))?;
        }
        Ok(())
    }
}
