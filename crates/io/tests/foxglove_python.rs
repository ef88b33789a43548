//! A recording with every Foxglove message kind, read back by the Python `mcap` reader
//! (`tests/fixtures/check_foxglove.py`): schema names and encodings, message counts per topic,
//! and decoded values (grid size and cells, point count and coordinates, poses, colours).
//!
//! Skips with a message when `python3` or its `mcap` package is missing, unless
//! `RAYPATH_REQUIRE_PYTHON=1` (set by CI), where that is a failure.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::f64::consts::FRAC_PI_2;
use std::path::Path;
use std::process::Command;

use nalgebra::{Point2, Point3};
use raypath_geometry::{Grid2, PointCloud, Pose2, Pose3, Scan2};
use raypath_io::foxglove::{
    Cube, Cylinder, Entity, GridLayer, GridValues, Line, LineKind, Recorder, Triangles, frame,
    topic,
};
use serde_json::{Value, json};

/// `(topic, index, path, value)` checks for the Python side.
struct Expect(Vec<Value>);

impl Expect {
    fn value(&mut self, topic: &str, index: usize, path: Value, value: Value) {
        self.0
            .push(json!({ "topic": topic, "index": index, "path": path, "value": value }));
    }
}

fn scan(i: usize) -> Scan2 {
    Scan2 {
        angle_min_rad: -FRAC_PI_2,
        angle_increment_rad: FRAC_PI_2 / 90.0,
        max_range_m: 30.0,
        ranges: (0..181)
            .map(|b| {
                if b == 7 {
                    f64::INFINITY
                } else {
                    2.0 + (b + i) as f64 * 0.01
                }
            })
            .collect(),
        intensities: Some((0..181).map(|b| b as f64).collect()),
    }
}

