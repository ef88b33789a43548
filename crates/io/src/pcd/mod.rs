//! PCD point clouds, the file format of the Point Cloud Library: read and write.
//!
//! Format (PCD v0.7, <https://pointclouds.org/documentation/tutorials/pcd_file_format.html>):
//! a text header of `KEYWORD values` lines — `VERSION`, `FIELDS` (names), `SIZE` (bytes per
//! value: 1, 2, 4, 8), `TYPE` (`I` signed, `U` unsigned, `F` float), `COUNT` (values per field,
//! default 1), `WIDTH`, `HEIGHT` (> 1 for organized clouds), `VIEWPOINT tx ty tz qw qx qy qz`
//! (sensor pose), `POINTS` (= `WIDTH × HEIGHT`) and last `DATA ascii|binary|binary_compressed`;
//! `#` starts a comment line. The data follows:
//!
//! * `ascii`: one point per line, values separated by blanks;
//! * `binary`: little-endian values point by point (array of structures);
//! * `binary_compressed`: `u32` compressed size, `u32` uncompressed size (both little endian),
//!   then [LZF](lzf) data that expands to the values **field by field** (structure of arrays:
//!   all `x`, then all `y`, …).
//!
//! ## Mapping to [`PointCloud`]
//!
//! `x y z` are required and become the points (metres, in the frame of the file; PCL uses the
//! sensor frame for single scans). `intensity` becomes the intensity channel, `rgb`/`rgba`
//! (4 bytes; a float whose bits hold `0x00RRGGBB` as PCL writes it, or an integer) the colour
//! (alpha is dropped), and the label channel comes from the field chosen by
//! [`ReadOptions::label_from`] — by default a field named `label`. SynPEB (Schaefer 2020,
//! ch. 11) stores the ground-truth plane id in `intensity`: read it with
//! [`LabelSource::Intensity`]. Labels must be non-negative integers (a float field must hold
//! integral values); a missing pixel (NaN coordinates) with a NaN label gets label 0. All other
//! fields, of any `SIZE`/`TYPE`/`COUNT`, are skipped. Clouds with `HEIGHT > 1` stay organized;
//! points with NaN coordinates are kept as missing pixels. The viewpoint becomes
//! [`PcdCloud::cloud_from_sensor`].
//!
//! ## Errors
//!
//! Header problems name the line, binary problems the byte offset (for `binary_compressed`,
//! the offset of the LZF token, or of the block with the position in the decompressed data).
//! Lengths are checked before anything is allocated: binary data must be present in full, and
//! compressed data cannot claim to expand more than LZF can.
//!
//! ```
//! use raypath_io::pcd::{self, DataEncoding, LabelSource, ReadOptions};
//! let text = "VERSION .7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\n\
//!             WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n1 2 3 14\nnan nan nan nan\n";
//! let options = ReadOptions { label_from: LabelSource::Intensity };
//! let read = pcd::read_pcd_bytes(text.as_bytes(), "mem.pcd", &options)?;
//! assert_eq!(read.cloud.label, Some(vec![14, 0]));
//! assert_eq!(read.cloud.num_valid(), 1);
//! let mut bytes = Vec::new();
//! let options = pcd::WriteOptions::new(DataEncoding::BinaryCompressed);
//! pcd::write_pcd_to(&mut bytes, &read.cloud, "out.pcd".as_ref(), &options)?;
//! # Ok::<(), raypath_io::Error>(())
//! ```

mod binary;
mod fields;
mod header;
pub mod lzf;
mod read;
mod write;

use std::collections::BTreeSet;
use std::io::{BufRead, Cursor};
use std::path::{Path, PathBuf};

use raypath_geometry::{PointCloud, Pose3};

pub use header::{DataEncoding, FieldType, PcdField, PcdHeader};
pub use write::{WriteOptions, write_pcd, write_pcd_to, write_pcd_with};

use crate::summary::BoundingBox;
use crate::{Result, Summary, source};

