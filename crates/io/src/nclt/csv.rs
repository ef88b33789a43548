//! NCLT CSV files: poses (`groundtruth_<date>.csv`, `odometry_mu*.csv`: utime, x, y, z, roll,
//! pitch, yaw) and covariances (`cov_<date>.csv`, `odometry_cov*.csv`: utime and the 21
//! upper-triangle entries of a 6×6 matrix, row by row, in the order x, y, z, roll, pitch,
//! yaw).
//!
//! Rows are comma-separated numbers; `utime` is an integer (microseconds). A first line that
//! does not start with a number is taken as a header and skipped. Rows containing NaN (the
//! ground truth has some where the optimization produced no pose) are skipped **and counted**
//! ([`PoseTable::nan_rows`]); infinite values are errors.

use std::io::BufRead;
use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Matrix6, Point3, UnitQuaternion};
use raypath_geometry::Pose3;

use super::utime_to_secs;
use crate::Result;
use crate::kitti::next_line_into;
use crate::source::LineReader;
use crate::summary::{BoundingBox, TimeSpan};

/// One row of a pose CSV, as stored (NED world, body x forward, y right, z down).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NcltPose {
    /// Microseconds since the UNIX epoch.
    pub utime: u64,
    /// Position in metres (x north, y east, z down).
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw in radians (fixed axes x-y-z).
    pub rpy: [f64; 3],
}

impl NcltPose {
    /// Timestamp in seconds since the UNIX epoch.
    pub fn stamp_secs(&self) -> f64 {
        utime_to_secs(self.utime)
    }

    /// The pose as stored: NED world, body x forward, y right, z down.
    pub fn world_from_body_ned(&self) -> Pose3 {
        let [x, y, z] = self.xyz;
        let [roll, pitch, yaw] = self.rpy;
        Pose3::from_xyz_rpy(x, y, z, roll, pitch, yaw)
    }

    /// The pose in REP-103 frames: world x east, y north, z up; body x forward, y left, z up
    /// (`ENU_FROM_NED · world_from_body_ned · FRD_FROM_FLU`).
    pub fn world_from_body(&self) -> Pose3 {
        let frd_from_flu = Pose3::from_parts(
            nalgebra::Vector3::zeros(),
            UnitQuaternion::from_matrix(&Matrix3::from_diagonal(&nalgebra::Vector3::new(
                1.0, -1.0, -1.0,
            ))),
        );
        super::enu_from_ned() * self.world_from_body_ned() * frd_from_flu
    }

    /// Position in the REP-103 world frame (x east, y north, z up), metres.
    pub fn position_enu(&self) -> Point3<f64> {
        let [x, y, z] = self.xyz;
        Point3::new(y, x, -z)
    }
}

/// The rows of a pose CSV.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PoseTable {
    /// The poses, in file order.
    pub poses: Vec<NcltPose>,
    /// Number of rows skipped because they contain NaN.
    pub nan_rows: u64,
    /// Line number of the first skipped row.
    pub first_nan_line: Option<u64>,
}

impl PoseTable {
    /// First and last timestamp, seconds.
    pub fn time_span(&self) -> Option<TimeSpan> {
        TimeSpan::from_times(self.poses.iter().map(NcltPose::stamp_secs))
    }

    /// Bounding box of the positions in the REP-103 world frame (x east, y north, z up).
    pub fn bbox(&self) -> Option<BoundingBox> {
        super::positions_bbox(self.poses.iter().map(NcltPose::position_enu))
    }
}

/// A covariance row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CovarianceRecord {
    /// Microseconds since the UNIX epoch.
    pub utime: u64,
    /// The symmetric 6×6 covariance of (x, y, z, roll, pitch, yaw), m² / rad².
    pub matrix: Matrix6<f64>,
}

/// The rows of a covariance CSV.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CovarianceTable {
    /// The covariances, in file order.
    pub records: Vec<CovarianceRecord>,
    /// Number of rows skipped because they contain NaN.
    pub nan_rows: u64,
}

/// Reads a pose CSV (plain or compressed).
pub fn read_pose_csv(path: &Path) -> Result<PoseTable> {
    PoseCsvReader::open(path)?.read_all()
}

/// Parses a pose CSV from `reader`; `name` is used in errors.
pub fn parse_pose_csv(
    reader: impl BufRead + Send + 'static,
    name: impl Into<PathBuf>,
) -> Result<PoseTable> {
    PoseCsvReader::new(reader, name).read_all()
}

/// Reads a covariance CSV (plain or compressed).
pub fn read_covariance(path: &Path) -> Result<CovarianceTable> {
    CovarianceReader::open(path)?.read_all()
}

/// Parses a covariance CSV from `reader`; `name` is used in errors.
pub fn parse_covariance(
    reader: impl BufRead + Send + 'static,
    name: impl Into<PathBuf>,
) -> Result<CovarianceTable> {
    CovarianceReader::new(reader, name).read_all()
}

/// Streams the rows of a pose CSV, skipping (and counting) rows with NaN.
pub struct PoseCsvReader(Rows<6>);

impl PoseCsvReader {
    /// Opens a pose CSV (plain or compressed).
    pub fn open(path: &Path) -> Result<Self> {
        Ok(Self(Rows::new(LineReader::open(path)?)))
    }

