//! KITTI odometry benchmark files: velodyne scans, poses, timestamps and calibration.
//!
//! The layout is the one of the KITTI odometry benchmark (Geiger et al., "Are we ready for
//! autonomous driving? The KITTI vision benchmark suite", CVPR 2012;
//! <https://www.cvlibs.net/datasets/kitti/eval_odometry.php>, development kit `readme.txt`):
//!
//! ```text
//! dataset/sequences/XX/velodyne/NNNNNN.bin   N × 4 little-endian f32: x y z reflectance
//! dataset/sequences/XX/times.txt             one timestamp a line, seconds since the start
//! dataset/sequences/XX/calib.txt             P0: … P3: (3×4 projections), Tr: (3×4 velo → cam0)
//! dataset/poses/XX.txt                       12 numbers a line: row-major 3×4 [R | t]
//! dataset/sequences/XX/labels/NNNNNN.label    SemanticKITTI: N × u32, class | instance << 16
//! ```
//!
//! Frames:
//!
//! * **Velodyne scans** are in the velodyne frame, which follows REP-103: x forward, y left,
//!   z up, metres. Reflectance is in `[0, 1]` and goes to [`PointCloud::intensity`].
//! * **Poses** are `world_from_cam0`: the left grey camera's pose in the frame of the camera
//!   at frame 0, with **camera axes: x right, y down, z forward**. Multiply by the
//!   calibration's `cam0_from_velo` ([`KittiCalib::cam0_from_velo`]) to place scans
//!   ([`velodyne_poses`]), and by [`flu_from_camera`] on the left to express the world frame
//!   REP-103 style (x forward, y left, z up).
//!
//! [`KittiSequence::open`] finds the files of one sequence, both in the benchmark layout and
//! with everything in one directory (`poses.txt`, `times.txt`, `calib.txt`, `velodyne/`).
//! Writers ([`write_velodyne`], [`write_poses`], [`write_times`], [`write_calib`],
//! [`KittiLayout`]) produce the same files with fixed number formatting.
//!
//! [`PointCloud::intensity`]: raypath_geometry::PointCloud::intensity

mod calib;
mod labels;
mod poses;
mod sequence;
mod velodyne;
mod write;

use std::path::Path;

use raypath_geometry::Aabb3;

use crate::summary::{BoundingBox, Summary, TimeSpan};
use crate::{Error, Format, Location, Result};

pub use calib::{KittiCalib, parse_calib, read_calib};
pub use labels::{
    ClassCount, LABEL_BYTES, PointLabel, check_label_count, count_classes, parse_labels,
    read_labels, semantic_class_name,
};
pub use poses::{
    flu_from_camera, parse_poses, parse_times, read_poses, read_times, velodyne_poses,
};
pub use sequence::{KittiScan, KittiScans, KittiSequence, ScanFile};
pub use velodyne::{VELODYNE_POINT_BYTES, parse_velodyne, read_velodyne, velodyne_point_count};
pub use write::{
    KittiLayout, cam0_poses_from_velodyne, encode_velodyne, velodyne_poses_from_cam0, write_calib,
    write_calib_to, write_poses, write_poses_to, write_times, write_times_to, write_velodyne,
};
pub(crate) use write::{push_exp, write_file};

/// Summarizes a KITTI sequence directory or one of its files, read as `format`.
pub fn summarize(path: &Path, format: Format) -> Result<Summary> {
    let mut summary = Summary::new(format.name());
    match format {
        Format::KittiVelodyne => {
            let cloud = read_velodyne(path)?;
            summary.points = Some(cloud.len() as u64);
            summary.bbox = BoundingBox::from_aabb(&cloud.bounding_box());
        }
        Format::KittiPoses => {
            let poses = read_poses(path)?;
            summary.poses = Some(poses.len() as u64);
            summary.bbox = pose_bbox(&poses);
        }
        Format::KittiTimes => {
            let times = read_times(path)?;
            summary = summary.with_extra("times", times.len() as u64);
            summary.time_span = TimeSpan::from_times(times);
        }
        Format::KittiCalib => {
            let calib = read_calib(path)?;
            let keys: Vec<&str> = calib.keys().collect();
            summary = summary.with_extra("keys", keys);
        }
        _ if is_dataset_root(path) => return summarize_dataset(path, summary),
        _ => return summarize_sequence(path, summary),
    }
    Ok(summary)
}

/// A benchmark root (`dataset/` holding `sequences/NN/` and `poses/NN.txt`) rather than a
/// sequence directory.
pub(crate) fn is_dataset_root(path: &Path) -> bool {
    path.join("sequences").is_dir()
        && !["velodyne", "poses.txt", "times.txt", "calib.txt"]
            .iter()
            .any(|name| path.join(name).exists())
}

