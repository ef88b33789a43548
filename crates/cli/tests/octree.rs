//! `raypath octree` end to end: the JSON contract on a synthetic scan graph, fusion shrinking
//! the leaves, `.bt` and `.ply` output, the real `scan.dat`, and bad input (exit 2 with the
//! file and the place).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use std::path::{Path, PathBuf};

use nalgebra::Point3;
use raypath_geometry::{PointCloud, Pose3};
use raypath_io::data::require;
use raypath_io::octomap::{ScanGraph, ScanNode, read_bt, write_graph_file};

mod common;
use common::{json_of, raypath};

/// A box room [−3, 3] × [−2, 2] × [−1, 2] m scanned `scans` times from near the origin.
fn room_graph(dir: &Path, scans: usize) -> PathBuf {
    let mut points = Vec::new();
    for i in 0..60 {
        for j in 0..30 {
            let (u, v) = (f64::from(i) / 59.0, f64::from(j) / 29.0);
            points.push(Point3::new(3.0, -2.0 + 4.0 * u, -1.0 + 3.0 * v));
            points.push(Point3::new(-3.0, -2.0 + 4.0 * u, -1.0 + 3.0 * v));
            points.push(Point3::new(-3.0 + 6.0 * u, 2.0, -1.0 + 3.0 * v));
            points.push(Point3::new(-3.0 + 6.0 * u, -2.0 + 4.0 * v, -1.0));
        }
    }
    let cloud: Vec<Point3<f32>> = points.iter().map(|p| p.cast::<f32>()).collect();
    let graph = ScanGraph {
        nodes: (0..scans)
            .map(|i| ScanNode {
                id: i as u32,
                world_from_sensor: Pose3::from_xyz_rpy(0.05, 0.05, 0.05, 0.0, 0.0, 0.0),
                points: PointCloud::from_points(
                    cloud
                        .iter()
                        .map(|p| p - nalgebra::Vector3::new(0.05, 0.05, 0.05))
                        .collect(),
                ),
            })
            .collect(),
        edges: Vec::new(),
    };
    let path = dir.join("room.graph");
    write_graph_file(&path, &graph).unwrap();
    path
}

#[test]
fn room_graph_follows_the_json_contract_and_fuses() {
    let dir = tempfile::tempdir().unwrap();
    let graph = room_graph(dir.path(), 8);
    let graph = graph.to_str().unwrap();
    let fused = json_of(&raypath(&[
        "octree",
        graph,
        "--resolution",
        "0.2",
        "--json",
    ]));
    for key in [
        "input",
        "scans",
        "points",
        "resolution_m",
        "model",
        "fusion",
        "max_entries",
        "min_entries",
        "nodes",
        "leaves",
        "occupied_leaves",
        "fused_leaves",
        "height",
        "base_cubes",
        "bytes",
        "insert_secs",
        "insert_us_per_point",
        "access_secs",
        "out",
    ] {
        assert!(fused.get(key).is_some(), "missing key {key}");
    }
    assert_eq!(fused["scans"], 8);
    assert_eq!(fused["points"], 8 * 60 * 30 * 4);
    let plain = json_of(&raypath(&[
        "octree",
        graph,
        "--resolution",
        "0.2",
        "--no-fusion",
        "--json",
    ]));
    // Same volume, fewer leaves after fusion.
    assert_eq!(fused["base_cubes"], plain["base_cubes"]);
    assert_eq!(plain["leaves"], plain["base_cubes"]);
    assert!(fused["leaves"].as_u64().unwrap() * 3 < plain["leaves"].as_u64().unwrap());
    assert!(fused["fused_leaves"].as_u64().unwrap() > 0);
    let endpoint = json_of(&raypath(&[
        "octree",
        graph,
        "--resolution",
        "0.2",
        "--model",
        "endpoint",
        "--json",
    ]));
    // The end-point model knows only occupied cells.
    assert_eq!(endpoint["occupied_leaves"], endpoint["leaves"]);
}

#[test]
fn equal_value_fusion_keeps_the_volume_and_fuses_a_single_scan() {
    let dir = tempfile::tempdir().unwrap();
    let graph = room_graph(dir.path(), 1);
    let graph = graph.to_str().unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec!["octree", graph, "--resolution", "0.2", "--json"];
        args.extend_from_slice(extra);
        json_of(&raypath(&args))
    };
    let clamped = run(&[]);
    let equal = run(&["--fusion", "equal"]);
    let plain = run(&["--no-fusion"]);
    assert_eq!(clamped["fusion"], "clamped");
    assert_eq!(equal["fusion"], "equal");
    // One scan clamps nothing: the thesis' rule cannot fuse, ours fuses the free space seen
    // once; both cover the same base cubes as the plain grid.
    assert_eq!(clamped["fused_leaves"], 0);
    assert!(equal["fused_leaves"].as_u64().unwrap() > 0);
    assert!(equal["leaves"].as_u64().unwrap() * 2 < plain["leaves"].as_u64().unwrap());
    assert_eq!(equal["base_cubes"], plain["base_cubes"]);
    assert!(equal["occupied_leaves"].as_u64().unwrap() > 0);
    // An interval longer than the graph: the pending fusions run after the last scan.
    let batch = run(&["--fusion", "equal", "--fusion-interval", "4"]);
    assert_eq!(batch["fusion_interval_scans"], 4);
    assert_eq!(batch["base_cubes"], plain["base_cubes"]);
    assert!(batch["fused_leaves"].as_u64().unwrap() > 0);
    // Seeds from every updated cell fuse at least as much, over the same cubes.
    let all = run(&[
        "--fusion",
        "equal",
        "--seeds",
        "all",
        "--fusion-interval",
        "4",
    ]);
    assert_eq!(all["seeds"], "all");
    assert_eq!(batch["seeds"], "samples");
    assert_eq!(all["base_cubes"], plain["base_cubes"]);
    assert!(all["leaves"].as_u64().unwrap() <= batch["leaves"].as_u64().unwrap());
    let zero = raypath(&[
        "octree",
        graph,
        "--resolution",
        "0.2",
        "--fusion-interval",
        "0",
    ]);
    assert_eq!(zero.status.code(), Some(2));
    let bad = raypath(&[
        "octree",
        graph,
        "--resolution",
        "0.2",
        "--fusion",
        "mean",
        "--json",
    ]);
    // An unknown rule is refused by clap: its message on standard error, and with --json
    // also as {"error": …} on standard output.
    assert_eq!(bad.status.code(), Some(2));
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("invalid value 'mean'") && err.contains("--fusion"),
        "{err}"
    );
    let json: serde_json::Value = serde_json::from_slice(&bad.stdout).unwrap();
    assert!(json["error"].as_str().unwrap().contains("'mean'"), "{json}");
}

