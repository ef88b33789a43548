//! rosbag2 robustness: thousands of truncated and mutated MCAP files and CDR messages never
//! make the reader panic.
#![allow(clippy::unwrap_used)]

use std::path::Path;
use std::sync::OnceLock;

use nalgebra::Point3;
use proptest::prelude::*;
use raypath_geometry::{PointCloud, Pose3, Scan2};
use raypath_io::rosbag::{self, BagCompression, BagWriteOptions, BagWriter, Stamp, Transform};
use raypath_io::sequence::{SweepSequence, Topics};

/// Small valid bags (uncompressed, zstd, lz4) with scans, clouds, odometry, tf and poses.
fn bases() -> &'static Vec<Vec<u8>> {
    static BASES: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    BASES.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        [
            BagCompression::None,
            BagCompression::Zstd,
            BagCompression::Lz4,
        ]
        .into_iter()
        .map(|compression| {
            let path = dir.path().join("b.mcap");
            write_base(&path, compression);
            std::fs::read(&path).unwrap()
        })
        .collect()
    })
}

fn write_base(path: &Path, compression: BagCompression) {
    let options = BagWriteOptions {
        compression,
        chunk_size_bytes: 700,
    };
    let mut w = BagWriter::create(path, &options).unwrap();
    let tf = Transform {
        stamp: Stamp::default(),
        parent: "base_link".into(),
        child: "laser".into(),
        parent_from_child: Pose3::from_xyz_rpy(0.1, 0.0, 0.0, 0.0, 0.0, 0.2),
    };
    w.write_tf("/tf_static", 1.0, &[tf]).unwrap();
    for k in 0..6 {
        let t = 1.0 + 0.1 * k as f64;
        let pose = Pose3::from_xyz_rpy(0.1 * k as f64, 0.0, 0.0, 0.0, 0.0, 0.05 * k as f64);
        w.write_odometry("/odom", t, "odom", "base_link", &pose)
            .unwrap();
        w.write_pose("/truth", t, "map", &pose).unwrap();
        let scan = Scan2 {
            angle_min_rad: -0.5,
            angle_increment_rad: 0.25,
            max_range_m: 10.0,
            ranges: vec![1.0, 2.0, f64::INFINITY, 10.0, 0.5],
            intensities: (k % 2 == 0).then(|| vec![1.0; 5]),
        };
        w.write_scan("/scan", t, "laser", &scan).unwrap();
        let mut cloud = PointCloud::from_points(
            (0..6)
                .map(|i| Point3::new(i as f32, 1.0, k as f32))
                .collect(),
        );
        cloud.intensity = Some(vec![3.0; 6]);
        if k % 2 == 1 {
            cloud.width = 3;
            cloud.height = 2;
        }
        w.write_cloud("/points", t, "laser", &cloud).unwrap();
    }
    w.finish().unwrap();
}

fn mutated() -> impl Strategy<Value = Vec<u8>> {
    (
        0..3usize,
        0.0f64..1.0,
        prop::collection::vec((0.0f64..1.0, any::<u8>()), 0..6),
    )
        .prop_map(|(which, cut, edits)| {
            let mut bytes = bases()[which].clone();
            for (at, value) in edits {
                let i = (at * bytes.len() as f64) as usize % bytes.len();
                bytes[i] = value;
            }
            let keep = 8 + ((bytes.len() - 8) as f64 * cut.sqrt()) as usize;
            bytes.truncate(keep.min(bytes.len()));
            bytes
        })
}

fn exercise(bytes: &[u8]) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.mcap");
    std::fs::write(&path, bytes).unwrap();
    let _ = rosbag::info(&path);
    if let Ok(source) = rosbag::open_planar(&path, &Topics::default()) {
        for frame in source.take(100) {
            if frame.is_err() {
                break;
            }
        }
    }
    if let Ok(seq) = SweepSequence::open(&path, &Default::default()) {
        for i in 0..seq.len() {
            let _ = seq.sweep(i);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 600, ..ProptestConfig::default() })]

    #[test]
    fn mutated_bags_never_panic(bytes in mutated()) {
        exercise(&bytes);
    }

    #[test]
    fn mutated_messages_never_panic(
        which in 0..5usize,
        edits in prop::collection::vec((0.0f64..1.0, any::<u8>()), 0..8),
        cut in 0.0f64..1.0,
    ) {
        let mut bytes = sample_message(which);
        for (at, value) in edits {
            let i = (at * bytes.len() as f64) as usize % bytes.len();
            bytes[i] = value;
        }
        bytes.truncate((bytes.len() as f64 * cut.sqrt()).ceil() as usize);
        let _ = rosbag::decode_scan(&bytes);
        let _ = rosbag::decode_cloud(&bytes);
        let _ = rosbag::decode_odometry(&bytes);
        let _ = rosbag::decode_tf(&bytes);
        let _ = rosbag::decode_pose_stamped(&bytes);
    }
}

/// One CDR message of each type (`raypath_io::samples::rosbag_cdr`).
fn sample_message(which: usize) -> Vec<u8> {
    raypath_io::samples::rosbag_cdr().swap_remove(which).bytes
}

#[test]
fn the_bases_are_valid() {
    for bytes in bases() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("b.mcap");
        std::fs::write(&path, bytes).unwrap();
        assert_eq!(
            rosbag::open_planar(&path, &Topics::default())
                .unwrap()
                .count(),
            6
        );
        let seq = SweepSequence::open(&path, &Default::default()).unwrap();
        assert_eq!(seq.len(), 6);
        assert_eq!(seq.sweep(3).unwrap().height, 2);
        let info = rosbag::info(&path).unwrap();
        assert_eq!(info.message_count, 25, "{info}");
    }
}