/// Writes the recording and returns the expectations.
fn record(path: &Path) -> Value {
    let mut expect = Expect(Vec::new());
    let mut recorder = Recorder::create(path).unwrap();
    let t0 = 1_262_304_000.0;

    // Ten scans with their robot poses.
    let poses: Vec<Pose2> = (0..10)
        .map(|i| Pose2::new(0.5 * i as f64, 0.1 * i as f64, 0.05 * i as f64))
        .collect();
    for (i, pose) in poses.iter().enumerate() {
        let t = t0 + 0.1 * i as f64;
        recorder
            .transform(t, frame::MAP, frame::BASE_LINK, &pose.to_pose3())
            .unwrap();
        recorder
            .laser_scan(
                topic::SCAN,
                t,
                frame::BASE_LINK,
                &scan(i),
                &Pose3::identity(),
            )
            .unwrap();
    }
    let t_end = t0 + 0.9;
    expect.value("/tf", 3, json!(["translation", "x"]), json!(1.5));
    expect.value(
        "/tf",
        0,
        json!(["timestamp"]),
        json!({ "sec": 1_262_304_000u64, "nsec": 0 }),
    );
    expect.value("/scan", 4, json!(["ranges", 0]), json!(2.04));
    expect.value("/scan", 4, json!(["ranges", 7]), json!(0.0));
    expect.value("/scan", 4, json!(["intensities", 180]), json!(180.0));
    expect.value("/scan", 4, json!(["end_angle"]), json!(FRAC_PI_2));
    recorder
        .planar_poses(topic::TRAJECTORY, t_end, frame::MAP, &poses)
        .unwrap();
    expect.value(
        "/trajectory",
        0,
        json!(["poses", 9, "position"]),
        json!({ "x": 4.5, "y": 0.9, "z": 0.0 }),
    );
    let half_yaw = 0.45f64 / 2.0;
    expect.value(
        "/trajectory",
        0,
        json!(["poses", 9, "orientation"]),
        json!({ "x": 0.0, "y": 0.0, "z": half_yaw.sin(), "w": half_yaw.cos() }),
    );

    // A 4 × 3 occupancy map (bytes) and a probability layer (floats) on two topics.
    let grid = Grid2::new(Point2::new(-1.0, -0.5), 0.25, [4, 3]).unwrap();
    let occupancy: Vec<u8> = (0..12).map(|v| v * 20).collect();
    let layer = GridLayer::from_grid2(&grid, frame::MAP, "occupancy", GridValues::U8(&occupancy));
    recorder.grid(topic::MAP, t_end, &layer).unwrap();
    let probability: Vec<f32> = (0..12).map(|v| v as f32 / 16.0).collect();
    let layer = GridLayer::from_grid2(
        &grid,
        frame::MAP,
        "reflection",
        GridValues::F32(&probability),
    );
    recorder.grid("/map/reflection", t_end, &layer).unwrap();
    expect.value("/map", 0, json!(["column_count"]), json!(4));
    expect.value("/map", 0, json!(["_rows"]), json!(3));
    expect.value("/map", 0, json!(["_cells"]), json!(occupancy));
    expect.value(
        "/map",
        0,
        json!(["pose", "position"]),
        json!({ "x": -1.0, "y": -0.5, "z": 0.0 }),
    );
    expect.value(
        "/map",
        0,
        json!(["cell_size"]),
        json!({ "x": 0.25, "y": 0.25 }),
    );
    expect.value("/map/reflection", 0, json!(["_cells"]), json!(probability));
    expect.value(
        "/map/reflection",
        0,
        json!(["fields", 0]),
        json!({ "name": "reflection", "offset": 0, "type": 7 }),
    );

    // A 3-D cloud with a missing point, intensity and per-point colours (planes by label).
    let mut cloud = PointCloud::from_points(
        (0..100)
            .map(|i| {
                if i == 50 {
                    Point3::new(f32::NAN, f32::NAN, f32::NAN)
                } else {
                    Point3::new(i as f32 * 0.1, -(i as f32) * 0.2, 1.5)
                }
            })
            .collect(),
    );
    cloud.intensity = Some((0..100).map(|i| i as f32).collect());
    cloud.label = Some((0..100).map(|i| i / 25).collect());
    let palette = [
        [1.0, 0.0, 0.0, 1.0],
        [0.0, 1.0, 0.0, 1.0],
        [0.0, 0.0, 1.0, 1.0],
        [1.0, 1.0, 0.0, 0.5],
    ];
    let colors: Vec<[f32; 4]> = (0..100).map(|i| palette[i / 25]).collect();
    recorder
        .point_cloud(topic::POINTS, t_end, frame::MAP, &cloud, Some(&colors))
        .unwrap();
    expect.value("/points", 0, json!(["_points"]), json!(99));
    expect.value("/points", 0, json!(["point_stride"]), json!(24));
    expect.value(
        "/points",
        0,
        json!(["_xyz", 3]),
        json!([0.3f32 as f64, -0.6f32 as f64, 1.5]),
    );
    expect.value(
        "/points",
        0,
        json!(["_xyz", 50]),
        json!([5.1f32 as f64, -10.2f32 as f64, 1.5]),
    );
    expect.value("/points", 0, json!(["_label", 98]), json!(3));
    expect.value("/points", 0, json!(["_intensity", 60]), json!(61.0));
    expect.value("/points", 0, json!(["_green", 30]), json!(255));
    expect.value("/points", 0, json!(["_alpha", 90]), json!(128));

    // Features: poles, a polyline, a plane patch with its outline, octree leaves.
    let poles: Vec<Entity> = (0..5)
        .map(|i| {
            let mut e = Entity::new(format!("pole {i}"));
            e.cylinders.push(Cylinder {
                base: Point3::new(i as f64, 2.0, 0.0),
                diameter_m: 0.2,
                height_m: 3.0,
                color: [0.9, 0.3, 0.1, 1.0],
            });
            e.metadata.push(("score".into(), format!("{}", i * 10)));
            e
        })
        .collect();
    recorder
        .scene(topic::POLES, t_end, frame::MAP, &poles)
        .unwrap();
    expect.value(
        "/poles",
        0,
        json!(["entities", 4, "cylinders", 0, "pose", "position"]),
        json!({ "x": 4.0, "y": 2.0, "z": 1.5 }),
    );
    expect.value(
        "/poles",
        0,
        json!(["entities", 4, "metadata", 0, "value"]),
        json!("40"),
    );
    let mut polyline = Entity::new("polyline 0");
    polyline.lines.push(Line {
        kind: LineKind::Strip,
        points: (0..4)
            .map(|i| Point3::new(i as f64, (i * i) as f64, 0.0))
            .collect(),
        thickness_m: 0.05,
        color: [0.0, 0.0, 1.0, 1.0],
    });
    recorder
        .scene(topic::POLYLINES, t_end, frame::MAP, &[polyline])
        .unwrap();
    expect.value(
        "/polylines",
        0,
        json!(["entities", 0, "lines", 0, "points", 3, "y"]),
        json!(9.0),
    );
    let corners = [
        Point3::new(0.0, 0.0, 0.0),
        Point3::new(2.0, 0.0, 0.0),
        Point3::new(2.0, 1.0, 0.5),
        Point3::new(0.0, 1.0, 0.5),
    ];
    let mut plane = Entity::new("plane 0");
    plane.triangles.push(Triangles {
        points: vec![
            corners[0], corners[1], corners[2], corners[0], corners[2], corners[3],
        ],
        color: [0.2, 0.8, 0.2, 0.6],
    });
    plane.lines.push(Line {
        kind: LineKind::Loop,
        points: corners.to_vec(),
        thickness_m: 0.02,
        color: [0.0, 0.0, 0.0, 1.0],
    });
    recorder
        .scene(topic::PLANES, t_end, frame::MAP, &[plane])
        .unwrap();
    expect.value(
        "/planes",
        0,
        json!(["entities", 0, "triangles", 0, "points", 4, "z"]),
        json!(0.5),
    );
    expect.value(
        "/planes",
        0,
        json!(["entities", 0, "lines", 0, "type"]),
        json!(1),
    );
    let mut leaves = Entity::new("octree");
    leaves.cubes = (0..8)
        .map(|i| Cube {
            center: Point3::new(0.1 + 0.2 * f64::from(i & 1), 0.1, 0.1),
            size_m: [0.2; 3],
            color: [0.5, 0.5, 0.5, 1.0],
        })
        .collect();
    recorder
        .scene(topic::OCTREE, t_end, frame::MAP, &[leaves])
        .unwrap();
    expect.value(
        "/octree",
        0,
        json!(["entities", 0, "cubes", 7, "pose", "position", "x"]),
        json!(0.3),
    );

    let counts = recorder.finish().unwrap();
    let topics: serde_json::Map<String, Value> = counts
        .iter()
        .map(|(topic, count)| {
            let schema = match topic.as_str() {
                "/tf" => "foxglove.FrameTransform",
                "/scan" => "foxglove.LaserScan",
                "/trajectory" => "foxglove.PosesInFrame",
                "/map" | "/map/reflection" => "foxglove.Grid",
                "/points" => "foxglove.PointCloud",
                _ => "foxglove.SceneUpdate",
            };
            (topic.clone(), json!({ "schema": schema, "count": count }))
        })
        .collect();
    assert_eq!(topics.len(), 10);
    assert_eq!(counts["/scan"], 10);
    json!({ "library_prefix": "raypath-io", "topics": topics, "values": expect.0 })
}

