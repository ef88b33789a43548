//! KITTI poses (`poses/XX.txt`) and timestamps (`times.txt`).

use std::io::BufRead;
use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Matrix3x4, UnitQuaternion};
use raypath_geometry::Pose3;

use crate::Result;
use crate::source::{LineReader, parse_field};

/// Largest deviation of `RᵀR` from the identity accepted for a pose's rotation block
/// (the files print 7 significant digits).
const ORTHONORMAL_TOLERANCE: f64 = 1e-3;

/// Reads a pose file (plain or compressed): one `world_from_cam0` pose per frame, camera axes
/// (x right, y down, z forward).
pub fn read_poses(path: &Path) -> Result<Vec<Pose3>> {
    poses_from(LineReader::open(path)?)
}

/// Parses poses from `reader`; `name` is used in errors.
pub fn parse_poses(
    reader: impl BufRead + Send + 'static,
    name: impl Into<PathBuf>,
) -> Result<Vec<Pose3>> {
    poses_from(LineReader::new(reader, name))
}

fn poses_from(mut lines: LineReader) -> Result<Vec<Pose3>> {
    let mut poses = Vec::new();
    let mut blank = None;
    let mut line = String::new();
    while super::next_line_into(&mut lines, &mut line)? {
        if line.trim().is_empty() {
            blank.get_or_insert(lines.line_number());
            continue;
        }
        check_no_gap(&lines, blank)?;
        let mut fields = line.split_whitespace();
        let mut m = [0.0f64; 12];
        for (i, value) in m.iter_mut().enumerate() {
            *value = parse_field(&lines, fields.next(), &format!("matrix entry {}", i + 1))?;
            if !value.is_finite() {
                return Err(lines.error(format!("matrix entry {} is {value}", i + 1)));
            }
        }
        if fields.next().is_some() {
            return Err(lines.error("more than 12 numbers on a pose line"));
        }
        let matrix = Matrix3x4::from_row_slice(&m);
        let rotation: Matrix3<f64> = matrix.fixed_view::<3, 3>(0, 0).into_owned();
        let error = (rotation.transpose() * rotation - Matrix3::identity())
            .abs()
            .max();
        if error > ORTHONORMAL_TOLERANCE || rotation.determinant() <= 0.0 {
            return Err(lines.error(format!(
                "the 3×3 block is not a rotation (|RᵀR − I| = {error:.3e}, det = {:.3})",
                rotation.determinant()
            )));
        }
        poses.push(Pose3::from_matrix3x4(&matrix));
    }
    Ok(poses)
}

/// Reads a timestamp file (plain or compressed): seconds, one a line, non-decreasing.
pub fn read_times(path: &Path) -> Result<Vec<f64>> {
    times_from(LineReader::open(path)?)
}

/// Parses timestamps from `reader`; `name` is used in errors.
pub fn parse_times(
    reader: impl BufRead + Send + 'static,
    name: impl Into<PathBuf>,
) -> Result<Vec<f64>> {
    times_from(LineReader::new(reader, name))
}

fn times_from(mut lines: LineReader) -> Result<Vec<f64>> {
    let mut times: Vec<f64> = Vec::new();
    let mut blank = None;
    let mut line = String::new();
    while super::next_line_into(&mut lines, &mut line)? {
        if line.trim().is_empty() {
            blank.get_or_insert(lines.line_number());
            continue;
        }
        check_no_gap(&lines, blank)?;
        let mut fields = line.split_whitespace();
        let t: f64 = parse_field(&lines, fields.next(), "timestamp")?;
        if fields.next().is_some() {
            return Err(lines.error("more than one number on a timestamp line"));
        }
        if !t.is_finite() {
            return Err(lines.error(format!("timestamp is {t}")));
        }
        if let Some(&previous) = times.last()
            && t < previous
        {
            return Err(lines.error(format!(
                "timestamp {t} s is earlier than the previous one ({previous} s)"
            )));
        }
        times.push(t);
    }
    Ok(times)
}

/// Blank lines are accepted only at the end: inside the list they would shift frame numbers.
fn check_no_gap(lines: &LineReader, blank: Option<u64>) -> Result<()> {
    match blank {
        Some(at) => Err(lines.error(format!(
            "blank line {at} inside the list would shift the frame numbers"
        ))),
        None => Ok(()),
    }
}

/// `world_from_velo` for every frame: `world_from_cam0 · cam0_from_velo`.
pub fn velodyne_poses(world_from_cam0: &[Pose3], cam0_from_velo: &Pose3) -> Vec<Pose3> {
    world_from_cam0
        .iter()
        .map(|pose| *pose * *cam0_from_velo)
        .collect()
}

/// The rotation from KITTI camera axes (x right, y down, z forward) to REP-103 axes
/// (x forward, y left, z up): `p_flu = (z, −x, −y)`. `flu_from_camera() * world_from_cam0`
/// is a pose in a REP-103 world frame.
pub fn flu_from_camera() -> Pose3 {
    let rotation = Matrix3::new(0.0, 0.0, 1.0, -1.0, 0.0, 0.0, 0.0, -1.0, 0.0);
    Pose3::from_parts(
        nalgebra::Vector3::zeros(),
        UnitQuaternion::from_matrix(&rotation),
    )
}
