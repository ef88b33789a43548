//! `raypath poles` end to end on a small synthetic KITTI-layout drive past six poles: the
//! poles are extracted at their centres, the map round-trips through CSV, localization on it
//! converges (JSON `summary` contract), and bad input exits with 2 naming file and place.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use std::path::{Path, PathBuf};

use nalgebra::{Matrix3x4, Point3, Vector3};
use raypath_geometry::{PointCloud, Pose3};
use raypath_io::kitti;

mod common;
use common::{json_of, raypath};

/// Poles (x, y, radius) beside a straight street along x.
const POLES: [(f64, f64, f64); 6] = [
    (2.0, 5.0, 0.12),
    (6.0, -5.0, 0.1),
    (11.0, 5.5, 0.15),
    (15.0, -5.0, 0.1),
    (20.0, 5.0, 0.2),
    (24.0, -5.5, 0.12),
];
const HEIGHT: f64 = 1.73;

/// Points of a scan from `sensor` (world frame) in the sensor frame (identity rotation).
fn scan(sensor: &Point3<f64>) -> PointCloud {
    let mut points = Vec::new();
    for e in 0..40 {
        let elevation = (-24.0 + e as f64 * 0.8f64).to_radians();
        for k in 0..1200 {
            let azimuth = (k as f64 * 0.3).to_radians();
            let d = Vector3::new(
                elevation.cos() * azimuth.cos(),
                elevation.cos() * azimuth.sin(),
                elevation.sin(),
            );
            let mut t = 60.0f64;
            if d.z < 0.0 {
                t = t.min(-sensor.z / d.z);
            }
            for (cx, cy, r) in POLES {
                let (ox, oy) = (sensor.x - cx, sensor.y - cy);
                let a = d.x * d.x + d.y * d.y;
                let b = 2.0 * (ox * d.x + oy * d.y);
                let c = ox * ox + oy * oy - r * r;
                let disc = b * b - 4.0 * a * c;
                if a > 0.0 && disc >= 0.0 {
                    let tc = (-b - disc.sqrt()) / (2.0 * a);
                    if tc > 0.0 && sensor.z + tc * d.z < 5.0 {
                        t = t.min(tc);
                    }
                }
            }
            if t < 60.0 {
                let p = t * d;
                points.push(Point3::new(p.x as f32, p.y as f32, p.z as f32));
            }
        }
    }
    PointCloud::from_points(points)
}

/// Writes the drive (scans every 0.5 m along x from x = 0, 10 Hz) in the KITTI layout.
fn write_drive(dir: &Path, scans: usize) -> PathBuf {
    let seq = dir.join("00");
    std::fs::create_dir_all(seq.join("velodyne")).unwrap();
    // Camera axes: cam0_from_velo maps (x fwd, y left, z up) to (x right, y down, z fwd).
    let cam0_from_velo = Pose3::from_matrix3x4(&Matrix3x4::new(
        0.0, -1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0,
    ));
    let mut world_from_velo = Vec::new();
    for i in 0..scans {
        let sensor = Point3::new(0.5 * i as f64, 0.0, HEIGHT);
        world_from_velo.push(Pose3::from_xyz_rpy(sensor.x, 0.0, HEIGHT, 0.0, 0.0, 0.0));
        kitti::write_velodyne(&seq.join(format!("velodyne/{i:06}.bin")), &scan(&sensor)).unwrap();
    }
    let cam = kitti::cam0_poses_from_velodyne(&world_from_velo, &cam0_from_velo);
    kitti::write_poses(&seq.join("poses.txt"), &cam).unwrap();
    let times: Vec<f64> = (0..scans).map(|i| 0.1 * i as f64).collect();
    kitti::write_times(&seq.join("times.txt"), &times).unwrap();
    let p = "7.0 0 6.0 0 0 7.0 1.8 0 0 0 1 0";
    std::fs::write(
        seq.join("calib.txt"),
        format!("P0: {p}\nP1: {p}\nP2: {p}\nP3: {p}\nTr: 0 -1 0 0 0 0 -1 0 1 0 0 0\n"),
    )
    .unwrap();
    seq
}

