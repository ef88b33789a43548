//! `raypath convert` on the real benchmark data: a corrected CARMEN log becomes a rosbag2 bag
//! that maps like the log, and comes back as a CARMEN log; a KITTI sequence becomes a bag and
//! comes back with the same scans; `raypath info` lists the bag's topics.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use std::path::Path;

mod common;
use common::{json_of, raypath};

fn s(path: &Path) -> &str {
    path.to_str().expect("UTF-8 path")
}

/// The map of the bag equals the map of the log it was converted from: the PGM byte for byte
/// and every count; the cell statistics may differ in the last bits (headings pass through
/// quaternions).
#[test]
fn converted_intel_log_maps_like_the_log() {
    let Some(log) = raypath_io::data::require("carmen/corrected/intel-corrected.log.gz") else {
        return;
    };
    let dir = tempfile::tempdir().expect("temp dir");
    let bag = dir.path().join("intel.mcap");
    let report = json_of(&raypath(&["convert", s(&log), s(&bag), "--json"]));
    assert_eq!(report["from"], "carmen");
    assert_eq!(report["to"], "rosbag2");
    assert_eq!(report["frames"], 910);

    let info = json_of(&raypath(&["info", s(&bag), "--json"]));
    assert_eq!(info["format"], "rosbag2");
    assert_eq!(info["scans"], 910);
    assert_eq!(info["odometry"], 910);
    assert_eq!(info["profile"], "ros2");
    let topics: Vec<&str> = info["topics"]
        .as_array()
        .expect("topics")
        .iter()
        .map(|t| t["name"].as_str().expect("name"))
        .collect();
    assert!(
        topics.contains(&"/scan") && topics.contains(&"/odom"),
        "{topics:?}"
    );

    let map = |input: &Path, out: &Path| {
        json_of(&raypath(&[
            "map",
            s(input),
            "--model",
            "decay-rate",
            "--resolution",
            "0.1",
            "--out",
            s(out),
            "--json",
        ]))
    };
    let from_log = map(&log, &dir.path().join("log"));
    let from_bag = map(&bag, &dir.path().join("bag"));
    for key in [
        "cells",
        "grid",
        "rays",
        "hits",
        "crossings",
        "observed_cells",
        "no_returns_traced",
    ] {
        assert_eq!(from_log[key], from_bag[key], "{key}");
    }
    let pgm = |name: &str| std::fs::read(dir.path().join(name)).expect("pgm");
    assert!(pgm("log.pgm") == pgm("bag.pgm"), "the PGM maps differ");

    // And back to CARMEN: the same scans and poses.
    let back = dir.path().join("back.log");
    json_of(&raypath(&["convert", s(&bag), s(&back), "--json"]));
    let read =
        |p: &Path| raypath_io::sequence::read_planar(p, &Default::default()).expect("frames");
    let (original, returned) = (read(&log), read(&back));
    assert_eq!(original.len(), returned.len());
    for (a, b) in original.iter().zip(&returned) {
        assert_eq!(a.scan.ranges, b.scan.ranges);
        assert_eq!(a.scan.angle_min_rad, b.scan.angle_min_rad);
        assert_eq!(a.scan.angle_increment_rad, b.scan.angle_increment_rad);
        let d = a.world_from_laser.inverse() * b.world_from_laser;
        assert!(d.translation().norm() < 1e-12 && d.theta().abs() < 1e-12);
    }
}

#[test]
fn kitti_sequence_round_trips_through_a_bag() {
    let Some(seq) = raypath_io::data::require("kitti/sequences/00") else {
        return;
    };
    let dir = tempfile::tempdir().expect("temp dir");
    let bag = dir.path().join("00.mcap");
    let report = json_of(&raypath(&["convert", s(&seq), s(&bag), "--json"]));
    assert_eq!(report["from"], "kitti");
    let frames = report["frames"].as_u64().expect("frames");
    assert_eq!(report["reference_poses"].as_u64(), Some(frames));
    let back = dir.path().join("back");
    let report = json_of(&raypath(&["convert", s(&bag), s(&back), "--json"]));
    assert_eq!(report["to"], "kitti");
    let mut names: Vec<_> = std::fs::read_dir(seq.join("velodyne"))
        .expect("velodyne")
        .map(|e| e.expect("entry").file_name())
        .collect();
    names.sort();
    assert_eq!(names.len() as u64, frames);
    for (i, name) in names.iter().enumerate() {
        let original = std::fs::read(seq.join("velodyne").join(name)).expect("scan");
        let returned =
            std::fs::read(back.join("velodyne").join(format!("{i:06}.bin"))).expect("scan");
        assert!(original == returned, "scan {i} differs");
    }
    // One sweep to PCD and a bad target.
    let pcd_dir = dir.path().join("pcds");
    json_of(&raypath(&[
        "convert",
        s(&bag),
        s(&pcd_dir),
        "--to",
        "pcd",
        "--json",
    ]));
    assert_eq!(
        std::fs::read_dir(&pcd_dir).expect("pcds").count() as u64,
        frames
    );
    let out = raypath(&["convert", s(&bag), s(&dir.path().join("x.log"))]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("CARMEN"));
}

/// An Ouster capture with vendor poses becomes a KITTI sequence: one scan per frame with
/// every valid return (no NaN no-returns), the poses and the frame times.
#[test]
fn ouster_capture_converts_to_kitti() {
    let Some(pcap) = raypath_io::data::require("ouster/OS-1-128_v2.3.0_1024x10_lb_n3.pcap") else {
        return;
    };
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("kitti");
    let report = json_of(&raypath(&["convert", s(&pcap), s(&out), "--json"]));
    assert_eq!(report["from"], "ouster-pcap");
    assert_eq!(report["frames"], 3);
    assert_eq!(report["reference_poses"], 3);
    let sequence = raypath_io::sequence::SweepSequence::open(
        &pcap,
        &raypath_io::sequence::SweepOptions::default(),
    )
    .expect("capture");
    let info = json_of(&raypath(&["info", s(&out), "--json"]));
    let valid: usize = (0..3)
        .map(|k| sequence.sweep(k).expect("sweep").num_valid())
        .sum();
    assert_eq!(info["points"].as_u64(), Some(valid as u64));
    assert_eq!(info["poses"], 3);
}
