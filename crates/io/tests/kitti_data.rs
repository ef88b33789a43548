//! KITTI readers on the real pole-map sequences (RAYPATH_DATA/kitti-poles) and on a
//! synthetic sequence in the benchmark layout.

// Test helpers (outside #[test] functions) panic on setup failures too.
#![allow(clippy::unwrap_used)]

use std::path::{Path, PathBuf};

use raypath_io::data::require;
use raypath_io::kitti::{self, KittiSequence};

fn line_count(path: &Path) -> usize {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.trim().is_empty())
        .count()
}

#[test]
fn pole_sequences_have_one_time_per_pose() {
    let Some(root) = require("kitti-poles") else {
        return;
    };
    for seq in ["00", "01", "02", "03", "04", "05", "06", "07"] {
        let sequence = KittiSequence::open(&root.join(seq)).unwrap();
        assert_eq!(sequence.name.as_deref(), Some(seq));
        assert!(sequence.velodyne_dir.is_none() && sequence.scan_files.is_empty());
        let poses = sequence.poses().unwrap();
        let times = sequence.times().unwrap();
        assert_eq!(poses.len(), times.len(), "sequence {seq}");
        assert_eq!(poses.len(), line_count(&root.join(seq).join("poses.txt")));
        // The trajectory starts at the identity, at time 0.
        let first = poses[0];
        assert!(first.translation().norm() < 1e-9 && first.rotation().angle() < 1e-6);
        assert_eq!(times[0], 0.0);
        // KITTI records at 10 Hz.
        let rate = (times.len() - 1) as f64 / (times[times.len() - 1] - times[0]);
        assert!((rate - 10.0).abs() < 0.5, "sequence {seq}: {rate} Hz");
    }
}

