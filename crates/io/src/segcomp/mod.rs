//! SegComp (Hoover et al. 1996, "An experimental comparison of range image segmentation
//! algorithms") Perceptron files: range images, ground-truth segmentations and angles.
//!
//! The benchmark is distributed as tar archives of Unix-`compress`ed files (10 training and
//! 30 test scans of polyhedral objects on a table, 512 × 512 pixels; the PPE experiments of
//! Schaefer 2020, §11.5, use them):
//!
//! * `perc.{train,test}.N` — a range image: 10 ASCII header lines (line 1 holds the number of
//!   rows, line 2 the number of columns) plus one more line, then `rows × columns` big-endian
//!   32-bit words whose low 12 bits are the range ([`RangeImage`]); converted to an organized
//!   cloud in the REP-103 sensor frame, metres, with the scanner geometry of
//!   [`PerceptronGeometry`] ([`PerceptronScan`]);
//! * `perc.*.N.gt-seg` — the ground-truth label image ([`GroundTruthSegmentation`]; labels
//!   ≥ 10 are planes);
//! * `perc.*.N.gt-ang` — angles between adjacent ground-truth planes ([`GroundTruthAngles`]).
//!
//! Every reader accepts the files plain, gzip-, bzip2- or `compress`-ed ([`crate::lzw`]); errors
//! name the line of a header or the byte offset in the decompressed data.
//!
//! ```
//! use raypath_io::segcomp::{PerceptronGeometry, parse_range_image};
//! let mut file = b"1 rows\n2 columns\n".to_vec();
//! for _ in 0..8 {
//!     file.extend_from_slice(b"header\n");
//! }
//! file.extend_from_slice(b"\n"); // the extra line
//! for word in [0x0001_0800u32, 0x0000_0fff] {
//!     file.extend_from_slice(&word.to_be_bytes());
//! }
//! let image = parse_range_image(&file, "mem")?;
//! assert_eq!((image.rows, image.columns, image.range.clone()), (1, 2, vec![0x800, 0xfff]));
//! let cloud = image.to_cloud(&PerceptronGeometry::default());
//! assert_eq!(cloud.len(), 2);
//! # Ok::<(), raypath_io::Error>(())
//! ```

mod geometry;
mod gt_ang;
mod gt_seg;
mod header;
mod range;

use std::path::Path;

pub use geometry::{PerceptronBeam, PerceptronGeometry};
pub use gt_ang::{AnglePair, GroundTruthAngles, parse_gt_ang, read_gt_ang};
pub use gt_seg::{
    FIRST_PLANE_LABEL, GroundTruthSegmentation, RasterFormat, SUN_RASTER_MAGIC, parse_gt_seg,
    read_gt_seg,
};
pub use range::{PerceptronScan, RangeImage, parse_range_image, read_perceptron, read_range_image};

use crate::summary::BoundingBox;
use crate::{Error, Format, Result, Summary, source};

/// Reads a whole file, undoing gzip, bzip2 or Unix `compress` (see [`source::open`]).
pub(crate) fn load(path: &Path) -> Result<Vec<u8>> {
    source::read_all(path)
}

/// Summarizes a SegComp file read as `format` ([`Format::SegcompRange`],
/// [`Format::SegcompGtSeg`] or [`Format::SegcompGtAng`]).
///
/// * `segcomp-range`: `width`, `height`, `points` (every pixel), `bbox` (metres), extra
///   `range_min`/`range_max` (raw counts);
/// * `segcomp-gt-seg`: `width`, `height`, `labels` (all distinct values), extras `planes`
///   (labels ≥ 10) and `raster` (file layout);
/// * `segcomp-gt-ang`: `labels` (those in any pair) and extra `pairs`.
pub fn summarize(path: &Path, format: Format) -> Result<Summary> {
    match format {
        Format::SegcompRange => {
            let scan = read_perceptron(path)?;
            let image = &scan.image;
            let mut summary = Summary::new(format.name());
            summary.width = Some(image.columns as u64);
            summary.height = Some(image.rows as u64);
            summary.points = Some(scan.cloud.len() as u64);
            summary.bbox = BoundingBox::from_aabb(&scan.cloud.bounding_box());
            let min = image.range.iter().min().copied().unwrap_or_default();
            let max = image.range.iter().max().copied().unwrap_or_default();
            Ok(summary
                .with_extra("range_min", min)
                .with_extra("range_max", max))
        }
        Format::SegcompGtSeg => {
            let seg = read_gt_seg(path)?;
            let mut summary = Summary::new(format.name())
                .with_extra("planes", seg.plane_labels().len() as u64)
                .with_extra("raster", seg.format.name());
            summary.width = Some(seg.columns as u64);
            summary.height = Some(seg.rows as u64);
            summary.labels = Some(seg.distinct_labels());
            Ok(summary)
        }
        Format::SegcompGtAng => {
            let angles = read_gt_ang(path)?;
            let mut summary =
                Summary::new(format.name()).with_extra("pairs", angles.pairs.len() as u64);
            summary.labels = Some(angles.labels());
            Ok(summary)
        }
        other => Err(Error::UnknownFormat {
            path: path.to_path_buf(),
            reason: format!("{other} is not a SegComp format"),
        }),
    }
}
