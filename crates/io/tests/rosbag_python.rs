//! rosbag2 against independent tools: bags written by the python `rosbags` package from the
//! real CARMEN and KITTI files read back by raypath equal what raypath's CARMEN and KITTI
//! readers return; bags raypath writes are read by the python `mcap` reader with
//! `mcap_ros2`. Skipped (with a message) without python3 and those packages, unless
//! `RAYPATH_REQUIRE_PYTHON=1`.
#![allow(clippy::unwrap_used)]

use std::path::Path;
use std::process::Command;

use raypath_geometry::{Pose2, Pose3, Scan2};
use raypath_io::rosbag::{self, BagCompression, BagWriteOptions};
use raypath_io::sequence::{
    Origin, PlanarFrame, PlanarOptions, SweepFormat, SweepOptions, SweepSequence, Topics,
    read_planar,
};
use serde_json::Value;

mod common;
use common::{assert_pose2, assert_pose3, assert_same_scan};

fn fixture(name: &str) -> String {
    format!("{}/tests/fixtures/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn python(args: &[&str]) -> String {
    let out = Command::new("python3").args(args).output().unwrap();
    assert!(
        out.status.success(),
        "python3 {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn rosbags_carmen_bags_equal_the_log() {
    let Some(log) = raypath_io::data::require("carmen/corrected/intel-corrected.log.gz") else {
        return;
    };
    if !raypath_io::data::require_python("rosbags, mcap, mcap_ros2, numpy") {
        return;
    }
    let frames = read_planar(&log, &PlanarOptions::default()).unwrap();
    let range_max = frames[0].scan.max_range_m;
    assert!(frames.iter().all(|f| f.scan.max_range_m == range_max));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    python(&[
        &fixture("make_bags.py"),
        "carmen",
        log.to_str().unwrap(),
        &range_max.to_string(),
        "0",
        out,
    ]);

    // Dynamic tf base_link → laser with each scan.
    let tf = read_planar(&dir.path().join("carmen_tf"), &PlanarOptions::default()).unwrap();
    assert_eq!(tf.len(), frames.len());
    for (k, (a, b)) in frames.iter().zip(&tf).enumerate() {
        let what = format!("carmen_tf scan {k}");
        assert!((a.stamp_secs - b.stamp_secs).abs() < 1e-9, "{what}");
        assert_same_scan(&a.scan, &b.scan, &what);
        assert_pose2(&a.world_from_robot, &b.world_from_robot, 1e-9, &what);
        assert_pose2(&a.world_from_laser, &b.world_from_laser, 1e-9, &what);
        assert!(b.reference.is_none());
        assert!(matches!(b.origin, Origin::LogTimeNs(_)));
    }

    // Identity mounting on /tf_static, the corrected laser pose as the reference topic.
    let with_ref = read_planar(&dir.path().join("carmen_ref"), &PlanarOptions::default()).unwrap();
    assert_eq!(with_ref.len(), frames.len());
    for (k, (a, b)) in frames.iter().zip(&with_ref).enumerate() {
        let what = format!("carmen_ref scan {k}");
        assert_same_scan(&a.scan, &b.scan, &what);
        assert_pose2(&a.world_from_robot, &b.world_from_robot, 1e-9, &what);
        assert_pose2(&a.world_from_robot, &b.world_from_laser, 1e-9, &what);
        assert_pose2(
            &a.world_from_laser,
            b.reference.as_ref().unwrap(),
            1e-9,
            &what,
        );
    }
    let info = rosbag::info(&dir.path().join("carmen_ref")).unwrap();
    assert!(info.indexed);
    assert_eq!(info.compression, vec!["none".to_string()]);
    let scan = info.topics.iter().find(|t| t.name == "/scan").unwrap();
    assert_eq!(scan.message_count, frames.len() as u64);
    let span = frames[frames.len() - 1].stamp_secs - frames[0].stamp_secs;
    assert!((scan.rate_hz.unwrap() - (frames.len() - 1) as f64 / span).abs() < 1e-6);
}

#[test]
fn rosbags_kitti_bags_equal_the_sequence() {
    let Some(seq_dir) = raypath_io::data::require("kitti/sequences/00") else {
        return;
    };
    if !raypath_io::data::require_python("rosbags, mcap, mcap_ros2, numpy") {
        return;
    }
    let seq = SweepSequence::open(&seq_dir, &SweepOptions::default()).unwrap();
    let n = 3;
    let dir = tempfile::tempdir().unwrap();
    python(&[
        &fixture("make_bags.py"),
        "kitti",
        seq_dir.to_str().unwrap(),
        &n.to_string(),
        dir.path().to_str().unwrap(),
    ]);
    for name in ["kitti", "kitti_be"] {
        let bag = rosbag::open_sweeps(&dir.path().join(name), &Topics::default()).unwrap();
        assert_eq!(bag.format, SweepFormat::Bag);
        assert_eq!(bag.len(), n);
        for k in 0..n {
            let what = format!("{name} sweep {k}");
            assert!(
                (bag.stamps_secs[k] - seq.stamps_secs[k]).abs() < 1e-9,
                "{what}"
            );
            let truth = &seq.reference.as_ref().unwrap()[k];
            assert_pose3(&bag.odometry.as_ref().unwrap()[k], truth, 1e-9, &what);
            assert_pose3(&bag.reference.as_ref().unwrap()[k], truth, 1e-9, &what);
            let cloud = bag.sweep(k).unwrap();
            let want = seq.sweep(k).unwrap();
            assert!(cloud.len() > 100_000, "{what}");
            assert_eq!(cloud, want, "{what}");
        }
    }
}

fn frames(n: usize) -> Vec<PlanarFrame> {
    (0..n)
        .map(|k| {
            let robot = Pose2::new(k as f64, 0.5 * k as f64, 0.1 * k as f64);
            let mount = Pose2::new(0.25, 0.0, 0.0);
            PlanarFrame {
                stamp_secs: 1_700_000_000.5 + k as f64 * 0.1,
                ipc_stamp_secs: None,
                scan: Scan2 {
                    angle_min_rad: -1.5,
                    angle_increment_rad: 0.01,
                    max_range_m: 25.0,
                    ranges: (0..301).map(|i| 0.5 + 0.01 * i as f64 + k as f64).collect(),
                    intensities: Some((0..301).map(|i| i as f64).collect()),
                },
                world_from_robot: robot,
                world_from_laser: robot * mount,
                reference: Some(Pose2::new(k as f64 + 0.1, 0.0, 0.0) * mount),
                origin: Origin::Line(k as u64 + 1),
            }
        })
        .collect()
}

fn read_back(path: &Path) -> Value {
    serde_json::from_str(&python(&[&fixture("read_bag.py"), path.to_str().unwrap()])).unwrap()
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

#[test]
fn python_mcap_reads_our_bags() {
    if !raypath_io::data::require_python("rosbags, mcap, mcap_ros2, numpy") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let planar = frames(7);
    for compression in [
        BagCompression::Zstd,
        BagCompression::Lz4,
        BagCompression::None,
    ] {
        let options = BagWriteOptions {
            compression,
            ..BagWriteOptions::default()
        };
        let bag = dir.path().join(format!("planar-{compression:?}"));
        rosbag::write_planar(&bag, &planar, &options).unwrap();
        let file = bag.join(format!("planar-{compression:?}_0.mcap"));
        let json = read_back(&file);
        assert_eq!(json["profile"], "ros2");
        let topics = json["topics"].as_object().unwrap();
        let expect = [
            ("/scan", "sensor_msgs/msg/LaserScan", 7),
            ("/odom", "nav_msgs/msg/Odometry", 7),
            ("/tf", "tf2_msgs/msg/TFMessage", 7),
            ("/tf_static", "tf2_msgs/msg/TFMessage", 1),
            ("/reference", "geometry_msgs/msg/PoseStamped", 7),
        ];
        assert_eq!(topics.len(), expect.len(), "{json}");
        for (topic, schema, count) in expect {
            let t = &topics[topic];
            assert_eq!(t["schema"], schema, "{topic}");
            assert_eq!(t["schema_encoding"], "ros2msg", "{topic}");
            assert_eq!(t["message_encoding"], "cdr", "{topic}");
            assert_eq!(t["count"], count, "{topic}");
        }
        let scan = &topics["/scan"]["first"];
        assert_eq!(scan["header"]["frame_id"], "laser");
        assert_eq!(scan["header"]["stamp"]["sec"], 1_700_000_000);
        assert_eq!(scan["header"]["stamp"]["nanosec"], 500_000_000);
        assert_eq!(
            topics["/scan"]["first_log_time"],
            1_700_000_000_500_000_000u64
        );
        assert_eq!(scan["ranges"]["len"], 301);
        assert_eq!(f(&scan["ranges"]["head"][2]) as f32, 0.52f32);
        assert_eq!(f(&scan["range_max"]) as f32, 25.0);
        assert_eq!(f(&scan["angle_min"]) as f32, -1.5f32);
        assert_eq!(scan["intensities"]["head"][3], 3.0);
        let odom = &topics["/odom"]["first"];
        assert_eq!(odom["child_frame_id"], "base_link");
        assert_eq!(odom["header"]["frame_id"], "odom");
        assert_eq!(odom["pose"]["pose"]["orientation"]["w"], 1.0);
        assert_eq!(odom["pose"]["covariance"]["len"], 36);
        let tf_static = &topics["/tf_static"]["first"]["transforms"];
        assert_eq!(tf_static["len"], 1);
        let mount = &tf_static["head"][0];
        assert_eq!(mount["child_frame_id"], "laser");
        assert_eq!(mount["header"]["frame_id"], "base_link");
        assert!((f(&mount["transform"]["translation"]["x"]) - 0.25).abs() < 1e-12);
        let reference = &topics["/reference"]["first"];
        assert_eq!(reference["header"]["frame_id"], "map");
        assert!((f(&reference["pose"]["position"]["x"]) - 0.1).abs() < 1e-12);
    }

    // Point clouds, organized, as one .mcap file.
    let cloud_frames: Vec<f64> = (0..4).map(|k| 50.0 + k as f64).collect();
    let seq = SweepSequence::from_fn(
        "memory",
        SweepFormat::Bag,
        cloud_frames,
        Some(vec![Pose3::from_xyz_rpy(1.0, 2.0, 3.0, 0.0, 0.0, 0.5); 4]),
        Some(vec![Pose3::identity(); 4]),
        Box::new(|k| {
            let mut cloud = raypath_geometry::PointCloud::from_points(
                (0..12)
                    .map(|i| nalgebra::Point3::new(i as f32, k as f32, -1.0))
                    .collect(),
            );
            cloud.intensity = Some((0..12).map(|i| 2.0 * i as f32).collect());
            cloud.width = 4;
            cloud.height = 3;
            Ok(cloud)
        }),
    )
    .unwrap();
    let file = dir.path().join("clouds.mcap");
    rosbag::write_sweeps(&file, &seq, &BagWriteOptions::default()).unwrap();
    let json = read_back(&file);
    let points = &json["topics"]["/points"];
    assert_eq!(points["schema"], "sensor_msgs/msg/PointCloud2");
    assert_eq!(points["count"], 4);
    let first = &points["first"];
    assert_eq!(
        (first["height"].clone(), first["width"].clone()),
        (3.into(), 4.into())
    );
    assert_eq!(first["point_step"], 16);
    assert_eq!(first["row_step"], 64);
    assert_eq!(first["is_bigendian"], false);
    assert_eq!(first["data"]["len"], 12 * 16);
    let names: Vec<&str> = (0..4)
        .map(|i| first["fields"]["head"][i]["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["x", "y", "z", "intensity"]);
    assert_eq!(first["fields"]["head"][3]["datatype"], 7);
    assert_eq!(json["topics"]["/tf"]["count"], 4);
    assert_eq!(json["topics"]["/reference"]["count"], 4);
}
