//! `raypath dct-map` end to end: the JSON contract on a synthetic room log, the map outputs,
//! a known answer on Intel (the DCT map explains held-back rays better than the grid map with
//! as many parameters) and bad input (exit 2 with file and place).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use std::f64::consts::PI;
use std::io::Write;
use std::path::{Path, PathBuf};

use raypath_io::data::require;

mod common;
use common::{json_of, raypath};

/// A CARMEN log of `scans` FLASER scans (180 beams over 180°) in the room [−3, 4] × [−2, 2.5] m
/// from poses on a small circle, turning by 0.4 rad per scan.
fn room_log(dir: &Path, scans: usize) -> PathBuf {
    let path = dir.join("room.log");
    let mut file = std::fs::File::create(&path).unwrap();
    writeln!(file, "# synthetic room").unwrap();
    for s in 0..scans {
        let theta = 0.4 * s as f64;
        let (px, py) = (0.8 * (0.7 * s as f64).cos(), 0.6 * (0.7 * s as f64).sin());
        let ranges: Vec<String> = (0..180)
            .map(|i| {
                let a = theta - PI / 2.0 + i as f64 * PI / 179.0;
                let (c, si) = (a.cos(), a.sin());
                let tx = if c.abs() < 1e-12 {
                    f64::INFINITY
                } else if c > 0.0 {
                    (4.0 - px) / c
                } else {
                    (-3.0 - px) / c
                };
                let ty = if si.abs() < 1e-12 {
                    f64::INFINITY
                } else if si > 0.0 {
                    (2.5 - py) / si
                } else {
                    (-2.0 - py) / si
                };
                format!("{:.4}", tx.min(ty))
            })
            .collect();
        writeln!(
            file,
            "FLASER 180 {} {px} {py} {theta} {px} {py} {theta} {} host {}",
            ranges.join(" "),
            s as f64,
            s as f64
        )
        .unwrap();
    }
    path
}

const CONTRACT: [&str; 7] = [
    "time_s",
    "grid_time_s",
    "log_likelihood",
    "grid_log_likelihood",
    "rmse_p_ref",
    "grid_rmse_p_ref",
    "iterations",
];

#[test]
fn room_log_follows_the_json_contract_and_writes_maps() {
    let dir = tempfile::tempdir().unwrap();
    let log = room_log(dir.path(), 30);
    let log = log.to_str().unwrap();
    let png = dir.path().join("map.png");
    let json = json_of(&raypath(&[
        "dct-map",
        log,
        "--patch=-3,-2,7,4.5",
        "--coefficients",
        "8,6",
        "--rays",
        "3000",
        "--out",
        png.to_str().unwrap(),
        "--json",
    ]));
    for key in CONTRACT {
        let v = json[key]
            .as_f64()
            .unwrap_or_else(|| panic!("{key} missing: {json}"));
        assert!(v.is_finite(), "{key} = {v}");
    }
    assert!(json["iterations"].as_u64().unwrap() >= 1);
    for key in ["rmse_p_ref", "grid_rmse_p_ref"] {
        let v = json[key].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&v), "{key} = {v}");
    }
    assert!(json["time_s"].as_f64().unwrap() > 0.0);
    assert_eq!(json["rays"], 3000);
    assert_eq!(json["held_back_rays"], 500);
    assert_eq!(json["coefficients"], serde_json::json!([8, 6]));
    let img = std::fs::read(&png).unwrap();
    assert_eq!(&img[1..4], b"PNG");

    // The coefficients as JSON: 8 × 6 values over the 7 m × 4.5 m patch.
    let out = dir.path().join("map.json");
    let _ = json_of(&raypath(&[
        "dct-map",
        log,
        "--patch=-3,-2,7,4.5",
        "--coefficients",
        "8,6",
        "--rays",
        "1000",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]));
    let map: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(map["coefficients"].as_array().unwrap().len(), 48);
    assert_eq!(map["extent_m"], serde_json::json!([7.0, 4.5]));
}

#[test]
fn intel_auto_patch_dct_beats_the_grid_on_held_back_rays() {
    let Some(log) = require("carmen/corrected/intel-corrected.log.gz") else {
        return;
    };
    let json = json_of(&raypath(&[
        "dct-map",
        log.to_str().unwrap(),
        "--patch",
        "auto",
        "--coefficients",
        "20,20",
        "--json",
    ]));
    // The auto patch is deterministic: the 10 m square with the most ray path length.
    assert_eq!(json["patch"], serde_json::json!([5.0, -8.0, 10.0, 10.0]));
    assert_eq!(json["rays"], 10_000);
    let (ll, grid_ll) = (
        json["log_likelihood"].as_f64().unwrap(),
        json["grid_log_likelihood"].as_f64().unwrap(),
    );
    assert!(ll > grid_ll + 50.0, "DCT {ll} vs grid {grid_ll}");
    let (rmse, grid_rmse) = (
        json["rmse_p_ref"].as_f64().unwrap(),
        json["grid_rmse_p_ref"].as_f64().unwrap(),
    );
    assert!(rmse < grid_rmse, "DCT {rmse} vs grid {grid_rmse}");
}

#[test]
fn bad_input_exits_2_with_file_and_place() {
    let dir = tempfile::tempdir().unwrap();
    let log = room_log(dir.path(), 3);
    let log_s = log.to_str().unwrap();
    // Missing file.
    let out = raypath(&["dct-map", "/nonexistent/x.log", "--coefficients", "4,4"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/x.log"));
    // Bad parameters.
    for args in [
        ["--coefficients", "4"],
        ["--coefficients", "4,x"],
        ["--coefficients", "0,4"],
        ["--patch", "1,2,3"],
        ["--rays", "0"],
    ] {
        let mut all = vec!["dct-map", log_s, "--json"];
        all.extend(args);
        if args[0] != "--coefficients" {
            all.extend(["--coefficients", "4,4"]);
        }
        let out = raypath(&all);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert!(json["error"].as_str().is_some());
    }
    // A patch no ray reaches, an unknown output type.
    let out = raypath(&[
        "dct-map",
        log_s,
        "--patch",
        "100,100,5,5",
        "--coefficients",
        "4,4",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let out = raypath(&[
        "dct-map",
        log_s,
        "--coefficients",
        "4,4",
        "--out",
        "/tmp/x.txt",
    ]);
    assert_eq!(out.status.code(), Some(2));
    // A malformed line: the file and the line number are named.
    let bad = dir.path().join("bad.log");
    let mut text = std::fs::read_to_string(&log).unwrap();
    text.push_str("FLASER 180 1.0 2.0 oops\n");
    std::fs::write(&bad, text).unwrap();
    let out = raypath(&["dct-map", bad.to_str().unwrap(), "--coefficients", "4,4"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.log") && err.contains('5'), "{err}");
}
