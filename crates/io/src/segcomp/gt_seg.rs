//! SegComp ground-truth segmentations (`<name>.gt-seg`): one region label per pixel.
//!
//! The USF segmentation-comparison tools store label images as **Sun rasterfiles** (the
//! ground truth is "read with an image reader" by the reference implementation; other
//! SegComp readers parse the Sun header: eight big-endian words `magic 0x59a66a95, width,
//! height, depth, length, type, maptype, maplength`, a colour map of `maplength` bytes, then
//! the pixels, each row padded to an even number of bytes). Accepted here:
//!
//! * Sun rasterfile, 8 bits per pixel, types 0 (old), 1 (standard) and 2 (byte-encoded:
//!   `0x80 n v` repeats `v` n + 1 times, `0x80 0x00` is a literal `0x80`); a colour map is
//!   skipped — the pixel values (map indices) are the labels;
//! * PGM (`P5` binary with 8- or 16-bit samples, `P2` text), for converted copies;
//! * the Perceptron range-file layout (11 text header lines, then one byte or one big-endian
//!   32-bit word per pixel).
//!
//! Pixels are kept in raster order (row 0 at the top), like [`super::RangeImage`], so label
//! `(row, col)` belongs to range pixel `(row, col)`. Labels ≥ 10 are ground-truth planes;
//! smaller values mark unlabelled, shadow or no-data pixels.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use super::header::{self, MAX_SIDE};
use super::load;
use crate::{Error, Location, Result};

/// The Sun rasterfile magic number.
pub const SUN_RASTER_MAGIC: u32 = 0x59a6_6a95;
/// Smallest label of a ground-truth plane.
pub const FIRST_PLANE_LABEL: u32 = 10;

/// The file layout a segmentation was read from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RasterFormat {
    /// Sun rasterfile.
    SunRaster,
    /// Netpbm greymap (`P5` or `P2`).
    Pgm,
    /// Perceptron-style text header and raw pixels.
    RawWithHeader,
}

impl RasterFormat {
    /// A short name (`sun-raster`, `pgm`, `raw`).
    pub fn name(self) -> &'static str {
        match self {
            RasterFormat::SunRaster => "sun-raster",
            RasterFormat::Pgm => "pgm",
            RasterFormat::RawWithHeader => "raw",
        }
    }
}

/// A ground-truth segmentation: a label per pixel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GroundTruthSegmentation {
    /// Image rows.
    pub rows: usize,
    /// Image columns.
    pub columns: usize,
    /// Labels, `rows × columns`, row-major.
    pub labels: Vec<u32>,
    /// The layout the file had.
    pub format: RasterFormat,
}

impl GroundTruthSegmentation {
    /// The label of pixel `(row, col)`.
    pub fn get(&self, row: usize, col: usize) -> Option<u32> {
        if row >= self.rows || col >= self.columns {
            return None;
        }
        self.labels.get(row * self.columns + col).copied()
    }

    /// Distinct labels, ascending.
    pub fn distinct_labels(&self) -> Vec<u32> {
        self.labels
            .iter()
            .copied()
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect()
    }

    /// Distinct plane labels (≥ [`FIRST_PLANE_LABEL`]), ascending.
    pub fn plane_labels(&self) -> Vec<u32> {
        self.distinct_labels()
            .into_iter()
            .filter(|&l| l >= FIRST_PLANE_LABEL)
            .collect()
    }
}

/// Reads a `.gt-seg` file (plain, `.Z`, gzip or bzip2).
pub fn read_gt_seg(path: &Path) -> Result<GroundTruthSegmentation> {
    parse_gt_seg(&load(path)?, path)
}