#[test]
fn writes_bt_and_ply() {
    let dir = tempfile::tempdir().unwrap();
    let graph = room_graph(dir.path(), 6);
    let bt = dir.path().join("map.bt");
    let ply = dir.path().join("map.ply");
    let json = json_of(&raypath(&[
        "octree",
        graph.to_str().unwrap(),
        "--resolution",
        "0.2",
        "--out",
        bt.to_str().unwrap(),
        "--json",
    ]));
    let tree = read_bt(&bt).unwrap();
    assert!((tree.resolution_m - 0.2).abs() < 1e-12);
    let volume: f64 = tree.leaves.iter().map(|l| (l.size_m / 0.2).powi(3)).sum();
    assert!((volume - json["base_cubes"].as_f64().unwrap()).abs() < 1e-6);
    assert!(tree.occupied_leaves() > 0 && tree.free_leaves() > 0);
    let out = raypath(&[
        "octree",
        graph.to_str().unwrap(),
        "--resolution",
        "0.2",
        "--out",
        ply.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let text = std::fs::read_to_string(&ply).unwrap();
    assert!(text.starts_with("ply\n"));
    assert!(text.contains("element face"));
}

#[test]
fn real_scan_dat() {
    let Some(scan) = require("octomap/scan.dat.bz2") else {
        return;
    };
    let json = json_of(&raypath(&[
        "octree",
        scan.to_str().unwrap(),
        "--resolution",
        "0.4",
        "--model",
        "endpoint",
        "--json",
    ]));
    assert_eq!(json["points"], 88_206);
    assert_eq!(json["scans"], 1);
    // One scan: nothing is clamped, so nothing fuses.
    assert_eq!(json["fused_leaves"], 0);
    assert!(json["leaves"].as_u64().unwrap() > 1000);
}

#[test]
fn bad_input_exits_2_with_file_and_place() {
    let dir = tempfile::tempdir().unwrap();
    let graph = room_graph(dir.path(), 1);
    let bytes = std::fs::read(&graph).unwrap();
    let cut = dir.path().join("cut.graph");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let out = raypath(&["octree", cut.to_str().unwrap(), "--resolution", "0.2"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("cut.graph") && err.contains("byte"), "{err}");

    let bad_model = raypath(&[
        "octree",
        graph.to_str().unwrap(),
        "--resolution",
        "0.2",
        "--model",
        "cone",
        "--json",
    ]);
    assert_eq!(bad_model.status.code(), Some(2));
    let err = String::from_utf8_lossy(&bad_model.stderr);
    assert!(err.contains("invalid value 'cone'"), "{err}");
    let json: serde_json::Value = serde_json::from_slice(&bad_model.stdout).unwrap();
    assert!(json["error"].as_str().unwrap().contains("cone"), "{json}");

    let bad_resolution = raypath(&["octree", graph.to_str().unwrap(), "--resolution", "-1"]);
    assert_eq!(bad_resolution.status.code(), Some(2));
    // At 1 nm the lattice reaches ±33 µm: every point of the room would fall off it.
    let tiny = raypath(&["octree", graph.to_str().unwrap(), "--resolution", "1e-9"]);
    assert_eq!(tiny.status.code(), Some(2));
    let err = String::from_utf8_lossy(&tiny.stderr);
    assert!(
        err.contains("room.graph")
            && err.contains("7200 of 7200 points")
            && err.contains("lattice"),
        "{err}"
    );

    let xyz = dir.path().join("bad.xyz");
    std::fs::write(&xyz, "1 2 3\n4 five 6\n").unwrap();
    let out = raypath(&["octree", xyz.to_str().unwrap(), "--resolution", "0.2"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.xyz") && err.contains('2'), "{err}");
}

#[test]
fn quiet_and_verbose_are_global_flags() {
    let dir = tempfile::tempdir().unwrap();
    let graph = room_graph(dir.path(), 2);
    let graph = graph.to_str().unwrap();
    // -v (before or after the subcommand) adds the stage times on standard error.
    for args in [
        ["-v", "octree", graph, "--resolution", "0.2", "--json"],
        ["octree", graph, "--resolution", "0.2", "--json", "-v"],
    ] {
        let out = raypath(&args);
        assert!(out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("insertion and fusion: "), "{args:?}: {err}");
        json_of(&out);
    }
    // --quiet: nothing on standard error for a run without errors; the report is unchanged.
    let out = raypath(&["octree", graph, "--resolution", "0.2", "--quiet"]);
    assert!(out.status.success());
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!out.stdout.is_empty());
    let both = raypath(&["octree", graph, "--resolution", "0.2", "-q", "-v"]);
    assert_eq!(both.status.code(), Some(2));
}
