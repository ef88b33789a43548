//! `raypath localize` end to end: a simulated office (raw log with drifting odometry,
//! corrected log as ground truth), a map written with `export::binary`, and bad input.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use std::path::{Path, PathBuf};

use nalgebra::Point2;
use raypath_geometry::{Aabb2, Grid2, Pose2, Scan2};
use raypath_io::carmen::{CarmenReader, Record};
use raypath_sensor_models::export::{MapFile, MapKind, StoredStats};
use raypath_sensor_models::{DenseStats2, DenseStats3, MappingConfig};
use raypath_sim::indoor::{FloorPlanConfig, IndoorConfig, Laser2Config, WorldConfig, generate};

mod common;
use common::raypath;

fn s(path: &Path) -> &str {
    path.to_str().expect("UTF-8 path")
}

/// A small simulated office under `dir` and a decay-rate map of it from the corrected log.
fn office(dir: &Path) -> (PathBuf, PathBuf, PathBuf) {
    let world = WorldConfig::new(
        "office",
        FloorPlanConfig {
            width_m: 14.0,
            height_m: 10.0,
            ..FloorPlanConfig::default()
        },
        Laser2Config::sick_180(),
        240,
    );
    let config = IndoorConfig {
        worlds: vec![world],
    };
    generate(&config, 3, dir, raypath_sim::no_progress()).unwrap();
    let raw = dir.join("office.clf");
    let corrected = dir.join("office-corrected.log");
    let scans: Vec<(Pose2, Scan2)> = CarmenReader::open(&corrected)
        .unwrap()
        .filter_map(|r| match r.unwrap() {
            Record::Laser(m) => Some((m.world_from_laser, m.scan)),
            _ => None,
        })
        .collect();
    assert_eq!(scans.len(), 240);
    let grid = Grid2::covering(
        &Aabb2::new(Point2::new(-1.0, -1.0), Point2::new(15.0, 11.0)),
        0.1,
    )
    .unwrap();
    let mut stats = DenseStats2::new(grid);
    let refs: Vec<(Pose2, &Scan2)> = scans.iter().map(|(p, s)| (*p, s)).collect();
    let mapping = MappingConfig::default();
    stats.insert_scans_par(&refs, &mapping);
    let map = dir.join("office.map");
    MapFile {
        kind: MapKind::DecayRate,
        posterior: false,
        mapping,
        stats: StoredStats::Planar(stats),
    }
    .write_file(&map)
    .unwrap();
    (raw, corrected, map)
}

