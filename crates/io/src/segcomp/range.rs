//! SegComp Perceptron range images (`perc.train.N`, `perc.test.N`).

use std::path::{Path, PathBuf};

use raypath_geometry::PointCloud;

use super::geometry::PerceptronGeometry;
use super::{header, load};
use crate::{Error, Location, Result};

/// A Perceptron range image as stored: raw 12-bit range counts, row by row.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RangeImage {
    /// Image rows (scanner elevation steps; row 0 is the top).
    pub rows: usize,
    /// Image columns (scanner azimuth steps; column 0 is the left as seen from the scanner).
    pub columns: usize,
    /// The text header lines as found.
    pub header: Vec<String>,
    /// Raw range counts (the low 12 bits of each stored word), `rows × columns`, row-major.
    pub range: Vec<u16>,
}

impl RangeImage {
    /// The raw range of pixel `(row, col)`.
    pub fn get(&self, row: usize, col: usize) -> Option<u16> {
        if row >= self.rows || col >= self.columns {
            return None;
        }
        self.range.get(row * self.columns + col).copied()
    }

    /// The organized cloud (`height = rows`, `width = columns`, same pixel order) in the
    /// REP-103 sensor frame, metres, through `geometry` (see [`PerceptronGeometry`]). Every
    /// pixel becomes a point, as in the reference implementation.
    pub fn to_cloud(&self, geometry: &PerceptronGeometry) -> PointCloud {
        let mut points = Vec::with_capacity(self.range.len());
        for (i, &range) in self.range.iter().enumerate() {
            let (row, col) = (i / self.columns.max(1), i % self.columns.max(1));
            let p = geometry.point(row, col, self.rows, self.columns, f64::from(range));
            points.push(p.cast::<f32>());
        }
        PointCloud {
            points,
            width: self.columns,
            height: self.rows,
            ..PointCloud::default()
        }
    }
}

/// A Perceptron scan: the raw image and its points.
#[derive(Clone, Debug, PartialEq)]
pub struct PerceptronScan {
    /// The range image as stored.
    pub image: RangeImage,
    /// The organized point cloud (default [`PerceptronGeometry`]).
    pub cloud: PointCloud,
}

/// Reads a range image file (plain, `.Z`, gzip or bzip2).
pub fn read_range_image(path: &Path) -> Result<RangeImage> {
    parse_range_image(&load(path)?, path)
}

/// Reads a range image file and converts it with the default geometry.
pub fn read_perceptron(path: &Path) -> Result<PerceptronScan> {
    let image = read_range_image(path)?;
    let cloud = image.to_cloud(&PerceptronGeometry::default());
    Ok(PerceptronScan { image, cloud })
}

/// Parses a (decompressed) range image held in memory; `name` names it in errors.
///
/// Layout: the 11-line text header, then `rows × columns` big-endian 32-bit words, of which
/// the low 12 bits are the range (the upper bits carry reflectance and control bits).
pub fn parse_range_image(bytes: &[u8], name: impl Into<PathBuf>) -> Result<RangeImage> {
    let path = name.into();
    let header = header::parse(bytes, &path)?;
    let (start, _) = header.data_start(bytes.len(), &[4], &path)?;
    let data = bytes
        .get(start..)
        .ok_or_else(|| Error::truncated(&path, Location::Byte(start as u64), "the range data"))?;
    let range = data
        .chunks_exact(4)
        .map(|w| (u32::from_be_bytes([w[0], w[1], w[2], w[3]]) & 0x0fff) as u16)
        .collect();
    Ok(RangeImage {
        rows: header.rows,
        columns: header.columns,
        header: header.lines,
        range,
    })
}
