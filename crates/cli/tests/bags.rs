//! Every command that reads a log or a sequence accepts a rosbag2 bag: a synthetic CARMEN log,
//! a synthetic KITTI sequence and an organized scan, written as bags with raypath-io's writer,
//! give the answers the files themselves give (up to the `float32` ranges of LaserScan).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::Point3;
use raypath_geometry::{PointCloud, Pose2, Pose3};
use raypath_io::kitti;
use raypath_io::pcd::{DataEncoding, write_pcd};
use raypath_io::rosbag::{BagWriteOptions, write_planar, write_sweeps};
use raypath_io::sequence::{PlanarOptions, SweepFormat, SweepOptions, SweepSequence, read_planar};

mod common;
use common::{json_of, raypath};

fn s(path: &Path) -> &str {
    path.to_str().expect("UTF-8 path")
}

/// Range from `(x, y)` along `a` to the walls of [−3, 4] × [−2, 2.5] m or the pillar
/// [1, 1.5] × [0.8, 1.2] m.
fn range(x: f64, y: f64, a: f64) -> f64 {
    let (c, s) = (a.cos(), a.sin());
    let wall = |o: f64, d: f64, lo: f64, hi: f64| {
        if d > 1e-12 {
            (hi - o) / d
        } else if d < -1e-12 {
            (lo - o) / d
        } else {
            f64::INFINITY
        }
    };
    let mut t = wall(x, c, -3.0, 4.0).min(wall(y, s, -2.0, 2.5));
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for (o, d, lo, hi) in [(x, c, 1.0, 1.5), (y, s, 0.8, 1.2)] {
        if d.abs() < 1e-12 {
            if o < lo || o > hi {
                t1 = -1.0;
            }
        } else {
            let (a0, a1) = ((lo - o) / d, (hi - o) / d);
            t0 = t0.max(a0.min(a1));
            t1 = t1.min(a0.max(a1));
        }
    }
    if t1 >= t0 && t0 > 0.0 {
        t = t.min(t0);
    }
    t
}

const SCANS: usize = 40;

/// A FLASER log of 40 scans (180 beams, 1° apart from −90°) along an S-curve, the laser
/// 0.2 m ahead of the robot; the logged poses are the truth (a "corrected" log). IPC stamps
/// 100 s after the logger stamps.
fn room_log(dir: &Path) -> PathBuf {
    let mut text = String::from("# synthetic room\n");
    let robot_from_laser = Pose2::new(0.2, 0.0, 0.0);
    for k in 0..SCANS {
        let t = k as f64 * 0.05;
        let robot = Pose2::new(
            -1.7 + t,
            -0.5 + 0.3 * (t * 1.2).sin(),
            0.3 * (t * 0.8).sin(),
        );
        let laser = robot * robot_from_laser;
        let ranges: Vec<String> = (0..180)
            .map(|i| {
                let a = laser.theta() - PI / 2.0 + i as f64 * PI / 180.0;
                format!("{:.3}", range(laser.x(), laser.y(), a))
            })
            .collect();
        writeln!(
            text,
            "FLASER 180 {} {} {} {} {} {} {} {} host {}",
            ranges.join(" "),
            laser.x(),
            laser.y(),
            laser.theta(),
            robot.x(),
            robot.y(),
            robot.theta(),
            100.0 + 1.0 + k as f64 * 0.1,
            1.0 + k as f64 * 0.1
        )
        .unwrap();
    }
    let path = dir.join("room.log");
    std::fs::write(&path, text).unwrap();
    path
}

/// The log written as a bag (`.mcap` file) through the planar source.
fn log_as_bag(log: &Path, bag: &Path) {
    let frames = read_planar(log, &PlanarOptions::default()).unwrap();
    write_planar(bag, &frames, &BagWriteOptions::default()).unwrap();
}

fn close(a: &serde_json::Value, b: &serde_json::Value, tolerance: f64) -> bool {
    (a.as_f64().unwrap() - b.as_f64().unwrap()).abs() <= tolerance
}

