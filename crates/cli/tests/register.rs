//! `raypath register` end to end: two synthetic scans with a known motion, a real KITTI
//! sequence against its poses (skipped without RAYPATH_DATA), and bad input.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

mod common;
use std::fmt::Write;

use common::{json_of, raypath};
use nalgebra::Point3;
use raypath_geometry::Pose3;

/// A 30 m × 16 m × 5 m hall with two pillars, sampled every 0.2 m, seen from
/// `world_from_sensor`, as `x y z` lines.
fn hall(world_from_sensor: &Pose3) -> String {
    let mut points = Vec::new();
    let steps = |len: f64| (0..(len / 0.2) as usize).map(|i| i as f64 * 0.2);
    for a in steps(30.0) {
        for b in steps(16.0) {
            points.push(Point3::new(a - 15.0, b - 8.0, -1.5)); // floor
        }
        for c in steps(5.0) {
            points.push(Point3::new(a - 15.0, -8.0, c - 1.5)); // side walls
            points.push(Point3::new(a - 15.0, 8.0, c - 1.5));
        }
    }
    for b in steps(16.0) {
        for c in steps(5.0) {
            points.push(Point3::new(15.0, b - 8.0, c - 1.5)); // end walls
            points.push(Point3::new(-15.0, b - 8.0, c - 1.5));
        }
    }
    for (x, y) in [(4.0, 3.0), (-6.0, -2.0)] {
        for a in steps(2.0) {
            for c in steps(5.0) {
                // Square pillars, 2 m wide.
                points.push(Point3::new(x + a, y, c - 1.5));
                points.push(Point3::new(x + a, y + 2.0, c - 1.5));
                points.push(Point3::new(x, y + a, c - 1.5));
                points.push(Point3::new(x + 2.0, y + a, c - 1.5));
            }
        }
    }
    let sensor_from_world = world_from_sensor.inverse();
    let mut text = String::new();
    for p in points {
        let q = sensor_from_world.transform_point(&p);
        writeln!(text, "{:.4} {:.4} {:.4}", q.x, q.y, q.z).unwrap();
    }
    text
}

#[test]
fn two_scans_known_motion_and_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let truth = Pose3::from_xyz_rpy(0.7, -0.2, 0.0, 0.0, 0.0, 2f64.to_radians());
    let (source, target) = (dir.path().join("source.xyz"), dir.path().join("target.xyz"));
    std::fs::write(&source, hall(&truth)).unwrap();
    std::fs::write(&target, hall(&Pose3::identity())).unwrap();
    let doc = json_of(&raypath(&[
        "register",
        source.to_str().unwrap(),
        target.to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(doc["mode"], "pair");
    let t: Vec<f64> = doc["target_from_source"]["translation_m"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let yaw = doc["target_from_source"]["rpy_deg"][2].as_f64().unwrap();
    assert!(
        (t[0] - 0.7).abs() < 0.01 && (t[1] + 0.2).abs() < 0.01 && t[2].abs() < 0.01,
        "{doc}"
    );
    assert!((yaw - 2.0).abs() < 0.02, "{doc}");
    assert_eq!(doc["converged"], true);
    for key in [
        "iterations",
        "fitness",
        "rmse_m",
        "correspondences",
        "source_points",
        "seconds",
    ] {
        assert!(doc.get(key).is_some(), "missing {key}: {doc}");
    }

    // Bad input: exit code 2 and {"error": …} naming the file.
    let missing = dir.path().join("missing.xyz");
    let out = raypath(&[
        "register",
        missing.to_str().unwrap(),
        target.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(
        doc["error"].as_str().unwrap().contains("missing.xyz"),
        "{doc}"
    );
    // A scan alone, an unknown kernel, an invalid voxel size.
    for args in [
        vec!["register", target.to_str().unwrap()],
        vec![
            "register",
            source.to_str().unwrap(),
            target.to_str().unwrap(),
            "--kernel",
            "x",
        ],
        vec![
            "register",
            source.to_str().unwrap(),
            target.to_str().unwrap(),
            "--voxel-size",
            "0",
        ],
    ] {
        assert_eq!(raypath(&args).status.code(), Some(2), "{args:?}");
    }
    // Scans that do not overlap: the hall seen from 60 m behind it.
    let far = dir.path().join("far.xyz");
    std::fs::write(
        &far,
        hall(&Pose3::from_xyz_rpy(-60.0, 0.0, 0.0, 0.0, 0.0, 0.0)),
    )
    .unwrap();
    let out = raypath(&["register", far.to_str().unwrap(), target.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn kitti_sequence_against_its_poses() {
    let Some(seq) = raypath_io::data::require("kitti/sequences/00") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let poses = dir.path().join("poses.txt");
    let doc = json_of(&raypath(&[
        "register",
        seq.to_str().unwrap(),
        "--frames",
        "4",
        "--out",
        poses.to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(doc["mode"], "sequence");
    assert_eq!(doc["frames"], 4);
    let steps = doc["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 4);
    assert!(steps[0]["error"].is_null() && steps[0]["iterations"].is_null());
    let s = &doc["summary"];
    assert_eq!(s["pairs"], 3);
    // SuMa's poses: the 0.7 m steps agree to centimetres and a tenth of a degree.
    assert!(s["translation_error_m_max"].as_f64().unwrap() < 0.06, "{s}");
    assert!(s["rotation_error_deg_max"].as_f64().unwrap() < 0.15, "{s}");
    let written = raypath_io::kitti::read_poses(&poses).unwrap();
    assert_eq!(written.len(), 4);
    assert!(
        (written[1].translation().x - 0.7).abs() < 0.05,
        "{:?}",
        written[1]
    );
}