/// The sums over the sequences of a benchmark root, with their names in `sequences`.
fn summarize_dataset(root: &Path, mut summary: Summary) -> Result<Summary> {
    let dir = root.join("sequences");
    let entries = std::fs::read_dir(&dir).map_err(|e| Error::io(&dir, Location::File, e))?;
    let mut dirs = Vec::new();
    for entry in entries {
        let path = entry
            .map_err(|e| Error::io(&dir, Location::File, e))?
            .path();
        if path.is_dir() {
            dirs.push(path);
        }
    }
    dirs.sort();
    if dirs.is_empty() {
        return Err(Error::UnknownFormat {
            path: root.to_path_buf(),
            reason: "sequences/ holds no sequence directories".into(),
        });
    }
    let add = |total: &mut Option<u64>, part: Option<u64>| {
        if let Some(part) = part {
            *total = Some(total.unwrap_or(0) + part);
        }
    };
    let (mut names, mut times) = (Vec::new(), None);
    for dir in &dirs {
        let part = summarize_sequence(dir, Summary::new(summary.format.clone()))?;
        add(&mut summary.scans, part.scans);
        add(&mut summary.points, part.points);
        add(&mut summary.poses, part.poses);
        add(
            &mut times,
            part.extra.get("times").and_then(serde_json::Value::as_u64),
        );
        names.push(
            dir.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
        );
    }
    if let Some(times) = times {
        summary = summary.with_extra("times", times);
    }
    Ok(summary.with_extra("sequences", names))
}

fn summarize_sequence(path: &Path, mut summary: Summary) -> Result<Summary> {
    let sequence = KittiSequence::open(path)?;
    if sequence.velodyne_dir.is_some() {
        summary.scans = Some(sequence.scan_files.len() as u64);
        summary.points = Some(sequence.count_points()?);
    }
    if sequence.poses_path.is_some() {
        let poses = sequence.poses()?;
        summary.poses = Some(poses.len() as u64);
        summary.bbox = pose_bbox(&poses);
    }
    if sequence.times_path.is_some() {
        let times = sequence.times()?;
        summary = summary.with_extra("times", times.len() as u64);
        summary.time_span = TimeSpan::from_times(times);
    }
    if let Some(calib) = sequence.calib()? {
        let keys: Vec<&str> = calib.keys().collect();
        summary = summary.with_extra("calib_keys", keys);
    }
    if let Some(name) = &sequence.name {
        summary = summary.with_extra("sequence", name.clone());
    }
    if let Some(classes) = label_classes(&sequence)? {
        summary = summary.with_extra("semantic_classes", classes);
    }
    Ok(summary)
}

/// Points and instances per SemanticKITTI class over the labelled frames of a sequence, as
/// the `semantic_classes` entry of `raypath info`: `[{class, name, points, instances}]`
/// (instances counted per frame and summed). `None` when no frame has labels.
fn label_classes(sequence: &KittiSequence) -> Result<Option<serde_json::Value>> {
    let mut totals: std::collections::BTreeMap<u16, ClassCount> = Default::default();
    let mut labelled = 0usize;
    for scan in &sequence.scan_files {
        let Some(labels) = sequence.labels(scan.frame)? else {
            continue;
        };
        labelled += 1;
        for (class, count) in count_classes(&labels) {
            let total = totals.entry(class).or_default();
            total.points += count.points;
            total.instances += count.instances;
        }
    }
    if labelled == 0 {
        return Ok(None);
    }
    let rows: Vec<serde_json::Value> = totals
        .into_iter()
        .map(|(class, count)| {
            serde_json::json!({
                "class": class,
                "name": semantic_class_name(class).unwrap_or("unknown"),
                "points": count.points,
                "instances": count.instances,
            })
        })
        .collect();
    Ok(Some(
        serde_json::json!({ "frames": labelled, "classes": rows }),
    ))
}

/// Reads the next line of `lines` into `buf` (reused, so no allocation per line), for parsers
/// that need the reader again (to build errors) while they look at the line. False at the end.
pub(crate) fn next_line_into(
    lines: &mut crate::source::LineReader,
    buf: &mut String,
) -> Result<bool> {
    buf.clear();
    match lines.next_line()? {
        Some(line) => {
            buf.push_str(line);
            Ok(true)
        }
        None => Ok(false),
    }
}

/// Bounding box of pose positions (the frame of the poses).
fn pose_bbox(poses: &[raypath_geometry::Pose3]) -> Option<BoundingBox> {
    let mut bbox = Aabb3::empty();
    for pose in poses {
        bbox.extend(&pose.translation().into());
    }
    BoundingBox::from_aabb(&bbox)
}
