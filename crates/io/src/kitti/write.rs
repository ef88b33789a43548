//! Writing KITTI odometry files: velodyne scans, poses, timestamps and calibration, in the
//! layout [`KittiSequence::open`](super::KittiSequence::open) discovers.
//!
//! Number formatting is fixed so that the same data always gives the same bytes:
//!
//! * poses and timestamps: C `%.9e` style (`1.000000000e+00`, ten significant digits; the
//!   benchmark's files print `%e` with seven) — round trips stay within 1e-9 relative;
//! * calibration entries: `key: ` and twelve numbers in `%.12e` style, as the benchmark's `Tr`
//!   line; entries in the order `P0`–`P3`, `Tr`, then other keys sorted;
//! * negative zero is written as zero.
//!
//! Frames follow the reader ([module documentation](super)): poses are `world_from_cam0` in
//! camera axes (x right, y down, z forward). [`cam0_poses_from_velodyne`] turns REP-103
//! velodyne poses into such camera poses, and [`velodyne_poses_from_cam0`] inverts it exactly.

use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use nalgebra::Matrix3x4;
use raypath_geometry::{PointCloud, Pose3};

use super::calib::KittiCalib;
use crate::{Error, Location, Result};

/// Significant digits after the point of poses and timestamps.
const POSE_DIGITS: usize = 9;
/// Digits after the point of calibration entries.
const CALIB_DIGITS: usize = 12;

/// Appends `value` in C `%.{digits}e` style (`-1.250000e-03`): a signed two-digit (or longer)
/// exponent. Negative zero is written as zero. The caller checks finiteness.
pub(crate) fn push_exp(out: &mut String, value: f64, digits: usize) {
    let value = value + 0.0; // −0 → +0
    let text = format!("{value:.digits$e}");
    match text.split_once('e') {
        Some((mantissa, exponent)) => {
            let exponent: i32 = exponent.parse().unwrap_or(0);
            let sign = if exponent < 0 { '-' } else { '+' };
            let _ = write!(out, "{mantissa}e{sign}{:02}", exponent.unsigned_abs());
        }
        None => out.push_str(&text),
    }
}

/// An [`Error::Unwritable`] for `name`.
fn unwritable(name: &Path, reason: impl Into<String>) -> Error {
    Error::Unwritable {
        path: name.to_path_buf(),
        reason: reason.into(),
    }
}

/// Creates `path` and hands a buffered writer to `write`, flushing at the end.
pub(crate) fn write_file(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<()>,
) -> Result<()> {
    let file = File::create(path).map_err(|e| Error::io(path, Location::File, e))?;
    let mut writer = BufWriter::new(file);
    write(&mut writer)?;
    writer
        .flush()
        .map_err(|e| Error::io(path, Location::File, e))
}