fn nearest(poles: &[serde_json::Value], x: f64, y: f64) -> f64 {
    poles
        .iter()
        .map(|p| {
            let (px, py) = (p["x"].as_f64().unwrap(), p["y"].as_f64().unwrap());
            ((px - x).powi(2) + (py - y).powi(2)).sqrt()
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn extract_map_and_localize() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = write_drive(tmp.path(), 48);
    let seq_arg = seq.to_str().unwrap();

    // One local map (the first 5 m): the poles within its 30 m × 30 m grid are found.
    let out = json_of(&raypath(&["poles", "extract", seq_arg, "--json"]));
    assert_eq!(out["preset"], "kitti");
    let poles = out["poles"].as_array().unwrap();
    for (x, y, _) in POLES.iter().filter(|p| p.0 < 14.0) {
        let d = nearest(poles, *x, *y);
        assert!(d < 0.15, "pole ({x}, {y}) found {d} m off: {poles:?}");
    }

    // The map of the whole drive holds all six poles.
    let map = tmp.path().join("map.csv");
    let out = json_of(&raypath(&[
        "poles",
        "map",
        seq_arg,
        "--out",
        map.to_str().unwrap(),
        "--json",
    ]));
    let poles = out["poles"].as_array().unwrap();
    assert_eq!(poles.len(), POLES.len(), "{poles:?}");
    for (x, y, _) in POLES {
        assert!(nearest(poles, x, y) < 0.15);
    }
    let csv = std::fs::read_to_string(&map).unwrap();
    assert!(csv.starts_with("x,y,width,height,score\n"));
    assert_eq!(csv.lines().count(), POLES.len() + 1);

    // Localization on the map converges from the 3 m / ±5° spread.
    let out = json_of(&raypath(&[
        "poles",
        "localize",
        "--map",
        map.to_str().unwrap(),
        seq_arg,
        "--runs",
        "2",
        "--particles",
        "1000",
        "--json",
    ]));
    let summary = &out["summary"];
    for key in [
        "mean_pos_m",
        "rmse_pos_m",
        "mean_lat_m",
        "mean_lon_m",
        "mean_ang_deg",
        "rmse_ang_deg",
        "diverged_runs",
    ] {
        assert!(!summary[key].is_null(), "summary lacks {key}: {summary}");
    }
    assert_eq!(summary["diverged_runs"], 0);
    assert!(summary["mean_pos_m"].as_f64().unwrap() < 1.0, "{summary}");
}

#[test]
fn a_bag_gives_the_poles_of_its_sequence() {
    use raypath_io::rosbag::{BagWriteOptions, write_sweeps};
    use raypath_io::sequence::{SweepOptions, SweepSequence};

    let tmp = tempfile::tempdir().unwrap();
    let seq = write_drive(tmp.path(), 12);
    let bag = tmp.path().join("drive.mcap");
    let sweeps = SweepSequence::open(&seq, &SweepOptions::default()).unwrap();
    write_sweeps(&bag, &sweeps, &BagWriteOptions::default()).unwrap();
    let from_seq = json_of(&raypath(&[
        "poles",
        "extract",
        seq.to_str().unwrap(),
        "--json",
    ]));
    let from_bag = json_of(&raypath(&[
        "poles",
        "extract",
        bag.to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(from_bag["preset"], "kitti");
    assert_eq!(from_seq["scans"], from_bag["scans"]);
    let (a, b) = (
        from_seq["poles"].as_array().unwrap(),
        from_bag["poles"].as_array().unwrap(),
    );
    assert!(!a.is_empty());
    assert_eq!(a.len(), b.len());
    for (p, q) in a.iter().zip(b) {
        for key in ["x", "y", "width"] {
            let (u, v) = (p[key].as_f64().unwrap(), q[key].as_f64().unwrap());
            assert!((u - v).abs() < 1e-6, "{key}: {u} vs {v}");
        }
    }
    // A topic the bag does not have is bad input naming it.
    let out = raypath(&[
        "poles",
        "extract",
        bag.to_str().unwrap(),
        "--cloud-topic",
        "/nope",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nope"));
}

#[test]
fn a_kitti_root_with_one_sequence_is_that_sequence() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = write_drive(&tmp.path().join("sequences"), 12);
    let by_root = json_of(&raypath(&[
        "poles",
        "extract",
        tmp.path().to_str().unwrap(),
        "--json",
    ]));
    let by_seq = json_of(&raypath(&[
        "poles",
        "extract",
        seq.to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(by_root["poles"], by_seq["poles"]);
    assert!(!by_root["poles"].as_array().unwrap().is_empty());
    // Two sequences: the user must name one.
    write_drive(&tmp.path().join("sequences/01"), 2);
    std::fs::rename(
        tmp.path().join("sequences/01/00"),
        tmp.path().join("sequences/02"),
    )
    .unwrap();
    let out = raypath(&["poles", "extract", tmp.path().to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("name one"));
}

#[test]
fn bad_input_exits_2_with_file_and_place() {
    let tmp = tempfile::tempdir().unwrap();
    let out = raypath(&[
        "poles",
        "extract",
        tmp.path().join("nothing").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));

    let seq = write_drive(tmp.path(), 3);
    let map = tmp.path().join("bad.csv");
    std::fs::write(&map, "x,y\n1.0,oops\n").unwrap();
    let out = raypath(&[
        "poles",
        "localize",
        "--map",
        map.to_str().unwrap(),
        seq.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("bad.csv:2"), "{stderr}");

    let out = raypath(&[
        "poles",
        "extract",
        seq.to_str().unwrap(),
        "--preset",
        "mars",
    ]);
    assert_eq!(out.status.code(), Some(2));
}

/// Real KITTI 00 (10 frames): `auto` traces rays from each firing's position, the
/// SemanticKITTI pole at (4.5, −3.4) m is found either way, and `origin` is honoured.
#[test]
fn real_kitti_uses_the_sweep_timing() {
    let Some(seq) = raypath_io::data::require("kitti/sequences/00") else {
        return;
    };
    let seq = seq.to_str().unwrap();
    let auto = json_of(&raypath(&["poles", "extract", seq, "--json"]));
    assert_eq!(auto["sweep_timing"], "kitti");
    let origin = json_of(&raypath(&[
        "poles",
        "extract",
        seq,
        "--sweep-timing",
        "origin",
        "--json",
    ]));
    assert_eq!(origin["sweep_timing"], "origin");
    for out in [&auto, &origin] {
        let poles = out["poles"].as_array().unwrap();
        assert!(nearest(poles, 4.46, -3.42) < 0.3, "{poles:?}");
    }
}
