//! `raypath planes` and `raypath segcomp-eval` end to end: the JSON contracts on a
//! synthetic organized scan and on the real SynPEB sample, labels round trip through the
//! evaluator, and bad input (exit 2 naming file and line).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use std::path::Path;

use nalgebra::Point3;
use raypath_geometry::PointCloud;
use raypath_io::data::require;
use raypath_io::pcd::{DataEncoding, write_pcd};

mod common;
use common::{json_of, raypath};

/// A 40 × 30 organized scan of the wall x = 3 m (label 10) and the floor z = −1 m
/// (label 11), labels in `intensity`.
fn write_scene(path: &Path) {
    let (w, h) = (40, 30);
    let mut points = Vec::new();
    let mut labels = Vec::new();
    for row in 0..h {
        for col in 0..w {
            let v =
                nalgebra::Vector3::new(1.0, (col as f64 - 19.5) * 0.02, 0.05 - row as f64 * 0.02)
                    .normalize();
            let t_wall = 3.0 / v.x;
            let t_floor = if v.z < 0.0 { -1.0 / v.z } else { f64::INFINITY };
            let (t, l) = if t_wall <= t_floor {
                (t_wall, 10.0)
            } else {
                (t_floor, 11.0)
            };
            let p = v * t;
            points.push(Point3::new(p.x as f32, p.y as f32, p.z as f32));
            labels.push(l);
        }
    }
    let mut cloud = PointCloud::from_points(points);
    cloud.width = w;
    cloud.height = h;
    cloud.intensity = Some(labels);
    write_pcd(path, &cloud, DataEncoding::Binary).expect("write pcd");
}

