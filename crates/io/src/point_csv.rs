//! CSV files of points with a header row: `x,y[,z][,more named columns]`.
//!
//! Such files hold pole maps and similar landmark lists, for example the KITTI and NCLT pole
//! maps of the pole-localization experiments (Schaefer 2020, chapter 12): `x,y` (metres),
//! `x,y,z`, or `x,y,w` with the pole width `w`. The header names the columns; its first two
//! must be `x` and `y` (case-insensitive). A third column named `z` is the height; any other
//! columns are kept by name. Every row holds the same number of finite numbers. Blank lines
//! are skipped. Coordinates are in metres in whatever map frame the producer used (REP-103
//! axes for raypath's own files).
//!
//! ```
//! use raypath_io::point_csv::PointCsv;
//! let csv = PointCsv::parse(std::io::Cursor::new(b"x,y,w\n1,2,0.1\n3,4,0.2\n".to_vec()), "poles.csv")?;
//! assert_eq!(csv.columns, ["x", "y", "w"]);
//! assert_eq!(csv.row(1), Some(&[3.0, 4.0, 0.2][..]));
//! assert_eq!(csv.column("w"), Some(vec![0.1, 0.2]));
//! # Ok::<(), raypath_io::Error>(())
//! ```

use std::io::BufRead;
use std::path::{Path, PathBuf};

use nalgebra::Point3;
use raypath_geometry::Aabb3;

use crate::kitti::next_line_into;
use crate::source::LineReader;
use crate::summary::{BoundingBox, Summary};
use crate::{Format, Result};

/// A whole point CSV: the column names and the rows, stored flat.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointCsv {
    /// Column names from the header (`x`, `y`, …), trimmed, as written.
    pub columns: Vec<String>,
    /// All values row by row (`rows × columns.len()`).
    pub values: Vec<f64>,
}

impl PointCsv {
    /// Reads a file (plain or compressed).
    pub fn read(path: &Path) -> Result<Self> {
        PointCsvReader::open(path)?.read_all()
    }

    /// Parses from `reader`; `name` is used in errors.
    pub fn parse(reader: impl BufRead + Send + 'static, name: impl Into<PathBuf>) -> Result<Self> {
        PointCsvReader::new(reader, name)?.read_all()
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.values
            .len()
            .checked_div(self.columns.len())
            .unwrap_or(0)
    }

    /// True when there are no rows.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Row `i`, `None` past the end.
    pub fn row(&self, i: usize) -> Option<&[f64]> {
        let n = self.columns.len();
        let start = i.checked_mul(n)?;
        self.values.get(start..start.checked_add(n)?)
    }

    /// The rows in order.
    pub fn rows(&self) -> impl Iterator<Item = &[f64]> {
        self.values.chunks_exact(self.columns.len().max(1))
    }

    /// Index of a column by name (case-insensitive).
    pub fn column_index(&self, name: &str) -> Option<usize> {
        self.columns
            .iter()
            .position(|c| c.eq_ignore_ascii_case(name))
    }

    /// All values of a column by name.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let i = self.column_index(name)?;
        Some(self.rows().filter_map(|r| r.get(i).copied()).collect())
    }

    /// The points: `(x, y, z)` with `z = 0` when the file has no `z` column.
    pub fn points(&self) -> Vec<Point3<f64>> {
        let z = self.column_index("z");
        self.rows().map(|r| row_point(r, z)).collect()
    }
}

fn row_point(row: &[f64], z: Option<usize>) -> Point3<f64> {
    let get = |i: usize| row.get(i).copied().unwrap_or(0.0);
    Point3::new(get(0), get(1), z.map_or(0.0, get))
}

/// Streams the rows of a point CSV without holding the file.
pub struct PointCsvReader {
    lines: LineReader,
    columns: Vec<String>,
    line: String,
    row: Vec<f64>,
}

impl PointCsvReader {
    /// Opens a file (plain or compressed) and reads its header.
    pub fn open(path: &Path) -> Result<Self> {
        Self::from_lines(LineReader::open(path)?)
    }

    /// Reads from `reader` (header first); `name` is used in errors.
    pub fn new(reader: impl BufRead + Send + 'static, name: impl Into<PathBuf>) -> Result<Self> {
        Self::from_lines(LineReader::new(reader, name))
    }

    fn from_lines(mut lines: LineReader) -> Result<Self> {
        let mut line = String::new();
        if !next_line_into(&mut lines, &mut line)? {
            return Err(crate::Error::truncated(
                lines.path(),
                crate::Location::Line(1),
                "the header row (x,y,…)",
            ));
        }
        let header = line.trim_start_matches('\u{feff}');
        let columns: Vec<String> = header.split(',').map(|c| c.trim().to_owned()).collect();
        let first_two = (columns.first(), columns.get(1));
        if !matches!(first_two, (Some(x), Some(y)) if x.eq_ignore_ascii_case("x") && y.eq_ignore_ascii_case("y"))
        {
            return Err(lines.error(format!(
                "the header must start with the columns x,y, not {header:?}"
            )));
        }
        if let Some(empty) = columns.iter().position(String::is_empty) {
            return Err(lines.error(format!("column {} has no name", empty + 1)));
        }
        let row = Vec::with_capacity(columns.len());
        Ok(Self {
            lines,
            columns,
            line,
            row,
        })
    }

    /// The column names.
    pub fn columns(&self) -> &[String] {
        &self.columns
    }

    /// The next row (as many values as columns), `None` at the end.
    pub fn next_row(&mut self) -> Result<Option<&[f64]>> {
        loop {
            if !next_line_into(&mut self.lines, &mut self.line)? {
                return Ok(None);
            }
            if !self.line.trim().is_empty() {
                break;
            }
        }
        self.row.clear();
        for (i, field) in self.line.split(',').map(str::trim).enumerate() {
            let Some(name) = self.columns.get(i) else {
                return Err(self.lines.error(format!(
                    "more than the {} columns of the header",
                    self.columns.len()
                )));
            };
            let value = field
                .parse::<f64>()
                .map_err(|_| self.lines.error(format!("{name}: cannot parse {field:?}")))?;
            if !value.is_finite() {
                return Err(self.lines.error(format!("{name} is {value}")));
            }
            self.row.push(value);
        }
        if self.row.len() != self.columns.len() {
            return Err(self.lines.error(format!(
                "{} values, the header has {} columns",
                self.row.len(),
                self.columns.len()
            )));
        }
        Ok(Some(&self.row))
    }

    /// Reads all remaining rows.
    pub fn read_all(mut self) -> Result<PointCsv> {
        let mut values = Vec::new();
        while let Some(row) = self.next_row()? {
            values.extend_from_slice(row);
        }
        Ok(PointCsv {
            columns: self.columns,
            values,
        })
    }
}

/// Summarizes a point CSV: `points` (rows), `bbox` (z = 0 without a `z` column) and extra
/// `columns` (the header's names).
pub fn summarize(path: &Path) -> Result<Summary> {
    let mut reader = PointCsvReader::open(path)?;
    let z = reader
        .columns()
        .iter()
        .position(|c| c.eq_ignore_ascii_case("z"));
    let (mut points, mut bbox) = (0u64, Aabb3::empty());
    while let Some(row) = reader.next_row()? {
        points += 1;
        bbox.extend(&row_point(row, z));
    }
    let mut summary =
        Summary::new(Format::PointCsv.name()).with_extra("columns", reader.columns().to_vec());
    summary.points = Some(points);
    summary.bbox = BoundingBox::from_aabb(&bbox);
    Ok(summary)
}