    /// Reads from `reader`; `name` is used in errors.
    pub fn new(reader: impl BufRead + Send + 'static, name: impl Into<PathBuf>) -> Self {
        Self(Rows::new(LineReader::new(reader, name)))
    }

    /// Rows skipped so far because they contain NaN.
    pub fn nan_rows(&self) -> u64 {
        self.0.nan_rows
    }

    /// Reads all remaining rows.
    pub fn read_all(mut self) -> Result<PoseTable> {
        let mut poses = Vec::new();
        for pose in &mut self {
            poses.push(pose?);
        }
        Ok(PoseTable {
            poses,
            nan_rows: self.0.nan_rows,
            first_nan_line: self.0.first_nan_line,
        })
    }
}

impl Iterator for PoseCsvReader {
    type Item = Result<NcltPose>;

    fn next(&mut self) -> Option<Self::Item> {
        let row = self.0.next_row().transpose()?;
        Some(row.map(|(utime, v)| NcltPose {
            utime,
            xyz: [v[0], v[1], v[2]],
            rpy: [v[3], v[4], v[5]],
        }))
    }
}

/// Streams the rows of a covariance CSV, skipping (and counting) rows with NaN.
pub struct CovarianceReader(Rows<21>);

impl CovarianceReader {
    /// Opens a covariance CSV (plain or compressed).
    pub fn open(path: &Path) -> Result<Self> {
        Ok(Self(Rows::new(LineReader::open(path)?)))
    }

    /// Reads from `reader`; `name` is used in errors.
    pub fn new(reader: impl BufRead + Send + 'static, name: impl Into<PathBuf>) -> Self {
        Self(Rows::new(LineReader::new(reader, name)))
    }

    /// Reads all remaining rows.
    pub fn read_all(mut self) -> Result<CovarianceTable> {
        let mut records = Vec::new();
        for record in &mut self {
            records.push(record?);
        }
        Ok(CovarianceTable {
            records,
            nan_rows: self.0.nan_rows,
        })
    }
}

impl Iterator for CovarianceReader {
    type Item = Result<CovarianceRecord>;

    fn next(&mut self) -> Option<Self::Item> {
        let row = self.0.next_row().transpose()?;
        Some(row.map(|(utime, upper)| {
            let mut matrix = Matrix6::zeros();
            let mut values = upper.iter();
            for r in 0..6 {
                for c in r..6 {
                    let v = values.next().copied().unwrap_or(0.0);
                    matrix[(r, c)] = v;
                    matrix[(c, r)] = v;
                }
            }
            CovarianceRecord { utime, matrix }
        }))
    }
}

/// Rows of `utime` followed by `N` numbers.
struct Rows<const N: usize> {
    lines: LineReader,
    line: String,
    nan_rows: u64,
    first_nan_line: Option<u64>,
    failed: bool,
}

impl<const N: usize> Rows<N> {
    fn new(lines: LineReader) -> Self {
        Self {
            lines,
            line: String::new(),
            nan_rows: 0,
            first_nan_line: None,
            failed: false,
        }
    }

    fn next_row(&mut self) -> Result<Option<(u64, [f64; N])>> {
        if self.failed {
            return Ok(None);
        }
        let row = self.parse_next();
        self.failed = row.is_err();
        row
    }

    fn parse_next(&mut self) -> Result<Option<(u64, [f64; N])>> {
        loop {
            if !next_line_into(&mut self.lines, &mut self.line)? {
                return Ok(None);
            }
            let text = self.line.trim();
            if text.is_empty() {
                continue;
            }
            let mut fields = text.split(',').map(str::trim);
            let first = fields.next().unwrap_or_default();
            if self.lines.line_number() == 1 && first.parse::<f64>().is_err() {
                continue; // a header row
            }
            let utime = parse_utime(first).ok_or_else(|| {
                self.lines
                    .error(format!("utime: {first:?} is not a non-negative integer"))
            })?;
            let mut values = [0.0; N];
            let mut has_nan = false;
            for (i, value) in values.iter_mut().enumerate() {
                let Some(field) = fields.next() else {
                    return Err(self
                        .lines
                        .error(format!("{} values, expected utime and {N}", i + 1)));
                };
                *value = field.parse::<f64>().map_err(|_| {
                    self.lines
                        .error(format!("column {}: cannot parse {field:?}", i + 2))
                })?;
                if value.is_nan() {
                    has_nan = true;
                } else if value.is_infinite() {
                    return Err(self.lines.error(format!("column {} is {value}", i + 2)));
                }
            }
            if fields.next().is_some() {
                return Err(self
                    .lines
                    .error(format!("more than {} values on a row", N + 1)));
            }
            if has_nan {
                self.nan_rows += 1;
                self.first_nan_line.get_or_insert(self.lines.line_number());
                continue;
            }
            return Ok(Some((utime, values)));
        }
    }
}

/// A utime as an integer, also accepted in floating-point notation when it is exact.
fn parse_utime(text: &str) -> Option<u64> {
    if let Ok(utime) = text.parse::<u64>() {
        return Some(utime);
    }
    let value = text.parse::<f64>().ok()?;
    // Integers up to 2^53 are exact in f64; NCLT utimes are about 1.3e15.
    (value.is_finite() && value >= 0.0 && value.fract() == 0.0 && value < 9.007_199_254_740_992e15)
        .then_some(value as u64)
}