fn localize_json(args: &[&str]) -> serde_json::Value {
    let out = raypath(args);
    assert!(
        out.status.success(),
        "raypath {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("valid JSON")
}

#[test]
fn localizes_a_simulated_office_with_carmen_and_tum_ground_truth() {
    let dir = tempfile::tempdir().unwrap();
    let (raw, corrected, map) = office(dir.path());
    let tum = dir.path().join("estimate.tum");
    let common = [
        "localize",
        "--map",
        s(&map),
        "--log",
        s(&raw),
        "--particles",
        "300",
        "--beam-step",
        "4",
        "--seed",
        "9",
        "--json",
    ];
    let mut args = common.to_vec();
    args.extend(["--ground-truth", s(&corrected), "--out", s(&tum)]);
    let first = localize_json(&args);
    eprintln!("{first:#}");
    assert_eq!(first["model"], "decay-rate [table]");
    assert_eq!(first["scans"], 240);
    let updates = first["updates"].as_u64().unwrap();
    assert!(updates > 50, "updates {updates}");
    let error = &first["error"];
    assert!(error["length_m"].as_f64().unwrap() > 10.0);
    assert!(error["position_mean_m"].as_f64().unwrap() < 0.3, "{error}");
    assert!(error["heading_mean_rad"].as_f64().unwrap() < 0.1, "{error}");
    assert_eq!(error["diverged"], false);
    // The TUM output has one line per estimate (plus a comment).
    let text = std::fs::read_to_string(&tum).unwrap();
    let lines = text.lines().filter(|l| !l.starts_with('#')).count();
    assert!(lines as u64 >= updates.min(240) / 2 && lines <= 240);

    // Same seed, same result.
    let again = localize_json(&args);
    assert_eq!(first, again);

    // Ground truth as a TUM file (the corrected poses): the same evaluation.
    let gt_tum = dir.path().join("truth.tum");
    let mut gt = String::from("# t x y z qx qy qz qw\n");
    for r in CarmenReader::open(&corrected).unwrap() {
        if let Record::Laser(m) = r.unwrap() {
            let p = m.world_from_robot;
            let h = p.theta() / 2.0;
            gt.push_str(&format!(
                "{:.6} {} {} 0 0 0 {} {}\n",
                m.logger_timestamp_secs,
                p.x(),
                p.y(),
                h.sin(),
                h.cos()
            ));
        }
    }
    std::fs::write(&gt_tum, gt).unwrap();
    let mut args = common.to_vec();
    args.extend(["--ground-truth", s(&gt_tum)]);
    let with_tum = localize_json(&args);
    let a = first["error"]["position_mean_m"].as_f64().unwrap();
    let b = with_tum["error"]["position_mean_m"].as_f64().unwrap();
    assert!((a - b).abs() < 0.05, "CARMEN {a} vs TUM {b}");

    // Without ground truth: no error block; text mode prints the summary line.
    let out = raypath(&[
        "localize",
        "--map",
        s(&map),
        "--log",
        s(&raw),
        "--particles",
        "100",
        "--beam-step",
        "6",
        "--model-override",
        "likelihood-field",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("240 scans") && stdout.contains("likelihood-field"),
        "{stdout}"
    );
}

fn expect_input_error(args: &[&str], needles: &[&str]) {
    let out = raypath(args);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    for needle in needles {
        assert!(
            stderr.contains(needle),
            "{args:?}: {needle:?} not in {stderr}"
        );
    }
}

#[test]
fn bad_input_exits_2_naming_the_file_and_place() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A tiny valid map and log.
    let grid = Grid2::covering(
        &Aabb2::new(Point2::new(0.0, 0.0), Point2::new(4.0, 4.0)),
        0.1,
    )
    .unwrap();
    let map = d.join("ok.map");
    MapFile {
        kind: MapKind::Reflection,
        posterior: false,
        mapping: MappingConfig::default(),
        stats: StoredStats::Planar(DenseStats2::new(grid)),
    }
    .write_file(&map)
    .unwrap();
    let log = d.join("ok.log");
    std::fs::write(&log, "FLASER 3 1.0 1.5 2.0 1 1 0 1 1 0 0.5 host 0.5\n").unwrap();

    // Truncated map: the byte offset.
    let bytes = std::fs::read(&map).unwrap();
    let truncated = d.join("truncated.map");
    std::fs::write(&truncated, &bytes[..100]).unwrap();
    expect_input_error(
        &["localize", "--map", s(&truncated), "--log", s(&log)],
        &["truncated.map", "byte"],
    );
    // Missing log.
    let missing = d.join("missing.log");
    expect_input_error(
        &["localize", "--map", s(&map), "--log", s(&missing)],
        &["missing.log"],
    );
    // Malformed log line.
    let bad_log = d.join("bad.log");
    std::fs::write(
        &bad_log,
        "FLASER 3 1.0 1.5 2.0 1 1 0 1 1 0 0.5 host 0.5\nFLASER 3 1.0 x\n",
    )
    .unwrap();
    expect_input_error(
        &["localize", "--map", s(&map), "--log", s(&bad_log)],
        &["bad.log", "2"],
    );
    // Malformed TUM ground truth.
    let bad_gt = d.join("bad.tum");
    std::fs::write(&bad_gt, "# header\n0.5 1 1 0 0 0 0 1\n0.6 1 1 0 0 0\n").unwrap();
    expect_input_error(
        &[
            "localize",
            "--map",
            s(&map),
            "--log",
            s(&log),
            "--ground-truth",
            s(&bad_gt),
        ],
        &["bad.tum:3"],
    );
    // Bad parameters.
    expect_input_error(
        &[
            "localize",
            "--map",
            s(&map),
            "--log",
            s(&log),
            "--model-override",
            "laser",
        ],
        &["--model-override", "laser"],
    );
    expect_input_error(
        &[
            "localize",
            "--map",
            s(&map),
            "--log",
            s(&log),
            "--initial",
            "1,2",
        ],
        &["--initial"],
    );
    expect_input_error(
        &[
            "localize",
            "--map",
            s(&map),
            "--log",
            s(&log),
            "--particles",
            "0",
        ],
        &["--particles"],
    );
    // A 3-D map.
    let map3 = d.join("three.map");
    let grid3 = raypath_geometry::Grid3::covering(
        &raypath_geometry::Aabb3::new(
            nalgebra::Point3::new(0.0, 0.0, 0.0),
            nalgebra::Point3::new(2.0, 2.0, 2.0),
        ),
        0.5,
    )
    .unwrap();
    MapFile {
        kind: MapKind::DecayRate,
        posterior: false,
        mapping: MappingConfig::default(),
        stats: StoredStats::Spatial(DenseStats3::new(grid3)),
    }
    .write_file(&map3)
    .unwrap();
    expect_input_error(
        &["localize", "--map", s(&map3), "--log", s(&log)],
        &["three.map", "3-D"],
    );
    // JSON mode: the error is also printed as JSON.
    let out = raypath(&[
        "localize",
        "--map",
        s(&truncated),
        "--log",
        s(&log),
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v["error"].as_str().unwrap().contains("truncated.map"));
}