/// Parses a (decompressed) segmentation held in memory; `name` names it in errors.
pub fn parse_gt_seg(bytes: &[u8], name: impl Into<PathBuf>) -> Result<GroundTruthSegmentation> {
    let path = name.into();
    if bytes.len() >= 4 && bytes.starts_with(&SUN_RASTER_MAGIC.to_be_bytes()) {
        return parse_sun_raster(bytes, &path);
    }
    if bytes.starts_with(b"P5") || bytes.starts_with(b"P2") {
        return parse_pgm(bytes, &path);
    }
    let header = header::parse(bytes, &path)?;
    let (start, bpp) = header.data_start(bytes.len(), &[1, 4], &path)?;
    let data = bytes.get(start..).unwrap_or_default();
    let labels = if bpp == 1 {
        data.iter().map(|&b| u32::from(b)).collect()
    } else {
        data.chunks_exact(4)
            .map(|w| u32::from_be_bytes([w[0], w[1], w[2], w[3]]))
            .collect()
    };
    Ok(GroundTruthSegmentation {
        rows: header.rows,
        columns: header.columns,
        labels,
        format: RasterFormat::RawWithHeader,
    })
}

fn parse_sun_raster(bytes: &[u8], path: &Path) -> Result<GroundTruthSegmentation> {
    let word = |k: usize| -> Result<u32> {
        bytes
            .get(4 * k..4 * k + 4)
            .and_then(|b| b.try_into().ok())
            .map(u32::from_be_bytes)
            .ok_or_else(|| {
                // The fields are read out of order: name the first incomplete word.
                let first_missing = (4 * k).min(bytes.len() / 4 * 4);
                Error::truncated(
                    path,
                    Location::Byte(first_missing as u64),
                    "the Sun rasterfile header",
                )
            })
    };
    let bad =
        |k: usize, reason: String| Error::malformed(path, Location::Byte(4 * k as u64), reason);
    let (width, height, depth, kind, map_length) =
        (word(1)?, word(2)?, word(3)?, word(5)?, word(7)?);
    for (k, side) in [(1, width), (2, height)] {
        if side == 0 || side as usize > MAX_SIDE {
            return Err(bad(
                k,
                format!("image side {side} is not between 1 and {MAX_SIDE}"),
            ));
        }
    }
    if depth != 8 {
        return Err(bad(
            3,
            format!("{depth} bits per pixel; label images have 8"),
        ));
    }
    let (columns, rows) = (width as usize, height as usize);
    let stride = columns.next_multiple_of(2);
    let start = 32usize + map_length as usize;
    let data = bytes.get(start..).ok_or_else(|| {
        Error::truncated(
            path,
            Location::Byte(32),
            format!("the {map_length}-byte colour map"),
        )
    })?;
    let padded = match kind {
        0 | 1 => data
            .get(..stride * rows)
            .map(<[u8]>::to_vec)
            .ok_or_else(|| {
                Error::truncated(
                    path,
                    Location::Byte(start as u64),
                    format!("{columns} × {rows} pixels"),
                )
            })?,
        2 => run_length_decode(data, stride * rows, path, start)?,
        _ => {
            return Err(bad(
                5,
                format!("raster type {kind} is not supported (0, 1 or 2)"),
            ));
        }
    };
    let labels = padded
        .chunks_exact(stride)
        .flat_map(|row| row.iter().take(columns).map(|&b| u32::from(b)))
        .collect();
    Ok(GroundTruthSegmentation {
        rows,
        columns,
        labels,
        format: RasterFormat::SunRaster,
    })
}

fn run_length_decode(data: &[u8], wanted: usize, path: &Path, base: usize) -> Result<Vec<u8>> {
    let mut out = Vec::with_capacity(wanted.min(data.len().saturating_mul(128)));
    let mut i = 0;
    while out.len() < wanted {
        let at = Location::Byte((base + i) as u64);
        let Some(&b) = data.get(i) else {
            return Err(Error::truncated(
                path,
                at,
                format!("run-length pixels ({} of {wanted})", out.len()),
            ));
        };
        if b != 0x80 {
            out.push(b);
            i += 1;
            continue;
        }
        match (data.get(i + 1), data.get(i + 2)) {
            (Some(0), _) => {
                out.push(0x80);
                i += 2;
            }
            (Some(&n), Some(&v)) => {
                let n = usize::from(n) + 1;
                if out.len() + n > wanted {
                    return Err(Error::malformed(path, at, "run extends beyond the image"));
                }
                out.resize(out.len() + n, v);
                i += 3;
            }
            _ => return Err(Error::truncated(path, at, "a run-length code")),
        }
    }
    Ok(out)
}

