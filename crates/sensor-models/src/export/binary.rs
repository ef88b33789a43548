//! A compact binary map file: the per-cell statistics `H`, `M`, `R` and the grid.
//!
//! Layout (version 1, all numbers little-endian):
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 8 | magic `RAYPMAP\0` |
//! | 8 | 4 | version `u32` = 1 |
//! | 12 | 1 | dimensions `u8`: 2 or 3 |
//! | 13 | 1 | model `u8` ([`MapKind`]: 0 statistics, 1 decay-rate, 2 reflection, 3 log-odds, 4 likelihood-field) |
//! | 14 | 1 | posterior `u8`: 0 or 1 |
//! | 15 | 1 | flags `u8`: bit 0 = no-returns included in mapping |
//! | 16 | 8 | cell size `f64`, metres |
//! | 24 | 24 | origin `3 × f64`, metres (z = 0 in 2-D) |
//! | 48 | 24 | cells per axis `3 × u64` (z = 1 in 2-D) |
//! | 72 | 16 | `r_min`, `r_max` `2 × f64`, metres |
//! | 88 | 8 | number of cells `n` `u64` (the product of the axes) |
//! | 96 | 64 | mapping summary `8 × u64` ([`MappingSummary`] in field order) |
//! | 160 | 4n | hits `H_i`, `u32` per cell (linear index, x fastest) |
//! | 160 + 4n | 4n | misses `M_i`, `u32` |
//! | 160 + 8n | 8n | path lengths `R_i`, `f64` metres |
//! | 160 + 16n | 4 | CRC-32 (IEEE) of all preceding bytes |
//!
//! The reader checks every field (magic, version, codes, finite positive geometry, the
//! cell count against the axes and the file length before allocating, finite non-negative
//! lengths, the checksum) and reports the byte offset of the first problem.

use std::io::Write;
use std::path::Path;

use nalgebra::{Point2, Point3};
use raypath_geometry::{Grid2, Grid3};

use crate::stats::{CellStats, DenseStats2, DenseStats3, MappingConfig, MappingSummary};
use crate::{SensorModelError, SensorRange};

const MAGIC: &[u8; 8] = b"RAYPMAP\0";
const VERSION: u32 = 1;
const HEADER_LEN: usize = 160;

/// The sensor model a stored map was built for (the statistics serve every model; the
/// code tells readers such as `raypath localize` which one to use by default).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapKind {
    /// Plain statistics, no preferred model.
    Statistics,
    /// The decay-rate model.
    DecayRate,
    /// The reflection model.
    Reflection,
    /// Log-odds occupancy.
    LogOdds,
    /// The likelihood-field (endpoint) model.
    LikelihoodField,
}

impl MapKind {
    fn code(self) -> u8 {
        match self {
            MapKind::Statistics => 0,
            MapKind::DecayRate => 1,
            MapKind::Reflection => 2,
            MapKind::LogOdds => 3,
            MapKind::LikelihoodField => 4,
        }
    }

    fn from_code(code: u8) -> Option<Self> {
        Some(match code {
            0 => MapKind::Statistics,
            1 => MapKind::DecayRate,
            2 => MapKind::Reflection,
            3 => MapKind::LogOdds,
            4 => MapKind::LikelihoodField,
            _ => return None,
        })
    }
}

/// The statistics of a stored map, 2-D or 3-D.
#[derive(Clone, Debug, PartialEq)]
pub enum StoredStats {
    /// A 2-D map.
    Planar(DenseStats2),
    /// A 3-D map.
    Spatial(DenseStats3),
}

/// A map file's contents.
#[derive(Clone, Debug, PartialEq)]
pub struct MapFile {
    /// The model the map was built for.
    pub kind: MapKind,
    /// Whether the full-posterior variant is meant.
    pub posterior: bool,
    /// How the map was built (range limits, no-returns).
    pub mapping: MappingConfig,
    /// The statistics and grid.
    pub stats: StoredStats,
}

