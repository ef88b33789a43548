//! SemanticKITTI point labels: `labels/NNNNNN.label` beside `velodyne/NNNNNN.bin`.
//!
//! One little-endian `u32` per point of the scan, in the scan's point order: the semantic
//! class in the low 16 bits, the instance id in the high 16 bits (Behley et al.,
//! "SemanticKITTI: A Dataset for Semantic Scene Understanding of LiDAR Sequences", ICCV 2019;
//! class ids and names as in the dataset's `semantic-kitti.yaml`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::{Error, Location, Result, source};

/// Bytes of one label.
pub const LABEL_BYTES: u64 = 4;

/// The label of one point.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PointLabel {
    /// Semantic class (low 16 bits), e.g. 40 road, 50 building, 71 trunk, 80 pole,
    /// 81 traffic sign; see [`semantic_class_name`].
    pub class: u16,
    /// Instance id (high 16 bits); 0 for classes without instances.
    pub instance: u16,
}

impl PointLabel {
    /// Splits a raw label: class in the low 16 bits, instance in the high 16.
    pub fn from_raw(raw: u32) -> Self {
        Self {
            class: (raw & 0xffff) as u16,
            instance: (raw >> 16) as u16,
        }
    }

    /// The raw `u32` as stored in the file.
    pub fn raw(self) -> u32 {
        u32::from(self.class) | (u32::from(self.instance) << 16)
    }
}

/// The SemanticKITTI class names (`semantic-kitti.yaml`), by id.
const CLASS_NAMES: [(u16, &str); 34] = [
    (0, "unlabeled"),
    (1, "outlier"),
    (10, "car"),
    (11, "bicycle"),
    (13, "bus"),
    (15, "motorcycle"),
    (16, "on-rails"),
    (18, "truck"),
    (20, "other-vehicle"),
    (30, "person"),
    (31, "bicyclist"),
    (32, "motorcyclist"),
    (40, "road"),
    (44, "parking"),
    (48, "sidewalk"),
    (49, "other-ground"),
    (50, "building"),
    (51, "fence"),
    (52, "other-structure"),
    (60, "lane-marking"),
    (70, "vegetation"),
    (71, "trunk"),
    (72, "terrain"),
    (80, "pole"),
    (81, "traffic-sign"),
    (99, "other-object"),
    (252, "moving-car"),
    (253, "moving-bicyclist"),
    (254, "moving-person"),
    (255, "moving-motorcyclist"),
    (256, "moving-on-rails"),
    (257, "moving-bus"),
    (258, "moving-truck"),
    (259, "moving-other-vehicle"),
];

/// The SemanticKITTI name of a class id (`80` → `"pole"`), `None` for ids the dataset does
/// not define.
pub fn semantic_class_name(class: u16) -> Option<&'static str> {
    CLASS_NAMES
        .binary_search_by_key(&class, |&(id, _)| id)
        .ok()
        .map(|i| CLASS_NAMES[i].1)
}

/// Reads a `.label` file (plain or compressed).
pub fn read_labels(path: &Path) -> Result<Vec<PointLabel>> {
    parse_labels(&source::read_all(path)?, path)
}

/// Parses labels held in memory; `name` is used in errors. Fails when the length is not a
/// multiple of 4 bytes. Class ids the dataset does not define are kept as they are.
pub fn parse_labels(bytes: &[u8], name: impl Into<PathBuf>) -> Result<Vec<PointLabel>> {
    let len = bytes.len() as u64;
    if len % LABEL_BYTES != 0 {
        return Err(Error::malformed(
            name.into(),
            Location::Byte(len - len % LABEL_BYTES),
            format!(
                "file size {len} is not a multiple of {LABEL_BYTES} bytes (one u32 per point); \
                 the last label is incomplete"
            ),
        ));
    }
    Ok(bytes
        .chunks_exact(LABEL_BYTES as usize)
        .map(|b| PointLabel::from_raw(u32::from_le_bytes([b[0], b[1], b[2], b[3]])))
        .collect())
}

/// Checks that a scan and its labels have one label per point.
pub fn check_label_count(labels: &[PointLabel], points: usize, name: &Path) -> Result<()> {
    if labels.len() == points {
        return Ok(());
    }
    Err(Error::malformed(
        name,
        Location::File,
        format!(
            "{} labels for a scan of {points} points (SemanticKITTI has one label per point)",
            labels.len()
        ),
    ))
}

/// Points and distinct instances of one class.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ClassCount {
    /// Labelled points.
    pub points: u64,
    /// Distinct non-zero instance ids.
    pub instances: u64,
}

/// Points and distinct instances per class of a set of labels.
pub fn count_classes(labels: &[PointLabel]) -> BTreeMap<u16, ClassCount> {
    let mut points: BTreeMap<u16, u64> = BTreeMap::new();
    let mut instances = std::collections::BTreeSet::new();
    for label in labels {
        *points.entry(label.class).or_default() += 1;
        if label.instance != 0 {
            instances.insert(*label);
        }
    }
    points
        .into_iter()
        .map(|(class, points)| {
            let instances = instances.iter().filter(|l| l.class == class).count() as u64;
            (class, ClassCount { points, instances })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_class_and_instance() {
        let raw = 80u32 | (7 << 16);
        let label = PointLabel::from_raw(raw);
        assert_eq!((label.class, label.instance), (80, 7));
        assert_eq!(label.raw(), raw);
        let bytes: Vec<u8> = [raw, 40].iter().flat_map(|v| v.to_le_bytes()).collect();
        let labels = parse_labels(&bytes, "x.label").unwrap();
        assert_eq!(
            labels[1],
            PointLabel {
                class: 40,
                instance: 0
            }
        );
    }

    #[test]
    fn names_are_sorted_and_known() {
        assert!(CLASS_NAMES.windows(2).all(|w| w[0].0 < w[1].0));
        assert_eq!(semantic_class_name(80), Some("pole"));
        assert_eq!(semantic_class_name(71), Some("trunk"));
        assert_eq!(semantic_class_name(81), Some("traffic-sign"));
        assert_eq!(semantic_class_name(3), None);
    }

    #[test]
    fn truncated_file_names_the_byte() {
        let err = parse_labels(&[0, 0, 0, 0, 1], "seq/labels/000001.label").unwrap_err();
        let text = err.to_string();
        assert!(
            text.contains("000001.label") && text.contains("byte 4"),
            "{text}"
        );
    }

    #[test]
    fn counts_points_and_instances() {
        let labels: Vec<PointLabel> = [80 | (1 << 16), 80 | (1 << 16), 80 | (2 << 16), 40, 40]
            .into_iter()
            .map(PointLabel::from_raw)
            .collect();
        let counts = count_classes(&labels);
        assert_eq!(
            counts[&80],
            ClassCount {
                points: 3,
                instances: 2
            }
        );
        assert_eq!(
            counts[&40],
            ClassCount {
                points: 2,
                instances: 0
            }
        );
    }
}
