//! Plain-text point lists: one point `x y z` per line, as in OctoMap's `scan.dat`.
//!
//! Format (no formal specification; this is what the tools that write it agree on):
//!
//! * one point per line, coordinates in metres separated by blanks or tabs;
//! * a line may carry further columns (intensity, colour, …): they are **ignored**, but every
//!   point line must have the same number of columns, so a damaged line is an error rather
//!   than a silently misread point — the count is reported as `columns`;
//! * `#` starts a comment (whole line or the rest of a line); blank lines are skipped;
//! * the file may be gzip- or bzip2-compressed (recognized by its first bytes).
//!
//! The frame is whatever the producer used (for a single scan usually the sensor frame,
//! x forward, y left, z up). Coordinates are parsed as `f64` and stored as `f32`; a value that
//! is not finite, or too large for `f32`, is an error naming the line.
//!
//! ```
//! use raypath_io::xyz::XyzReader;
//! let text = "# a scan\n1 2 3\n4.5 -1 0.25 # with a comment\n";
//! let mut reader = XyzReader::new(text.as_bytes(), "mem.xyz");
//! let points: Vec<_> = reader.by_ref().collect::<Result<_, _>>()?;
//! assert_eq!(points.len(), 2);
//! assert_eq!(reader.columns(), Some(3));
//! # Ok::<(), raypath_io::Error>(())
//! ```

use std::io::BufRead;
use std::path::{Path, PathBuf};

use nalgebra::Point3;
use raypath_geometry::{Aabb3, PointCloud};

use crate::source::LineReader;
use crate::summary::BoundingBox;
use crate::{Result, Summary};

/// Streams the points of an `x y z` text file, line by line.
///
/// Iterating yields `Result<Point3<f32>>`; after the first error the iterator ends.
pub struct XyzReader {
    lines: LineReader,
    columns: Option<usize>,
    failed: bool,
}

impl XyzReader {
    /// Opens `path` (plain, gzip or bzip2).
    pub fn open(path: &Path) -> Result<Self> {
        Ok(Self::with_lines(LineReader::open(path)?))
    }

    /// Reads from `reader`; `name` names the source in errors.
    pub fn new(reader: impl BufRead + Send + 'static, name: impl Into<PathBuf>) -> Self {
        Self::with_lines(LineReader::new(reader, name))
    }

    fn with_lines(lines: LineReader) -> Self {
        Self {
            lines,
            columns: None,
            failed: false,
        }
    }

    /// Columns per line, known after the first point.
    pub fn columns(&self) -> Option<usize> {
        self.columns
    }

    /// The next point, `None` at the end of the input.
    pub fn next_point(&mut self) -> Result<Option<Point3<f32>>> {
        while let Some(line) = self.lines.next_line()? {
            let parsed = parse_line(line);
            let (xyz, columns) = match parsed {
                Ok(Some(point)) => point,
                Ok(None) => continue,
                Err(reason) => return Err(self.lines.error(reason)),
            };
            match self.columns {
                None => self.columns = Some(columns),
                Some(n) if n != columns => {
                    return Err(self
                        .lines
                        .error(format!("{columns} columns; the first point line had {n}")));
                }
                Some(_) => {}
            }
            return Ok(Some(Point3::from(xyz)));
        }
        Ok(None)
    }

    /// Appends up to `max` points to `out`; returns how many were added (0 at the end).
    pub fn next_chunk(&mut self, max: usize, out: &mut Vec<Point3<f32>>) -> Result<usize> {
        let mut added = 0;
        while added < max {
            match self.next_point()? {
                Some(p) => {
                    out.push(p);
                    added += 1;
                }
                None => break,
            }
        }
        Ok(added)
    }
}

impl Iterator for XyzReader {
    type Item = Result<Point3<f32>>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed {
            return None;
        }
        let item = self.next_point();
        self.failed = item.is_err();
        item.transpose()
    }
}

/// The coordinates and column count of a point line; `None` for a blank or comment line.
fn parse_line(line: &str) -> std::result::Result<Option<([f32; 3], usize)>, String> {
    let data = line.split('#').next().unwrap_or_default();
    let mut fields = data.split_ascii_whitespace().peekable();
    if fields.peek().is_none() {
        return Ok(None);
    }
    let mut xyz = [0f32; 3];
    for (slot, axis) in xyz.iter_mut().zip(["x", "y", "z"]) {
        let Some(text) = fields.next() else {
            return Err(format!("missing {axis}: a point line needs x y z"));
        };
        let value = text
            .parse::<f64>()
            .map_err(|_| format!("{axis}: cannot parse {text:?} as a number"))?;
        let stored = value as f32;
        if !value.is_finite() || !stored.is_finite() {
            return Err(format!("{axis}: {text} is not a finite coordinate"));
        }
        *slot = stored;
    }
    Ok(Some((xyz, 3 + fields.count())))
}

/// Reads all points of `path` into an unorganized cloud.
pub fn read_xyz(path: &Path) -> Result<PointCloud> {
    collect(XyzReader::open(path)?)
}

/// Reads all points from `reader` into an unorganized cloud; `name` names it in errors.
pub fn read_xyz_from(
    reader: impl BufRead + Send + 'static,
    name: impl Into<PathBuf>,
) -> Result<PointCloud> {
    collect(XyzReader::new(reader, name))
}

fn collect(reader: XyzReader) -> Result<PointCloud> {
    let points = reader.collect::<Result<Vec<_>>>()?;
    Ok(PointCloud::from_points(points))
}

/// Summarizes an `x y z` file for `raypath info`: `points`, `bbox`, and `columns` per line.
/// Streams the file, so its size does not matter.
pub fn summarize(path: &Path) -> Result<Summary> {
    let mut reader = XyzReader::open(path)?;
    let mut aabb = Aabb3::empty();
    let mut points = 0u64;
    while let Some(p) = reader.next_point()? {
        aabb.extend(&p.cast::<f64>());
        points += 1;
    }
    let mut summary = Summary::new("xyz");
    summary.points = Some(points);
    summary.bbox = BoundingBox::from_aabb(&aabb);
    if let Some(columns) = reader.columns() {
        summary = summary.with_extra("columns", columns as u64);
    }
    Ok(summary)
}
