//! KITTI calibration files: `calib.txt` of the odometry benchmark (`P0:` … `P3:`, `Tr:`) and
//! the raw-data variants (`calib_velo_to_cam.txt` with `R:`/`T:`, `Tr_velo_to_cam:`).

use std::collections::BTreeMap;
use std::io::BufRead;
use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Matrix3x4, Vector3};
use raypath_geometry::Pose3;

use crate::Result;
use crate::source::LineReader;

/// Keys `cam0_from_velo` looks for, in order (12 numbers, row-major 3×4 velo → cam0).
const VELO_TO_CAM_KEYS: [&str; 3] = ["Tr", "Tr_velo_to_cam", "Tr_velo_cam"];

/// The entries of a calibration file, by key (the text before the colon).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct KittiCalib {
    /// Entries whose values are all numbers.
    pub numeric: BTreeMap<String, Vec<f64>>,
    /// Other entries (for example `calib_time: 09-Jan-2012 13:57:47`), as text.
    pub text: BTreeMap<String, String>,
}

impl KittiCalib {
    /// All keys, sorted.
    pub fn keys(&self) -> impl Iterator<Item = &str> {
        let mut keys: Vec<&str> = self
            .numeric
            .keys()
            .chain(self.text.keys())
            .map(String::as_str)
            .collect();
        keys.sort_unstable();
        keys.into_iter()
    }

    /// A 12-number entry as a row-major 3×4 matrix.
    pub fn matrix3x4(&self, key: &str) -> Option<Matrix3x4<f64>> {
        self.numeric
            .get(key)
            .filter(|v| v.len() == 12)
            .map(|v| Matrix3x4::from_row_slice(v))
    }

    /// Projection matrix of camera `i` (0–3): `P{i}` (odometry) or `P_rect_0{i}` (raw data).
    pub fn projection(&self, camera: usize) -> Option<Matrix3x4<f64>> {
        self.matrix3x4(&format!("P{camera}"))
            .or_else(|| self.matrix3x4(&format!("P_rect_0{camera}")))
    }

    /// The velodyne → cam0 transform (maps velodyne points into the camera-0 frame), from
    /// `Tr`, `Tr_velo_to_cam`, `Tr_velo_cam`, or `R` (9 numbers) with `T` (3 numbers);
    /// `None` when absent or when the numbers are not a rigid transform.
    pub fn cam0_from_velo(&self) -> Option<Pose3> {
        if let Some(m) = VELO_TO_CAM_KEYS.iter().find_map(|k| self.matrix3x4(k)) {
            return Pose3::try_from_matrix3x4(&m);
        }
        let r = self.numeric.get("R").filter(|v| v.len() == 9)?;
        let t = self.numeric.get("T").filter(|v| v.len() == 3)?;
        let mut m = Matrix3x4::zeros();
        m.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&Matrix3::from_row_slice(r));
        m.set_column(3, &Vector3::from_column_slice(t));
        Pose3::try_from_matrix3x4(&m)
    }
}

/// Reads a calibration file (plain or compressed).
pub fn read_calib(path: &Path) -> Result<KittiCalib> {
    calib_from(LineReader::open(path)?)
}

/// Parses a calibration file from `reader`; `name` is used in errors.
pub fn parse_calib(
    reader: impl BufRead + Send + 'static,
    name: impl Into<PathBuf>,
) -> Result<KittiCalib> {
    calib_from(LineReader::new(reader, name))
}

/// Number of values a known key must have.
fn expected_len(key: &str) -> Option<usize> {
    let camera_projection = key
        .strip_prefix('P')
        .and_then(|rest| rest.chars().next())
        .is_some_and(|c| c.is_ascii_digit());
    if camera_projection || key.starts_with("P_rect_") || key == "Tr" || key.starts_with("Tr_") {
        Some(12)
    } else if key == "R" || key.starts_with("R_rect_") {
        Some(9)
    } else if key == "T" {
        Some(3)
    } else {
        None
    }
}

fn calib_from(mut lines: LineReader) -> Result<KittiCalib> {
    let mut calib = KittiCalib::default();
    let mut line = String::new();
    while super::next_line_into(&mut lines, &mut line)? {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let Some((key, values)) = line.split_once(':') else {
            return Err(lines.error("expected `key: values`"));
        };
        let key = key.trim();
        if key.is_empty() || key.contains(char::is_whitespace) {
            return Err(lines.error(format!("{key:?} is not a calibration key")));
        }
        if calib.numeric.contains_key(key) || calib.text.contains_key(key) {
            return Err(lines.error(format!("key {key} appears twice")));
        }
        let parsed: std::result::Result<Vec<f64>, _> =
            values.split_whitespace().map(str::parse::<f64>).collect();
        match (parsed, expected_len(key)) {
            (Ok(numbers), expected) if !numbers.is_empty() => {
                if let Some(bad) = numbers.iter().find(|v| !v.is_finite()) {
                    return Err(lines.error(format!("{key}: value {bad} is not finite")));
                }
                if let Some(n) = expected
                    && numbers.len() != n
                {
                    return Err(
                        lines.error(format!("{key} has {} values, expected {n}", numbers.len()))
                    );
                }
                calib.numeric.insert(key.to_owned(), numbers);
            }
            (_, Some(n)) => {
                return Err(lines.error(format!("{key} must hold {n} numbers")));
            }
            (_, None) => {
                calib.text.insert(key.to_owned(), values.trim().to_owned());
            }
        }
    }
    Ok(calib)
}