#[test]
fn baselines_share_the_interface() {
    let dir = tempfile::tempdir().unwrap();
    let scan = dir.path().join("scene.pcd");
    write_scene(&scan);
    for method in ["peac", "msac"] {
        let labels = dir.path().join(format!("{method}.txt"));
        let out = raypath(&[
            "planes",
            scan.to_str().unwrap(),
            "--method",
            method,
            "--out",
            labels.to_str().unwrap(),
            "--json",
        ]);
        assert!(
            out.status.success(),
            "{method}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(doc["method"], method);
        let planes = doc["planes"].as_array().unwrap();
        assert!(!planes.is_empty(), "{method}: no plane");
        for key in ["label", "normal", "distance", "points", "rmse"] {
            assert!(planes[0].get(key).is_some(), "{method}: missing {key}");
        }
        assert_eq!(
            std::fs::read_to_string(&labels).unwrap().lines().count(),
            1200
        );
        if method == "peac" {
            // The block graph finds the wall (3 m) and the floor (1 m); the pixel-wise
            // refinement gives every ray to one of them, so both are correct detections.
            let d: Vec<f64> = planes
                .iter()
                .map(|p| p["distance"].as_f64().unwrap())
                .collect();
            assert_eq!(d.len(), 2, "{d:?}");
            assert!(d.iter().any(|d| (d - 3.0).abs() < 1e-3), "{d:?}");
            assert!(d.iter().any(|d| (d - 1.0).abs() < 1e-3), "{d:?}");
            let out = raypath(&[
                "segcomp-eval",
                "--truth",
                scan.to_str().unwrap(),
                "--labels",
                labels.to_str().unwrap(),
                "--json",
            ]);
            let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
            assert_eq!(doc["correct"], 2, "{doc}");
        }
    }
    let out = raypath(&["planes", scan.to_str().unwrap(), "--method", "nope"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nope"));
    // Per-noise presets are accepted.
    let out = raypath(&["planes", scan.to_str().unwrap(), "--preset", "synpeb-0.5"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn planes_json_and_labels_round_trip_through_the_evaluator() {
    let dir = tempfile::tempdir().unwrap();
    let scan = dir.path().join("scene.pcd");
    write_scene(&scan);
    let labels = dir.path().join("labels.txt");
    let doc = json_of(&raypath(&[
        "planes",
        scan.to_str().unwrap(),
        "--preset",
        "default",
        "--max-increment",
        "1e-8",
        "--out",
        labels.to_str().unwrap(),
        "--json",
    ]));
    let planes = doc["planes"].as_array().unwrap();
    assert!(planes.len() >= 2);
    for key in ["label", "normal", "distance", "points", "rmse"] {
        assert!(planes[0].get(key).is_some(), "missing {key}");
    }
    // The wall (distance 3 m, normal +x) and the floor (1 m, normal −z) are the two largest.
    let d: Vec<f64> = planes
        .iter()
        .take(2)
        .map(|p| p["distance"].as_f64().unwrap())
        .collect();
    assert!(
        d.iter().any(|d| (d - 3.0).abs() < 1e-4) && d.iter().any(|d| (d - 1.0).abs() < 1e-4),
        "{d:?}"
    );
    let text = std::fs::read_to_string(&labels).unwrap();
    assert_eq!(text.lines().count(), 1200);
    let doc = json_of(&raypath(&[
        "segcomp-eval",
        "--truth",
        scan.to_str().unwrap(),
        "--labels",
        labels.to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(doc["gt_planes"], 2);
    assert_eq!(doc["correct"], 2, "{doc}");
    assert!(doc["k"].as_f64().unwrap() == 1.0);
    for key in ["f", "k", "n_o", "n_u", "n_m", "n_s"] {
        assert!(doc.get(key).is_some(), "missing {key}");
    }
}

#[test]
fn real_synpeb_sample() {
    let Some(sample) = require("planes/synpeb-sample-100x100.pcd") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let labels = dir.path().join("labels.txt");
    let doc = json_of(&raypath(&[
        "planes",
        sample.to_str().unwrap(),
        "--out",
        labels.to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(
        (doc["width"].as_u64(), doc["height"].as_u64()),
        (Some(100), Some(100))
    );
    let out = raypath(&[
        "segcomp-eval",
        "--truth",
        sample.to_str().unwrap(),
        "--labels",
        labels.to_str().unwrap(),
        "--json",
    ]);
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    // 12 GT planes (labels ≥ 10); PPE with the synpeb preset finds at least 9 correctly.
    assert_eq!(doc["gt_planes"], 12);
    assert!(doc["correct"].as_u64().unwrap() >= 9, "{doc}");
    assert!(doc["k"].as_f64().unwrap() >= 0.9, "{doc}");
}

#[test]
fn bad_input_exits_2_with_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let scan = dir.path().join("scene.pcd");
    write_scene(&scan);
    let labels = dir.path().join("labels.txt");
    std::fs::write(&labels, "1\n2\nseven\n").unwrap();
    let out = raypath(&[
        "segcomp-eval",
        "--truth",
        scan.to_str().unwrap(),
        "--labels",
        labels.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(
        doc["error"].as_str().unwrap().contains("labels.txt:3"),
        "{doc}"
    );
    std::fs::write(&labels, "1\n2\n").unwrap();
    let out = raypath(&[
        "segcomp-eval",
        "--truth",
        scan.to_str().unwrap(),
        "--labels",
        labels.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("2 labels"));
    let out = raypath(&["planes", scan.to_str().unwrap(), "--preset", "nope"]);
    assert_eq!(out.status.code(), Some(2));
    let broken = dir.path().join("broken.pcd");
    std::fs::write(&broken, "# .PCD v0.7\nVERSION 0.7\nFIELDS x y\n").unwrap();
    let out = raypath(&["planes", broken.to_str().unwrap(), "--json"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stdout).contains("broken.pcd"));
}

/// A real Ouster OS-1-128 frame (128 × 1024, organized first returns) with the `kitti`
/// preset (tuned on KITTI, not on Ouster data): the ground, about 1.9 m below the sensor, is
/// found as horizontal planes (in many pieces: the preset's neighbour filter cuts the denser
/// Ouster ground at its ring gaps), and the labels cover every pixel.
#[test]
fn real_ouster_frame() {
    let Some(pcap) = require("ouster/OS-1-128_v2.3.0_1024x10_lb_n3.pcap") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let labels = dir.path().join("labels.txt");
    let doc = json_of(&raypath(&[
        "planes",
        pcap.to_str().unwrap(),
        "--frame-index",
        "1",
        "--preset",
        "kitti",
        "--out",
        labels.to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(
        (doc["width"].as_u64(), doc["height"].as_u64()),
        (Some(1024), Some(128))
    );
    let planes = doc["planes"].as_array().unwrap();
    let ground: u64 = planes
        .iter()
        .filter(|p| {
            let d = p["distance"].as_f64().unwrap();
            p["normal"][2].as_f64().unwrap() < -0.95 && (1.2..2.6).contains(&d)
        })
        .map(|p| p["points"].as_u64().unwrap())
        .sum();
    assert!(
        ground > 10_000,
        "{ground} ground points in {} planes",
        planes.len()
    );
    let written = std::fs::read_to_string(&labels).unwrap();
    assert_eq!(written.lines().count(), 128 * 1024);
    let out = raypath(&["planes", pcap.to_str().unwrap(), "--frame-index", "3"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("has 3 sweep(s)"));
}