/// Encodes a scan as the bytes of a velodyne `.bin` file: 16 bytes a point, `f32` x, y, z and
/// reflectance, little-endian, in the velodyne frame (x forward, y left, z up, metres).
///
/// Points with non-finite coordinates (the missing pixels of an organized cloud) are left
/// out; the reflectance is the cloud's intensity (0 without one) and must be finite.
pub fn encode_velodyne(cloud: &PointCloud, name: &Path) -> Result<Vec<u8>> {
    if let Some(intensity) = &cloud.intensity
        && intensity.len() != cloud.len()
    {
        return Err(unwritable(
            name,
            format!("{} intensities for {} points", intensity.len(), cloud.len()),
        ));
    }
    let mut bytes = Vec::with_capacity(cloud.len() * 16);
    for (i, p) in cloud.points.iter().enumerate() {
        if !p.iter().all(|v| v.is_finite()) {
            continue;
        }
        let reflectance = cloud
            .intensity
            .as_ref()
            .and_then(|v| v.get(i).copied())
            .unwrap_or(0.0);
        if !reflectance.is_finite() {
            return Err(unwritable(
                name,
                format!("point {i} has reflectance {reflectance}"),
            ));
        }
        for v in [p.x, p.y, p.z, reflectance] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    Ok(bytes)
}

/// Writes a scan to the velodyne file `path` ([`encode_velodyne`]); returns the number of
/// points written.
pub fn write_velodyne(path: &Path, cloud: &PointCloud) -> Result<u64> {
    let bytes = encode_velodyne(cloud, path)?;
    std::fs::write(path, &bytes).map_err(|e| Error::io(path, Location::File, e))?;
    Ok(bytes.len() as u64 / super::VELODYNE_POINT_BYTES)
}

/// Writes poses (`world_from_cam0`, camera axes) to `writer`, one row-major 3×4 `[R | t]` a
/// line; `name` names the destination in errors. Fails on non-finite poses.
pub fn write_poses_to(mut writer: impl Write, poses: &[Pose3], name: &Path) -> Result<()> {
    let mut line = String::with_capacity(200);
    for (i, pose) in poses.iter().enumerate() {
        if !pose.is_finite() {
            return Err(unwritable(name, format!("pose {i} is not finite")));
        }
        let m: Matrix3x4<f64> = pose.to_matrix3x4();
        line.clear();
        for r in 0..3 {
            for c in 0..4 {
                if !line.is_empty() {
                    line.push(' ');
                }
                push_exp(&mut line, m[(r, c)], POSE_DIGITS);
            }
        }
        line.push('\n');
        writer
            .write_all(line.as_bytes())
            .map_err(|e| Error::io(name, Location::File, e))?;
    }
    Ok(())
}

/// Writes a pose file ([`write_poses_to`]).
pub fn write_poses(path: &Path, poses: &[Pose3]) -> Result<()> {
    write_file(path, |w| write_poses_to(w, poses, path))
}

/// Writes timestamps in seconds, one a line; they must be finite and non-decreasing (as the
/// reader requires).
pub fn write_times_to(mut writer: impl Write, times: &[f64], name: &Path) -> Result<()> {
    let mut line = String::with_capacity(24);
    let mut previous = f64::NEG_INFINITY;
    for (i, &t) in times.iter().enumerate() {
        if !t.is_finite() || t < previous {
            return Err(unwritable(
                name,
                format!(
                    "timestamp {i} is {t} s (after {previous} s); timestamps must be finite and non-decreasing"
                ),
            ));
        }
        previous = t;
        line.clear();
        push_exp(&mut line, t, POSE_DIGITS);
        line.push('\n');
        writer
            .write_all(line.as_bytes())
            .map_err(|e| Error::io(name, Location::File, e))?;
    }
    Ok(())
}

/// Writes a timestamp file ([`write_times_to`]).
pub fn write_times(path: &Path, times: &[f64]) -> Result<()> {
    write_file(path, |w| write_times_to(w, times, path))
}

/// Writes a calibration file: numeric entries as `key: v1 … vn` (`%.12e`), `P0`–`P3` and `Tr`
/// first, then the other numeric keys and the text entries, each group sorted.
pub fn write_calib_to(mut writer: impl Write, calib: &KittiCalib, name: &Path) -> Result<()> {
    const FIRST: [&str; 5] = ["P0", "P1", "P2", "P3", "Tr"];
    let ordered = FIRST
        .iter()
        .filter_map(|k| calib.numeric.get_key_value(*k))
        .chain(
            calib
                .numeric
                .iter()
                .filter(|(k, _)| !FIRST.contains(&k.as_str())),
        );
    let mut text = String::new();
    for (key, values) in ordered {
        check_key(key, name)?;
        text.push_str(key);
        text.push(':');
        for v in values {
            if !v.is_finite() {
                return Err(unwritable(name, format!("{key} holds {v}")));
            }
            text.push(' ');
            push_exp(&mut text, *v, CALIB_DIGITS);
        }
        text.push('\n');
    }
    for (key, value) in &calib.text {
        check_key(key, name)?;
        if value.contains('\n') {
            return Err(unwritable(name, format!("text entry {key} spans lines")));
        }
        let _ = writeln!(text, "{key}: {}", value.trim());
    }
    // What the reader would make of it: wrong value counts for known keys, or text that
    // reads back as numbers, are refused here rather than discovered later.
    let reread =
        super::calib::parse_calib(std::io::Cursor::new(text.clone().into_bytes()), name)
            .map_err(|e| unwritable(name, format!("the calibration would not read back: {e}")))?;
    if reread.numeric.len() != calib.numeric.len() || reread.text.len() != calib.text.len() {
        return Err(unwritable(name, "a text entry would read back as numbers"));
    }
    writer
        .write_all(text.as_bytes())
        .map_err(|e| Error::io(name, Location::File, e))
}

/// Writes a calibration file ([`write_calib_to`]).
pub fn write_calib(path: &Path, calib: &KittiCalib) -> Result<()> {
    write_file(path, |w| write_calib_to(w, calib, path))
}

fn check_key(key: &str, name: &Path) -> Result<()> {
    if key.is_empty() || key.contains(|c: char| c.is_whitespace() || c == ':') {
        return Err(unwritable(
            name,
            format!("{key:?} is not a calibration key"),
        ));
    }
    Ok(())
}

impl KittiCalib {
    /// The calibration of an odometry sequence: projections `P0`… (row-major 3×4) and `Tr`,
    /// the velodyne → cam0 transform.
    pub fn odometry(projections: &[Matrix3x4<f64>], cam0_from_velo: &Pose3) -> Self {
        let row_major = |m: &Matrix3x4<f64>| -> Vec<f64> {
            (0..3)
                .flat_map(|r| (0..4).map(move |c| m[(r, c)]))
                .collect()
        };
        let mut calib = Self::default();
        for (i, p) in projections.iter().enumerate() {
            calib.numeric.insert(format!("P{i}"), row_major(p));
        }
        calib
            .numeric
            .insert("Tr".into(), row_major(&cam0_from_velo.to_matrix3x4()));
        calib
    }
}

/// Camera poses for a pose file from REP-103 velodyne poses: `cam0_from_velo · world_from_velo
/// · velo_from_cam0`, i.e. the camera poses in the world frame turned into camera axes. When
/// the world frame is the velodyne frame of the first scan, the first pose is the identity,
/// as in the benchmark.
pub fn cam0_poses_from_velodyne(world_from_velo: &[Pose3], cam0_from_velo: &Pose3) -> Vec<Pose3> {
    let velo_from_cam0 = cam0_from_velo.inverse();
    world_from_velo
        .iter()
        .map(|p| *cam0_from_velo * *p * velo_from_cam0)
        .collect()
}

/// The inverse of [`cam0_poses_from_velodyne`]: REP-103 velodyne poses `world_from_velo` in
/// the frame of the velodyne at the first frame (when the camera poses start at the identity).
pub fn velodyne_poses_from_cam0(world_from_cam0: &[Pose3], cam0_from_velo: &Pose3) -> Vec<Pose3> {
    let velo_from_cam0 = cam0_from_velo.inverse();
    world_from_cam0
        .iter()
        .map(|p| velo_from_cam0 * *p * *cam0_from_velo)
        .collect()
}

/// Paths of one sequence in the benchmark layout under `root` (`root/sequences/NN/…`,
/// `root/poses/NN.txt`), which [`KittiSequence::open`](super::KittiSequence::open) finds when
/// given [`KittiLayout::sequence_dir`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct KittiLayout {
    /// The data-set root (`dataset/` of the benchmark).
    pub root: PathBuf,
    /// The sequence name (`00`, …).
    pub sequence: String,
}