#[test]
fn planar_commands_read_a_bag_like_the_log() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let log = room_log(d);
    let bag = d.join("room.mcap");
    log_as_bag(&log, &bag);

    // map: the same rays, hits and extent.
    let map_of = |input: &Path, prefix: &str| {
        json_of(&raypath(&[
            "map",
            s(input),
            "--model",
            "decay-rate",
            "--resolution",
            "0.1",
            "--out",
            s(&d.join(prefix)),
            "--json",
        ]))
    };
    let (from_log, from_bag) = (map_of(&log, "log"), map_of(&bag, "bag"));
    assert_eq!(from_bag["dimensions"], 2);
    for key in ["rays", "hits", "no_returns_traced", "grid"] {
        assert_eq!(from_log[key], from_bag[key], "{key}");
    }
    for corner in ["min", "max"] {
        for axis in 0..2 {
            let (a, b) = (
                &from_log["extent"][corner][axis],
                &from_bag["extent"][corner][axis],
            );
            assert!(close(a, b, 1e-6), "extent {corner} {axis}: {a} vs {b}");
        }
    }
    let observed = |j: &serde_json::Value| j["observed_cells"].as_f64().unwrap();
    assert!((observed(&from_log) - observed(&from_bag)).abs() <= 0.01 * observed(&from_log));

    // polylines: the same vertices.
    let polylines_of = |input: &Path| {
        json_of(&raypath(&[
            "polylines",
            s(input),
            "--scans",
            "0,17",
            "--json",
        ]))
    };
    let (a, b) = (polylines_of(&log), polylines_of(&bag));
    for scan in 0..2 {
        let (pa, pb) = (
            &a["scans"][scan]["polylines"],
            &b["scans"][scan]["polylines"],
        );
        assert_eq!(pa.as_array().unwrap().len(), pb.as_array().unwrap().len());
        for (la, lb) in pa.as_array().unwrap().iter().zip(pb.as_array().unwrap()) {
            assert_eq!(la.as_array().unwrap().len(), lb.as_array().unwrap().len());
            for (va, vb) in la.as_array().unwrap().iter().zip(lb.as_array().unwrap()) {
                assert!(close(&va[0], &vb[0], 1e-3) && close(&va[1], &vb[1], 1e-3));
            }
        }
    }

    // score-model: the same rows.
    let score_of = |input: &Path| {
        json_of(&raypath(&[
            "score-model",
            s(input),
            "--max-test-scans",
            "3",
            "--poses",
            "5",
            "--json",
        ]))
    };
    let (a, b) = (score_of(&log), score_of(&bag));
    assert_eq!(a["scans"], b["scans"]);
    let rows = a["rows"].as_array().unwrap();
    assert_eq!(rows.len(), b["rows"].as_array().unwrap().len());
    for (ra, rb) in rows.iter().zip(b["rows"].as_array().unwrap()) {
        assert_eq!(ra["model"], rb["model"]);
        let (x, y) = (&ra["neg_log_likelihood"], &rb["neg_log_likelihood"]);
        assert!(
            close(x, y, 1e-3 * x.as_f64().unwrap().abs().max(1.0)),
            "{x} vs {y}"
        );
    }

    // dct-map: the same patch and ray counts.
    let dct_of = |input: &Path| {
        json_of(&raypath(&[
            "dct-map",
            s(input),
            "--coefficients",
            "4,4",
            "--rays",
            "500",
            "--patch=-3,-2,7,4.5",
            "--json",
        ]))
    };
    let (a, b) = (dct_of(&log), dct_of(&bag));
    assert_eq!(a["rays"], b["rays"]);
    assert_eq!(a["held_back_rays"], b["held_back_rays"]);

    // scan-match: every scan, scored against the bag's own poses; TUM times are the
    // messages' header stamps (the log's logger stamps).
    let tum = d.join("traj.txt");
    let doc = json_of(&raypath(&[
        "scan-match",
        s(&bag),
        "--ground-truth",
        s(&bag),
        "--out",
        s(&tum),
        "--json",
    ]));
    assert_eq!(doc["scans"], SCANS);
    assert_eq!(doc["beams"], 180);
    assert_eq!(doc["errors"]["pairs"], SCANS);
    let text = std::fs::read_to_string(&tum).unwrap();
    let first: f64 = text.split_whitespace().next().unwrap().parse().unwrap();
    assert!((first - 1.0).abs() < 1e-6, "{first}");
    // A corrected copy is written for CARMEN logs only.
    let out = raypath(&[
        "scan-match",
        s(&bag),
        "--corrected-log",
        s(&d.join("c.log")),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--corrected-log"));

    // localize: the bag's scans and odometry on the log's map, the bag as ground truth: the
    // same run as on the log.
    let localize_of = |input: &Path| {
        json_of(&raypath(&[
            "localize",
            "--map",
            s(&d.join("log.rpmap")),
            "--log",
            s(input),
            "--ground-truth",
            s(input),
            "--particles",
            "200",
            "--json",
        ]))
    };
    let (a, b) = (localize_of(&log), localize_of(&bag));
    assert_eq!(b["scans"], SCANS);
    for key in ["updates", "scans", "resamplings"] {
        assert_eq!(a[key], b[key], "{key}");
    }
    assert_eq!(
        a["error"]["evaluated_points"],
        b["error"]["evaluated_points"]
    );
    for i in 0..3 {
        assert!(close(&a["final_pose"][i], &b["final_pose"][i], 1e-6));
    }
    let (x, y) = (
        &a["error"]["position_mean_m"],
        &b["error"]["position_mean_m"],
    );
    assert!(close(x, y, 1e-6), "{x} vs {y}");

    // loop-closure: the same frames as the log.
    let loops_of = |input: &Path| {
        json_of(&raypath(&[
            "loop-closure",
            s(input),
            "--method",
            "polar",
            "--exclusion-frames",
            "5",
            "--ground-truth",
            s(input),
            "--json",
        ]))
    };
    let (a, b) = (loops_of(&log), loops_of(&bag));
    assert_eq!(a["frames"], SCANS);
    assert_eq!(b["frames"], SCANS);
    assert_eq!(
        a["candidates"].as_array().unwrap().len(),
        b["candidates"].as_array().unwrap().len()
    );

    // slam: the bag maps like the log (same scans and nodes, the same trajectory up to the
    // float32 ranges), with the bag's poses as ground truth; outputs in --out.
    let slam_of = |input: &Path, out: &str| {
        json_of(&raypath(&[
            "slam",
            s(input),
            "--out",
            s(&d.join(out)),
            "--ground-truth",
            s(input),
            "--json",
        ]))
    };
    let (a, b) = (slam_of(&log, "slam-log"), slam_of(&bag, "slam-bag"));
    assert_eq!(b["scans"], SCANS);
    for key in ["scans", "nodes", "paired_scans"] {
        assert_eq!(a[key], b[key], "{key}");
    }
    let (x, y) = (
        &a["summary"]["trans_error_m"],
        &b["summary"]["trans_error_m"],
    );
    assert!(close(x, y, 1e-3), "{x} vs {y}");
    assert!(y.as_f64().unwrap() < 0.05, "{b}");
    assert!(b["wrong_loop_closures_reference_disputed"].is_u64(), "{b}");
    // The bag's own poses refined by their scans: relations kept or counted, none lost.
    let refined = &b["scan_refined"];
    let dropped: u64 = refined["dropped"]
        .as_object()
        .unwrap()
        .values()
        .map(|v| v.as_u64().unwrap())
        .sum();
    assert_eq!(
        refined["summary"]["relations"].as_u64().unwrap() + dropped,
        b["summary"]["relations"].as_u64().unwrap(),
        "{refined}"
    );
    assert!(d.join("slam-bag/trajectory.txt").exists());
    assert!(d.join("slam-bag/map.pgm").exists());

    // A topic the bag does not have is bad input naming it.
    let out = raypath(&["polylines", s(&bag), "--scan-topic", "/nope"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nope"));
}

/// A KITTI-layout sequence with an identity `Tr`: three sweeps of a ring of points (two
/// heights) every 0.5 m along x.
fn kitti_sequence(dir: &Path) -> PathBuf {
    let seq = dir.join("00");
    std::fs::create_dir_all(seq.join("velodyne")).unwrap();
    let mut poses = Vec::new();
    for k in 0..3 {
        let x = 0.5 * k as f64;
        let mut points = Vec::new();
        for i in 0..90 {
            let a = i as f64 * 4f64.to_radians();
            for z in [-0.5, 0.5] {
                let r = 6.0 + a.cos();
                points.push(Point3::new(
                    (r * a.cos() - x) as f32,
                    (r * a.sin()) as f32,
                    z as f32,
                ));
            }
        }
        let mut cloud = PointCloud::from_points(points);
        cloud.intensity = Some(vec![0.5; cloud.len()]);
        kitti::write_velodyne(&seq.join(format!("velodyne/{k:06}.bin")), &cloud).unwrap();
        poses.push(Pose3::from_xyz_rpy(x, 0.0, 0.0, 0.0, 0.0, 0.0));
    }
    kitti::write_poses(&seq.join("poses.txt"), &poses).unwrap();
    kitti::write_times(&seq.join("times.txt"), &[0.0, 0.1, 0.2]).unwrap();
    std::fs::write(seq.join("calib.txt"), "Tr: 1 0 0 0 0 1 0 0 0 0 1 0\n").unwrap();
    seq
}

#[test]
fn sweep_commands_read_a_bag_like_the_sequence() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let seq = kitti_sequence(d);
    let bag = d.join("kitti.mcap");
    let sweeps = SweepSequence::open(&seq, &SweepOptions::default()).unwrap();
    write_sweeps(&bag, &sweeps, &BagWriteOptions::default()).unwrap();

    let map_of = |input: &Path, prefix: &str| {
        json_of(&raypath(&[
            "map",
            s(input),
            "--model",
            "reflection",
            "--resolution",
            "0.5",
            "--out",
            s(&d.join(prefix)),
            "--json",
        ]))
    };
    let (a, b) = (map_of(&seq, "seq"), map_of(&bag, "bag"));
    assert_eq!(b["dimensions"], 3);
    for key in ["rays", "hits", "grid", "observed_cells"] {
        assert_eq!(a[key], b[key], "{key}");
    }
    assert_eq!(a["rays"], 3 * 180);

    let octree_of = |input: &Path| {
        json_of(&raypath(&[
            "octree",
            s(input),
            "--resolution",
            "0.25",
            "--json",
        ]))
    };
    let (a, b) = (octree_of(&seq), octree_of(&bag));
    for key in ["scans", "points", "leaves", "base_cubes", "occupied_leaves"] {
        assert_eq!(a[key], b[key], "{key}");
    }

    let loops_of = |input: &Path| {
        json_of(&raypath(&[
            "loop-closure",
            s(input),
            "--method",
            "scan-context",
            "--exclusion-frames",
            "1",
            "--json",
        ]))
    };
    let (a, b) = (loops_of(&seq), loops_of(&bag));
    assert_eq!(a["frames"], 3);
    assert_eq!(a["candidates"], b["candidates"]);
}

/// A 40 × 30 organized scan of the wall x = 3 m and the floor z = −1 m.
fn scene() -> PointCloud {
    let (w, h) = (40, 30);
    let mut points = Vec::new();
    for row in 0..h {
        for col in 0..w {
            let v =
                nalgebra::Vector3::new(1.0, (col as f64 - 19.5) * 0.02, 0.05 - row as f64 * 0.02)
                    .normalize();
            let t_wall = 3.0 / v.x;
            let t_floor = if v.z < 0.0 { -1.0 / v.z } else { f64::INFINITY };
            let p = v * t_wall.min(t_floor);
            points.push(Point3::new(p.x as f32, p.y as f32, p.z as f32));
        }
    }
    let mut cloud = PointCloud::from_points(points);
    cloud.width = w;
    cloud.height = h;
    cloud
}

#[test]
fn planes_reads_an_organized_sweep_of_a_bag() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let pcd = d.join("scene.pcd");
    write_pcd(&pcd, &scene(), DataEncoding::Binary).unwrap();
    // Sweep 0 unorganized, sweep 1 the organized scene.
    let sweeps = SweepSequence::from_fn(
        "scene",
        SweepFormat::Bag,
        vec![1.0, 1.1],
        None,
        None,
        Box::new(|i| {
            let cloud = scene();
            Ok(if i == 0 {
                PointCloud::from_points(cloud.points)
            } else {
                cloud
            })
        }),
    )
    .unwrap();
    let bag = d.join("scene-bag");
    write_sweeps(&bag, &sweeps, &BagWriteOptions::default()).unwrap();

    let from_pcd = json_of(&raypath(&["planes", s(&pcd), "--json"]));
    let from_bag = json_of(&raypath(&[
        "planes",
        s(&bag),
        "--frame-index",
        "1",
        "--json",
    ]));
    assert_eq!(from_bag["width"], 40);
    assert_eq!(from_bag["height"], 30);
    let (pa, pb) = (
        from_pcd["planes"].as_array().unwrap(),
        from_bag["planes"].as_array().unwrap(),
    );
    assert_eq!(pa.len(), 2);
    assert_eq!(pa.len(), pb.len());
    for (a, b) in pa.iter().zip(pb) {
        assert_eq!(a["points"], b["points"]);
        assert!(close(&a["distance"], &b["distance"], 1e-6));
    }

    // The unorganized sweep and a sweep the bag does not have are bad input.
    let out = raypath(&["planes", s(&bag)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not organized"));
    let out = raypath(&["planes", s(&bag), "--frame-index", "2"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--frame-index 2"));
}