impl MapFile {
    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let (axes, cell, origin, dims, cells, summary) = match &self.stats {
            StoredStats::Planar(s) => {
                let g = s.grid();
                let [x, y] = g.dims();
                let o = g.origin();
                (
                    2u8,
                    g.cell_size(),
                    [o.x, o.y, 0.0],
                    [x, y, 1],
                    s.cells(),
                    s.summary(),
                )
            }
            StoredStats::Spatial(s) => {
                let g = s.grid();
                let o = g.origin();
                (
                    3u8,
                    g.cell_size(),
                    [o.x, o.y, o.z],
                    g.dims(),
                    s.cells(),
                    s.summary(),
                )
            }
        };
        let mut out = Vec::with_capacity(HEADER_LEN + 16 * cells.len() + 4);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.push(axes);
        out.push(self.kind.code());
        out.push(u8::from(self.posterior));
        out.push(u8::from(self.mapping.include_no_returns));
        out.extend_from_slice(&cell.to_le_bytes());
        for v in origin {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for d in dims {
            out.extend_from_slice(&(d as u64).to_le_bytes());
        }
        out.extend_from_slice(&self.mapping.range.min_range_m.to_le_bytes());
        out.extend_from_slice(&self.mapping.range.max_range_m.to_le_bytes());
        out.extend_from_slice(&(cells.len() as u64).to_le_bytes());
        for v in summary_fields(summary) {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for c in cells {
            out.extend_from_slice(&c.hits().to_le_bytes());
        }
        for c in cells {
            out.extend_from_slice(&c.misses().to_le_bytes());
        }
        for c in cells {
            out.extend_from_slice(&c.path_length_m().to_le_bytes());
        }
        let crc = crc32fast::hash(&out);
        out.extend_from_slice(&crc.to_le_bytes());
        out
    }

    /// Writes the file to `writer`.
    pub fn write(&self, mut writer: impl Write, name: &str) -> Result<(), SensorModelError> {
        writer
            .write_all(&self.to_bytes())
            .map_err(|source| SensorModelError::Io {
                name: name.to_string(),
                source,
            })
    }

    /// Writes the file to `path`.
    pub fn write_file(&self, path: &Path) -> Result<(), SensorModelError> {
        std::fs::write(path, self.to_bytes()).map_err(|e| SensorModelError::io(path, e))
    }

    /// Reads a file from `path`.
    pub fn read_file(path: &Path) -> Result<Self, SensorModelError> {
        let bytes = std::fs::read(path).map_err(|e| SensorModelError::io(path, e))?;
        Self::from_bytes(&bytes, &path.display().to_string())
    }

    /// Parses a file's bytes; `name` appears in errors.
    pub fn from_bytes(bytes: &[u8], name: &str) -> Result<Self, SensorModelError> {
        let mut r = Reader {
            bytes,
            offset: 0,
            name,
        };
        if bytes.len() < HEADER_LEN + 4 {
            return Err(r.error(format!(
                "file of {} bytes is shorter than the {}-byte header and checksum",
                bytes.len(),
                HEADER_LEN + 4
            )));
        }
        if r.take(8)? != MAGIC {
            return Err(r.error_at(0, "not a raypath map (bad magic)".into()));
        }
        let version = r.u32()?;
        if version != VERSION {
            return Err(r.error_at(8, format!("unsupported version {version} (expected 1)")));
        }
        let axes = r.u8()?;
        if axes != 2 && axes != 3 {
            return Err(r.error_at(12, format!("dimensions must be 2 or 3, got {axes}")));
        }
        let kind = MapKind::from_code(r.u8()?)
            .ok_or_else(|| r.error_at(13, "unknown model code".into()))?;
        let posterior = match r.u8()? {
            0 => false,
            1 => true,
            other => {
                return Err(r.error_at(14, format!("posterior flag must be 0 or 1, got {other}")));
            }
        };
        let flags = r.u8()?;
        if flags > 1 {
            return Err(r.error_at(15, format!("unknown flags {flags:#04x}")));
        }
        let cell = r.f64()?;
        let origin = [r.f64()?, r.f64()?, r.f64()?];
        let dims_u64 = [r.u64()?, r.u64()?, r.u64()?];
        let range_at = r.offset;
        let range = SensorRange::new(r.f64()?, r.f64()?)
            .map_err(|e| r.error_at(range_at, e.to_string()))?;
        let n_at = r.offset;
        let n = r.u64()?;
        let mut summary_values = [0u64; 8];
        for v in &mut summary_values {
            *v = r.u64()?;
        }
        // Geometry.
        let mut dims = [0usize; 3];
        let mut product: u128 = 1;
        for (d, v) in dims.iter_mut().zip(dims_u64) {
            *d = usize::try_from(v).map_err(|_| r.error_at(48, format!("axis of {v} cells")))?;
            // Three u64 factors can exceed u128: saturate (any such product is refused below).
            product = product.saturating_mul(u128::from(v));
        }
        if axes == 2 && origin[2].to_bits() != 0 {
            return Err(r.error_at(
                40,
                format!("a 2-D map must have origin z = 0, got {}", origin[2]),
            ));
        }
        if axes == 2 && dims[2] != 1 {
            return Err(r.error_at(
                64,
                format!("a 2-D map must have 1 cell along z, got {}", dims[2]),
            ));
        }
        if u128::from(n) != product {
            return Err(r.error_at(n_at, format!("{n} cells but the axes give {product}")));
        }
        let expected = (n as u128) * 16 + HEADER_LEN as u128 + 4;
        if expected != bytes.len() as u128 {
            return Err(r.error_at(
                n_at,
                format!(
                    "{n} cells need {expected} bytes, the file has {}",
                    bytes.len()
                ),
            ));
        }
        let body_end = bytes.len() - 4;
        let stored_crc = u32::from_le_bytes(
            bytes
                .get(body_end..)
                .and_then(|b| b.try_into().ok())
                .ok_or_else(|| r.error_at(body_end as u64, "missing checksum".into()))?,
        );
        if crc32fast::hash(bytes.get(..body_end).unwrap_or_default()) != stored_crc {
            return Err(r.error_at(body_end as u64, "checksum mismatch (file corrupted)".into()));
        }
        let n = n as usize;
        let hits = r.take(4 * n)?;
        let misses = r.take(4 * n)?;
        let lengths_at = r.offset;
        let lengths = r.take(8 * n)?;
        let mut cells = Vec::with_capacity(n);
        for i in 0..n {
            let h = u32::from_le_bytes(le4(hits, i));
            let m = u32::from_le_bytes(le4(misses, i));
            let length = f64::from_le_bytes(le8(lengths, i));
            if !(length.is_finite() && length >= 0.0) {
                return Err(r.error_at(
                    lengths_at + 8 * i as u64,
                    format!("path length of cell {i} is {length}"),
                ));
            }
            cells.push(CellStats::new(h, m, length));
        }
        let summary = summary_from(summary_values);
        let mapping = MappingConfig {
            range,
            include_no_returns: flags & 1 == 1,
        };
        let stats = if axes == 2 {
            let grid = Grid2::new(Point2::new(origin[0], origin[1]), cell, [dims[0], dims[1]])
                .map_err(|e| r.error_at(16, e.to_string()))?;
            StoredStats::Planar(
                DenseStats2::from_parts(grid, cells, summary)
                    .map_err(|e| r.error_at(n_at, e.to_string()))?,
            )
        } else {
            let grid = Grid3::new(Point3::from(origin), cell, dims)
                .map_err(|e| r.error_at(16, e.to_string()))?;
            StoredStats::Spatial(
                DenseStats3::from_parts(grid, cells, summary)
                    .map_err(|e| r.error_at(n_at, e.to_string()))?,
            )
        };
        Ok(Self {
            kind,
            posterior,
            mapping,
            stats,
        })
    }
}

fn le4(bytes: &[u8], i: usize) -> [u8; 4] {
    bytes
        .get(4 * i..4 * i + 4)
        .and_then(|b| b.try_into().ok())
        .unwrap_or_default()
}

fn le8(bytes: &[u8], i: usize) -> [u8; 8] {
    bytes
        .get(8 * i..8 * i + 8)
        .and_then(|b| b.try_into().ok())
        .unwrap_or_default()
}

fn summary_fields(s: &MappingSummary) -> [u64; 8] {
    [
        s.rays,
        s.hits,
        s.endpoints_outside,
        s.no_returns_traced,
        s.no_returns_skipped,
        s.sub_ignored,
        s.empty,
        s.crossings,
    ]
}

fn summary_from(v: [u64; 8]) -> MappingSummary {
    MappingSummary {
        rays: v[0],
        hits: v[1],
        endpoints_outside: v[2],
        no_returns_traced: v[3],
        no_returns_skipped: v[4],
        sub_ignored: v[5],
        empty: v[6],
        crossings: v[7],
    }
}

/// Offset-tracking little-endian reads over a byte slice.
struct Reader<'a> {
    bytes: &'a [u8],
    offset: u64,
    name: &'a str,
}

impl<'a> Reader<'a> {
    fn error(&self, reason: String) -> SensorModelError {
        self.error_at(self.offset, reason)
    }

    fn error_at(&self, offset: u64, reason: String) -> SensorModelError {
        SensorModelError::Format {
            name: self.name.to_string(),
            offset,
            reason,
        }
    }

    fn take(&mut self, len: usize) -> Result<&'a [u8], SensorModelError> {
        let start = self.offset as usize;
        let slice = start
            .checked_add(len)
            .and_then(|end| self.bytes.get(start..end))
            .ok_or_else(|| self.error(format!("truncated: need {len} more bytes")))?;
        self.offset += len as u64;
        Ok(slice)
    }

    fn u8(&mut self) -> Result<u8, SensorModelError> {
        Ok(self.take(1)?.first().copied().unwrap_or_default())
    }

    fn u32(&mut self) -> Result<u32, SensorModelError> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().unwrap_or_default(),
        ))
    }

    fn u64(&mut self) -> Result<u64, SensorModelError> {
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().unwrap_or_default(),
        ))
    }

    fn f64(&mut self) -> Result<f64, SensorModelError> {
        Ok(f64::from_le_bytes(
            self.take(8)?.try_into().unwrap_or_default(),
        ))
    }
}