impl KittiLayout {
    /// The layout of sequence `sequence` under `root`.
    pub fn new(root: impl Into<PathBuf>, sequence: impl Into<String>) -> Self {
        Self {
            root: root.into(),
            sequence: sequence.into(),
        }
    }

    /// `root/sequences/NN`.
    pub fn sequence_dir(&self) -> PathBuf {
        self.root.join("sequences").join(&self.sequence)
    }

    /// `root/sequences/NN/velodyne`.
    pub fn velodyne_dir(&self) -> PathBuf {
        self.sequence_dir().join("velodyne")
    }

    /// `root/sequences/NN/velodyne/FFFFFF.bin` (six digits, more when needed).
    pub fn scan_path(&self, frame: u64) -> PathBuf {
        self.velodyne_dir().join(format!("{frame:06}.bin"))
    }

    /// `root/sequences/NN/times.txt`.
    pub fn times_path(&self) -> PathBuf {
        self.sequence_dir().join("times.txt")
    }

    /// `root/sequences/NN/calib.txt`.
    pub fn calib_path(&self) -> PathBuf {
        self.sequence_dir().join("calib.txt")
    }

    /// `root/poses/NN.txt`.
    pub fn poses_path(&self) -> PathBuf {
        self.root
            .join("poses")
            .join(format!("{}.txt", self.sequence))
    }

    /// Creates the directories (`velodyne/` and `poses/`).
    pub fn create_dirs(&self) -> Result<()> {
        for dir in [self.velodyne_dir(), self.root.join("poses")] {
            std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, Location::File, e))?;
        }
        Ok(())
    }
}