/// Runs the checker on a fresh recording with `expectations` adjusted by `edit`: (success,
/// stdout, stderr).
fn check(edit: impl FnOnce(&mut Value)) -> (bool, String, String, Value) {
    let dir = tempfile::tempdir().unwrap();
    let recording = dir.path().join("record.mcap");
    let expected = dir.path().join("expected.json");
    let mut expectations = record(&recording);
    edit(&mut expectations);
    std::fs::write(&expected, expectations.to_string()).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/check_foxglove.py");
    let out = Command::new("python3")
        .arg(&script)
        .arg(&recording)
        .arg(&expected)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    (out.status.success(), stdout, stderr, expectations)
}

#[test]
fn python_mcap_reads_every_message_kind() {
    if !raypath_io::data::require_python("mcap") {
        return;
    }
    let (ok, stdout, stderr, expectations) = check(|_| {});
    assert!(ok, "check_foxglove.py failed:\n{stderr}\n{stdout}");
    let report: Value = serde_json::from_str(stdout.trim()).unwrap();
    assert_eq!(report["failures"], json!([]));
    assert_eq!(
        report["values_checked"],
        expectations["values"].as_array().unwrap().len()
    );
    assert_eq!(report["topics"], expectations["topics"]);
    if report["jsonschema_validation"] != json!(true) {
        eprintln!("note: python jsonschema not installed; messages were not schema-validated");
    }
}

#[test]
fn python_checker_reports_wrong_counts_and_values() {
    if !raypath_io::data::require_python("mcap") {
        return;
    }
    let (ok, _, stderr, _) = check(|e| {
        e["topics"]["/scan"]["count"] = json!(11);
        e["values"][0]["value"] = json!(1.25);
    });
    assert!(!ok, "the checker accepted wrong expectations");
    assert!(stderr.contains("topics {"), "{stderr}");
    assert!(
        stderr.contains("/tf #3 ['translation', 'x']: 1.5 != 1.25"),
        "{stderr}"
    );
}
