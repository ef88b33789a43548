//! `--record OUT.mcap` on the 3-D commands (`poles extract|map|localize`, `map` of a sequence,
//! `octree`, `planes`) end to end on data written here (a simulated KITTI drive from
//! `raypath simulate urban-kitti`, a wall of points, an organized scan of a wall and a floor):
//! each recording is read back with the `mcap` crate and checked against the command's JSON.
//! A `poles map` recording is also read by the Python `mcap` package
//! (`crates/io/tests/fixtures/check_foxglove.py`: topics, schemas, counts, values); that test
//! skips with a message when `python3` or `mcap` is missing, unless `RAYPATH_REQUIRE_PYTHON=1`.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use std::path::{Path, PathBuf};
use std::process::Command;

use nalgebra::{Point3, Vector3};
use raypath_geometry::PointCloud;
use raypath_io::pcd::{DataEncoding, write_pcd};
use serde_json::{Value, json};

mod common;
mod record_common;
use common::raypath;
use record_common::{along, cloud_points, grid_cells, record, s, xy};

/// Scans of the simulated drive.
const DRIVE_SCANS: usize = 12;

/// A simulated urban KITTI sequence of [`DRIVE_SCANS`] scans (10 Hz, from time 0) under `dir`.
fn drive(dir: &Path) -> PathBuf {
    let out = dir.join("urban");
    let run = raypath(&[
        "simulate",
        "urban-kitti",
        "--quick",
        "--scans",
        &DRIVE_SCANS.to_string(),
        "--out",
        s(&out),
        "--json",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    out.join("sequences/00")
}

/// Checks the cylinders of a `/poles` update against the command's `poles` JSON.
fn check_poles(update: &Value, poles: &[Value]) {
    let entities = update["entities"].as_array().unwrap();
    assert_eq!(entities.len(), poles.len());
    for (i, (entity, pole)) in entities.iter().zip(poles).enumerate() {
        assert_eq!(entity["id"], format!("pole {i}"));
        assert_eq!(entity["frame_id"], "map");
        let cylinder = &entity["cylinders"][0];
        let (x, y) = xy(&cylinder["pose"]["position"]);
        assert!((x - pole["x"].as_f64().unwrap()).abs() < 1e-9);
        assert!((y - pole["y"].as_f64().unwrap()).abs() < 1e-9);
        let width = pole["width"].as_f64().unwrap();
        assert!((cylinder["size"]["x"].as_f64().unwrap() - width).abs() < 1e-9);
        let height = pole["height"].as_f64().unwrap();
        assert!((cylinder["size"]["z"].as_f64().unwrap() - height).abs() < 1e-9);
    }
}

#[test]
fn poles_extract_map_and_localize_record_poles_and_trajectories() {
    let dir = tempfile::tempdir().unwrap();
    let seq = drive(dir.path());
    let csv = dir.path().join("poles.csv");

    let args = ["poles", "map", s(&seq), "--out", s(&csv)];
    let (doc, rec) = record(&args, dir.path().join("map.mcap"));
    let poles = doc["poles"].as_array().unwrap();
    assert!(!poles.is_empty(), "{doc}");
    rec.expect_topics(&doc, &along("/points", DRIVE_SCANS, "/poles"));
    check_poles(rec.first("/poles"), poles);
    // Each sweep in base_link, thinned to at most MAX_SWEEP_POINTS, with its intensities.
    for (_, sweep) in &rec["/points"].messages {
        assert_eq!(sweep["frame_id"], "base_link");
        let points = cloud_points(sweep);
        assert!(
            !points.is_empty() && points.len() <= 10_000,
            "{}",
            points.len()
        );
        assert!(points[0].contains_key("intensity"));
    }
    // KITTI times: 0.1 s apart from 0; the results at the last scan's time.
    let times: Vec<u64> = rec["/tf"].messages.iter().map(|(t, _)| *t).collect();
    assert_eq!(times[0], 0);
    assert!(times[DRIVE_SCANS - 1].abs_diff(1_100_000_000) < 1000);
    assert_eq!(rec["/poles"].messages[0].0, times[DRIVE_SCANS - 1]);

    let (doc, rec) = record(
        &["poles", "extract", s(&seq)],
        dir.path().join("extract.mcap"),
    );
    let scans = doc["scans"].as_u64().unwrap() as usize;
    rec.expect_topics(&doc, &along("/points", scans, "/poles"));
    check_poles(rec.first("/poles"), doc["poles"].as_array().unwrap());

    let args = [
        "poles",
        "localize",
        "--map",
        s(&csv),
        s(&seq),
        "--runs",
        "2",
    ];
    let (doc, rec) = record(&args, dir.path().join("localize.mcap"));
    assert!(!doc["summary"].is_null(), "{doc}");
    let estimates = rec["/tf"].messages.len();
    assert!(estimates >= 2);
    let mut topics = along("/points", estimates, "/poles");
    topics.push(("/ground_truth", 1));
    rec.expect_topics(&doc, &topics);
    // The map from the start; the first run's estimates; the ground truth of every scan.
    assert_eq!(rec["/poles"].messages[0].0, 0);
    assert_eq!(
        rec.first("/poles")["entities"].as_array().unwrap().len(),
        poles.len()
    );
    let trajectory = rec.first("/trajectory")["poses"].as_array().unwrap();
    assert_eq!(trajectory.len(), estimates);
    let truth = rec.first("/ground_truth")["poses"].as_array().unwrap();
    assert_eq!(truth.len(), DRIVE_SCANS);
}

#[test]
fn a_3d_map_records_sweep_poses_and_occupied_voxels() {
    let dir = tempfile::tempdir().unwrap();
    let seq = drive(dir.path());
    let out = dir.path().join("map3d");
    let args = [
        "map",
        s(&seq),
        "--model",
        "log-odds",
        "--resolution",
        "0.5",
        "--max-range",
        "30",
        "--ray-step",
        "8",
        "--out",
        s(&out),
    ];
    let (doc, rec) = record(&args, dir.path().join("map3d.mcap"));
    let mut topics = along("/points", DRIVE_SCANS, "/map");
    topics.push(("/map_points", 1));
    rec.expect_topics(&doc, &topics);
    // The column-sum picture over the map's x-y cells.
    let (columns, rows, cells) = grid_cells(rec.first("/map"));
    assert_eq!(
        json!([columns, rows]),
        json!([doc["grid"][0], doc["grid"][1]])
    );
    assert!(cells.iter().any(|v| !v.is_nan()));
    // Occupied voxel centres inside the map, occupancy above one half.
    let points = cloud_points(rec.first("/map_points"));
    assert!(!points.is_empty());
    let (min, max) = (&doc["extent"]["min"], &doc["extent"]["max"]);
    for p in &points {
        for (a, axis) in ["x", "y", "z"].into_iter().enumerate() {
            let v = p[axis];
            assert!(v >= min[a].as_f64().unwrap() && v <= max[a].as_f64().unwrap());
        }
        assert!(p["intensity"] > 0.5 && p["intensity"] <= 1.0);
    }
}

#[test]
fn octree_records_occupied_leaves_as_points_and_cubes() {
    let dir = tempfile::tempdir().unwrap();
    // A wall x = 3 m, y in [−2, 2], z in [−1, 1], seen from the origin.
    let mut text = String::new();
    for i in 0..=80 {
        for k in 0..=40 {
            let (y, z) = (-2.0 + 0.05 * i as f64, -1.0 + 0.05 * k as f64);
            text.push_str(&format!("3.0 {y:.3} {z:.3}\n"));
        }
    }
    let points = dir.path().join("wall.xyz");
    std::fs::write(&points, text).unwrap();
    let args = ["octree", s(&points), "--resolution", "0.2"];
    let (doc, rec) = record(&args, dir.path().join("octree.mcap"));
    let occupied = doc["occupied_leaves"].as_u64().unwrap() as usize;
    assert!(occupied > 0);
    let topics = ["/tf", "/trajectory", "/map_points", "/octree"];
    rec.expect_topics(&doc, &topics.map(|t| (t, 1)));
    let centres = cloud_points(rec.first("/map_points"));
    assert_eq!(centres.len(), occupied);
    let cubes = rec.first("/octree")["entities"][0]["cubes"]
        .as_array()
        .unwrap()
        .clone();
    assert_eq!(cubes.len(), occupied);
    for cube in &cubes {
        let (x, _) = xy(&cube["pose"]["position"]);
        let size = cube["size"]["x"].as_f64().unwrap();
        // Leaves are whole base cubes holding the wall.
        assert!((size / 0.2 - (size / 0.2).round()).abs() < 1e-9 && size > 0.0);
        assert!((x - 3.0).abs() <= size / 2.0 + 1e-9, "{cube}");
    }
}

/// A 40 × 30 organized scan of the wall x = 3 m and the floor z = −1 m.
fn write_scene(path: &Path) {
    let (w, h) = (40, 30);
    let mut points = Vec::new();
    for row in 0..h {
        for col in 0..w {
            let v =
                Vector3::new(1.0, (col as f64 - 19.5) * 0.02, 0.05 - row as f64 * 0.02).normalize();
            let t_wall = 3.0 / v.x;
            let t_floor = if v.z < 0.0 { -1.0 / v.z } else { f64::INFINITY };
            let p = v * t_wall.min(t_floor);
            points.push(Point3::new(p.x as f32, p.y as f32, p.z as f32));
        }
    }
    let mut cloud = PointCloud::from_points(points);
    cloud.width = w;
    cloud.height = h;
    write_pcd(path, &cloud, DataEncoding::Binary).unwrap();
}

#[test]
fn planes_records_the_labelled_cloud_and_the_plane_outlines() {
    let dir = tempfile::tempdir().unwrap();
    let scan = dir.path().join("scene.pcd");
    write_scene(&scan);
    let (doc, rec) = record(&["planes", s(&scan)], dir.path().join("planes.mcap"));
    let planes = doc["planes"].as_array().unwrap();
    assert_eq!(planes.len(), 2, "{doc}");
    rec.expect_topics(&doc, &[("/tf", 1), ("/points", 1), ("/planes", 1)]);
    // Every point, labelled as the planes count them; one colour per label.
    let points = cloud_points(rec.first("/points"));
    assert_eq!(points.len(), 40 * 30);
    for plane in planes {
        let label = plane["label"].as_f64().unwrap();
        let members: Vec<_> = points.iter().filter(|p| p["label"] == label).collect();
        assert_eq!(members.len() as u64, plane["points"].as_u64().unwrap());
        let rgb = |p: &std::collections::BTreeMap<String, f64>| [p["red"], p["green"], p["blue"]];
        assert!(members.iter().all(|p| rgb(p) == rgb(members[0])));
    }
    // Each outline lies on its fitted plane (n · p = distance).
    let entities = rec.first("/planes")["entities"].as_array().unwrap();
    assert_eq!(entities.len(), 2);
    for (entity, plane) in entities.iter().zip(planes) {
        assert_eq!(entity["id"], format!("plane {}", plane["label"]));
        let n: Vec<f64> = plane["normal"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let d = plane["distance"].as_f64().unwrap();
        let outline = entity["lines"][0]["points"].as_array().unwrap();
        assert!(outline.len() >= 3);
        for p in outline {
            let v = [&p["x"], &p["y"], &p["z"]].map(|c| c.as_f64().unwrap());
            let along = n[0] * v[0] + n[1] * v[1] + n[2] * v[2];
            assert!((along - d).abs() < 1e-6, "{along} vs {d}");
        }
        let fill = entity["triangles"][0]["points"].as_array().unwrap();
        assert_eq!(fill.len(), 3 * (outline.len() - 2));
    }
}

#[test]
fn a_poles_map_recording_opens_in_the_python_mcap_reader() {
    if !raypath_io::data::require_python("mcap") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let seq = drive(dir.path());
    let csv = dir.path().join("poles.csv");
    let args = ["poles", "map", s(&seq), "--out", s(&csv)];
    let (doc, rec) = record(&args, dir.path().join("poles.mcap"));
    let poles = doc["poles"].as_array().unwrap();
    assert!(!poles.is_empty());
    let pole = &poles[0];
    let expected = json!({
        "library_prefix": "raypath-io",
        "topics": {
            "/tf": {"schema": "foxglove.FrameTransform", "count": DRIVE_SCANS},
            "/points": {"schema": "foxglove.PointCloud", "count": DRIVE_SCANS},
            "/trajectory": {"schema": "foxglove.PosesInFrame", "count": 1},
            "/poles": {"schema": "foxglove.SceneUpdate", "count": 1},
        },
        "values": [
            {"topic": "/tf", "index": 0, "path": ["child_frame_id"], "value": "base_link"},
            {"topic": "/tf", "index": 0, "path": ["parent_frame_id"], "value": "map"},
            {"topic": "/trajectory", "index": 0, "path": ["frame_id"], "value": "map"},
            {"topic": "/points", "index": 0, "path": ["frame_id"], "value": "base_link"},
            {"topic": "/poles", "index": 0, "path": ["entities", 0, "id"], "value": "pole 0"},
            {"topic": "/poles", "index": 0,
             "path": ["entities", 0, "cylinders", 0, "pose", "position", "x"], "value": pole["x"]},
            {"topic": "/poles", "index": 0,
             "path": ["entities", 0, "cylinders", 0, "pose", "position", "y"], "value": pole["y"]},
            {"topic": "/poles", "index": 0,
             "path": ["entities", 0, "cylinders", 0, "size", "x"], "value": pole["width"]},
            {"topic": "/poles", "index": 0,
             "path": ["entities", poles.len() - 1, "id"],
             "value": format!("pole {}", poles.len() - 1)},
        ],
    });
    let expected_path = dir.path().join("expected.json");
    std::fs::write(&expected_path, expected.to_string()).unwrap();
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../io/tests/fixtures/check_foxglove.py"
    );
    let out = Command::new("python3")
        .args([script, s(&rec.path), s(&expected_path)])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "check_foxglove.py failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["failures"], json!([]));
    assert_eq!(report["values_checked"], 9);
    assert_eq!(report["topics"], expected["topics"]);
}