/// Which PCD field fills [`PointCloud::label`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum LabelSource {
    /// The field named `label`, when there is one (no labels otherwise).
    #[default]
    LabelField,
    /// The `intensity` field (the SynPEB convention); an error when there is none.
    Intensity,
    /// The field with this name; an error when there is none.
    Field(String),
    /// No labels.
    None,
}

/// Options of the PCD reader.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ReadOptions {
    /// Where labels come from.
    pub label_from: LabelSource,
}

impl ReadOptions {
    /// Labels from the `intensity` field, as SynPEB stores them.
    pub fn synpeb() -> Self {
        Self {
            label_from: LabelSource::Intensity,
        }
    }
}

/// A PCD file read into memory.
#[derive(Clone, Debug, PartialEq)]
pub struct PcdCloud {
    /// The header as parsed.
    pub header: PcdHeader,
    /// The points and their channels.
    pub cloud: PointCloud,
    /// The sensor pose in the frame of the points (`VIEWPOINT`; identity when absent).
    pub cloud_from_sensor: Pose3,
}

/// Reads a PCD file (plain, gzip or bzip2).
pub fn read_pcd(path: &Path, options: &ReadOptions) -> Result<PcdCloud> {
    read::read(source::open(path)?, path, options)
}

/// Reads PCD data from `reader`; `name` names the source in errors.
pub fn read_pcd_from(
    reader: impl BufRead,
    name: impl Into<PathBuf>,
    options: &ReadOptions,
) -> Result<PcdCloud> {
    read::read(reader, &name.into(), options)
}

/// Reads PCD data held in memory; `name` names it in errors.
pub fn read_pcd_bytes(
    bytes: &[u8],
    name: impl Into<PathBuf>,
    options: &ReadOptions,
) -> Result<PcdCloud> {
    read_pcd_from(Cursor::new(bytes), name, options)
}

/// Reads only the header of a PCD file.
pub fn read_pcd_header(path: &Path) -> Result<PcdHeader> {
    let mut reader = source::open(path)?;
    header::read_header(&mut reader, path)
}

/// Summarizes a PCD file for `raypath info`.
///
/// Keys: `points`, `width`, `height`, `bbox` (valid points), `labels` and extras `data`
/// (encoding), `fields` (names), `valid_points`. Labels come from a `label` field
/// (`label_field: "label"`); without one, from the `intensity` field when the cloud is
/// organized and every intensity of a valid point is a non-negative integer — the SynPEB
/// convention — reported with `label_field: "intensity"`. An unorganized cloud's intensities
/// are taken for what they are, since lidar intensities are often integers too.
pub fn summarize(path: &Path) -> Result<Summary> {
    let read = read_pcd(path, &ReadOptions::default())?;
    let cloud = &read.cloud;
    let mut summary = Summary::new("pcd")
        .with_extra("data", read.header.data.name())
        .with_extra("fields", read.header.field_names())
        .with_extra("valid_points", cloud.num_valid() as u64);
    summary.points = Some(cloud.len() as u64);
    summary.width = Some(cloud.width as u64);
    summary.height = Some(cloud.height as u64);
    summary.bbox = BoundingBox::from_aabb(&cloud.bounding_box());
    if let Some(labels) = &cloud.label {
        summary.labels = Some(
            labels
                .iter()
                .copied()
                .collect::<BTreeSet<_>>()
                .into_iter()
                .collect(),
        );
        summary = summary.with_extra("label_field", "label");
    } else if let Some(labels) = intensity_labels(cloud) {
        summary.labels = Some(labels);
        summary = summary.with_extra("label_field", "intensity");
    }
    Ok(summary)
}

/// The distinct intensities of valid points of an organized cloud when all are label-like.
fn intensity_labels(cloud: &PointCloud) -> Option<Vec<u32>> {
    let intensity = cloud.intensity.as_ref()?;
    if !cloud.is_organized() {
        return None;
    }
    let mut labels = BTreeSet::new();
    for (i, v) in intensity.iter().enumerate() {
        if !cloud.is_valid(i) {
            continue;
        }
        if v.fract() != 0.0 || *v < 0.0 || f64::from(*v) > f64::from(u32::MAX) {
            return None;
        }
        labels.insert(*v as u32);
    }
    Some(labels.into_iter().collect())
}