#[test]
fn real_frames_have_one_semantic_label_per_point() {
    let Some(root) = require("kitti/sequences") else {
        return;
    };
    for seq in ["00", "01", "04", "07"] {
        let sequence = KittiSequence::open(&root.join(seq)).unwrap();
        assert_eq!(sequence.scan_files.len(), 10, "sequence {seq}");
        let mut poles = 0;
        for scan in sequence.scans() {
            let scan = scan.unwrap();
            let labels = sequence.labels(scan.frame).unwrap().unwrap();
            assert_eq!(labels.len(), scan.points.len());
            let counts = kitti::count_classes(&labels);
            // Every class is one SemanticKITTI defines; roads and poles are there.
            assert!(
                counts
                    .keys()
                    .all(|&c| kitti::semantic_class_name(c).is_some())
            );
            assert!(counts[&40].points > 10_000, "sequence {seq}: road");
            poles += counts.get(&80).map_or(0, |c| c.points);
        }
        // The data README: ≈ 600–720 pole points per frame.
        assert!(
            (4000..9000).contains(&poles),
            "sequence {seq}: {poles} pole points"
        );
    }
    let summary = raypath_io::summarize(&root.join("00")).unwrap();
    let classes = &summary.extra["semantic_classes"];
    assert_eq!(classes["frames"], 10);
    let pole = classes["classes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["class"] == 80)
        .unwrap();
    assert_eq!(pole["name"], "pole");
}

#[test]
fn sequence_00_summary() {
    let Some(dir) = require("kitti-poles/00") else {
        return;
    };
    let poses = kitti::read_poses(&dir.join("poses.txt")).unwrap();
    assert_eq!(poses.len(), 4541);
    // The vehicle drives forward along camera z first.
    assert!(poses[10].translation().z > 5.0);
    let summary = raypath_io::summarize(&dir).unwrap();
    assert_eq!(summary.format, "kitti");
    assert_eq!(summary.poses, Some(4541));
    assert_eq!(summary.extra["times"], 4541);
    assert_eq!(summary.scans, None);
    let span = summary.time_span.unwrap();
    assert_eq!(span.start, 0.0);
    assert!((span.duration - 470.0).abs() < 10.0, "{span:?}");
    // Camera frame: y (down) varies little, x and z span hundreds of metres.
    let bbox = summary.bbox.unwrap();
    assert!(bbox.max[0] - bbox.min[0] > 300.0 && bbox.max[2] - bbox.min[2] > 300.0);
    assert!(bbox.max[1] - bbox.min[1] < 50.0);

    let poses_summary = raypath_io::summarize(&dir.join("poses.txt")).unwrap();
    assert_eq!(poses_summary.format, "kitti-poses");
    assert_eq!(poses_summary.poses, Some(4541));
    assert_eq!(poses_summary.bbox, summary.bbox);
    let times_summary = raypath_io::summarize(&dir.join("times.txt")).unwrap();
    assert_eq!(times_summary.format, "kitti-times");
    assert_eq!(times_summary.extra["times"], 4541);

    // The pole map is in a lidar-aligned frame: (x, y) ≈ (z, −x) of the camera poses, so the
    // REP-103 trajectory passes near the poles.
    let poles = raypath_io::point_csv::PointCsv::read(&dir.join("poles.csv")).unwrap();
    let flu = kitti::flu_from_camera();
    let trajectory: Vec<_> = poses.iter().map(|p| (flu * *p).translation()).collect();
    let near = poles
        .points()
        .iter()
        .filter(|pole| {
            trajectory
                .iter()
                .any(|t| (t.x - pole.x).hypot(t.y - pole.y) < 30.0)
        })
        .count();
    assert!(
        near * 10 >= poles.len() * 9,
        "{near} of {} poles near the path",
        poles.len()
    );
}

/// Writes a sequence in the benchmark layout: dataset/sequences/05/…, dataset/poses/05.txt.
fn synthetic_benchmark(root: &Path) -> PathBuf {
    let seq = root.join("dataset/sequences/05");
    std::fs::create_dir_all(seq.join("velodyne")).unwrap();
    std::fs::create_dir_all(root.join("dataset/poses")).unwrap();
    for frame in [0u32, 2, 1, 10] {
        let mut bytes = Vec::new();
        for i in 0..=frame {
            for v in [i as f32, -(frame as f32), 0.5, 0.25] {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        std::fs::write(seq.join("velodyne").join(format!("{frame:06}.bin")), bytes).unwrap();
    }
    std::fs::write(seq.join("times.txt"), "0.0\n0.1\n0.2\n").unwrap();
    std::fs::write(
        seq.join("calib.txt"),
        "P0: 7.1e2 0 6.0e2 0 0 7.1e2 1.8e2 0 0 0 1 0\nTr: 0 -1 0 0 0 0 -1 -0.08 1 0 0 -0.27\n",
    )
    .unwrap();
    std::fs::write(
        root.join("dataset/poses/05.txt"),
        "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0.5 0 1 0 0 0 0 1 1.0\n1 0 0 1 0 1 0 0 0 0 1 2\n",
    )
    .unwrap();
    seq
}

#[test]
fn benchmark_layout_is_found_and_read_lazily() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = synthetic_benchmark(tmp.path());
    let sequence = KittiSequence::open(&dir).unwrap();
    assert_eq!(sequence.name.as_deref(), Some("05"));
    assert!(
        sequence
            .poses_path
            .as_ref()
            .unwrap()
            .ends_with("poses/05.txt")
    );
    let frames: Vec<u64> = sequence.scan_files.iter().map(|f| f.frame).collect();
    assert_eq!(frames, [0, 1, 2, 10]);
    let scans: Vec<_> = sequence.scans().map(Result::unwrap).collect();
    assert_eq!(scans.len(), 4);
    for scan in &scans {
        assert_eq!(scan.points.len() as u64, scan.frame + 1);
        assert_eq!(scan.points.points[0].y, -(scan.frame as f32));
        assert_eq!(scan.points.intensity.as_ref().unwrap()[0], 0.25);
    }
    assert_eq!(sequence.count_points().unwrap(), 1 + 2 + 3 + 11);
    assert_eq!(sequence.scan(2).unwrap().unwrap().len(), 3);
    assert!(sequence.scan(3).is_none());
    let poses = sequence.poses().unwrap();
    assert_eq!(poses[1].translation().z, 1.0);
    let calib = sequence.calib().unwrap().unwrap();
    let cam0_from_velo = calib.cam0_from_velo().unwrap();
    // Velodyne forward (x) is camera forward (z), velodyne left (y) is camera −x.
    let forward = cam0_from_velo.transform_vector(&nalgebra::Vector3::x());
    assert!((forward - nalgebra::Vector3::z()).norm() < 1e-12);
    let left = cam0_from_velo.transform_vector(&nalgebra::Vector3::y());
    assert!((left + nalgebra::Vector3::x()).norm() < 1e-12);
    // flu_from_camera undoes that rotation.
    let flu_velo = kitti::flu_from_camera() * cam0_from_velo;
    assert!(flu_velo.rotation().angle() < 1e-12);

    let summary = raypath_io::summarize(&dir).unwrap();
    assert_eq!(summary.format, "kitti");
    assert_eq!(summary.scans, Some(4));
    assert_eq!(summary.points, Some(17));
    assert_eq!(summary.poses, Some(3));
    assert_eq!(summary.extra["sequence"], "05");
    let velo = raypath_io::summarize(&dir.join("velodyne/000010.bin")).unwrap();
    assert_eq!(velo.format, "kitti-velodyne");
    assert_eq!(velo.points, Some(11));
    assert_eq!(velo.bbox.unwrap().max, [10.0, -10.0, 0.5]);
    let calib_summary = raypath_io::summarize(&dir.join("calib.txt")).unwrap();
    assert_eq!(calib_summary.format, "kitti-calib");
    assert_eq!(calib_summary.extra["keys"], serde_json::json!(["P0", "Tr"]));

    // A scan file whose size is not a multiple of 16 is reported by name and offset.
    std::fs::write(dir.join("velodyne/000011.bin"), [0u8; 20]).unwrap();
    let sequence = KittiSequence::open(&dir).unwrap();
    let err = sequence.count_points().unwrap_err();
    assert!(err.to_string().contains("000011.bin: byte 16"), "{err}");
    std::fs::write(dir.join("velodyne/scan.bin"), [0u8; 16]).unwrap();
    assert!(KittiSequence::open(&dir).is_err());
}

#[test]
fn empty_directory_is_not_a_sequence() {
    let tmp = tempfile::tempdir().unwrap();
    assert!(KittiSequence::open(tmp.path()).is_err());
}