fn parse_pgm(bytes: &[u8], path: &Path) -> Result<GroundTruthSegmentation> {
    let binary = bytes.starts_with(b"P5");
    let mut pos = 2;
    let mut numbers = [0usize; 3];
    for (k, slot) in numbers.iter_mut().enumerate() {
        *slot = pgm_number(bytes, &mut pos, path, ["width", "height", "maxval"][k])?;
    }
    let [columns, rows, max_value] = numbers;
    if !(1..=MAX_SIDE).contains(&columns) || !(1..=MAX_SIDE).contains(&rows) {
        return Err(Error::malformed(
            path,
            Location::Byte(2),
            format!("PGM size {columns} × {rows} is out of range"),
        ));
    }
    if !(1..=65535).contains(&max_value) {
        return Err(Error::malformed(
            path,
            Location::Byte(2),
            format!("PGM maxval {max_value} is out of range"),
        ));
    }
    let pixels = rows * columns;
    let too_large = |i: usize, at: usize| {
        Error::malformed(
            path,
            Location::Byte(at as u64),
            format!("pixel {i} exceeds maxval {max_value}"),
        )
    };
    let labels: Vec<u32> = if binary {
        pos += 1; // the single whitespace after maxval
        let bpp = if max_value < 256 { 1 } else { 2 };
        let data = bytes.get(pos..pos + pixels * bpp).ok_or_else(|| {
            Error::truncated(
                path,
                Location::Byte(pos.min(bytes.len()) as u64),
                format!("{columns} × {rows} PGM pixels"),
            )
        })?;
        let labels: Vec<u32> = if bpp == 1 {
            data.iter().map(|&b| u32::from(b)).collect()
        } else {
            data.chunks_exact(2)
                .map(|w| u32::from(u16::from_be_bytes([w[0], w[1]])))
                .collect()
        };
        if let Some(i) = labels.iter().position(|&v| v as usize > max_value) {
            return Err(too_large(i, pos + i * bpp));
        }
        labels
    } else {
        let mut labels = Vec::with_capacity(pixels.min(bytes.len()));
        for i in 0..pixels {
            let value = pgm_number(bytes, &mut pos, path, "pixel")?;
            if value > max_value {
                let digits = bytes[..pos]
                    .iter()
                    .rev()
                    .take_while(|b| b.is_ascii_digit())
                    .count();
                return Err(too_large(i, pos - digits));
            }
            labels.push(value as u32);
        }
        labels
    };
    Ok(GroundTruthSegmentation {
        rows,
        columns,
        labels,
        format: RasterFormat::Pgm,
    })
}

/// The next decimal number of a PGM header or text body, skipping blanks and `#` comments.
fn pgm_number(bytes: &[u8], pos: &mut usize, path: &Path, what: &str) -> Result<usize> {
    loop {
        match bytes.get(*pos) {
            Some(b'#') => {
                while bytes.get(*pos).is_some_and(|&b| b != b'\n') {
                    *pos += 1;
                }
            }
            Some(b) if b.is_ascii_whitespace() => *pos += 1,
            _ => break,
        }
    }
    let start = *pos;
    while bytes.get(*pos).is_some_and(u8::is_ascii_digit) && *pos - start < 9 {
        *pos += 1;
    }
    let text = bytes.get(start..*pos).unwrap_or_default();
    std::str::from_utf8(text)
        .ok()
        .and_then(|t| t.parse::<usize>().ok())
        .ok_or_else(|| match bytes.get(start) {
            None => Error::truncated(
                path,
                Location::Byte(start as u64),
                format!("the PGM {what}"),
            ),
            Some(_) => Error::malformed(
                path,
                Location::Byte(start as u64),
                format!("PGM {what} is not a number"),
            ),
        })
}
