//! `raypath polylines` end to end: the JSON contract on a synthetic room log and on Intel,
//! PLE+ never worse than PLE, the SVG output, and bad input (exit 2 with file and place).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use std::f64::consts::PI;
use std::io::Write;
use std::path::Path;

use raypath_io::data::require;

mod common;
use common::{json_of, raypath};

/// A CARMEN log of `scans` FLASER scans (180 beams over 180°) of the room
/// [−3, 4] × [−2, 2.5] m seen from the origin, turning by 0.3 rad per scan.
fn room_log(dir: &Path, scans: usize) -> std::path::PathBuf {
    let path = dir.join("room.log");
    let mut file = std::fs::File::create(&path).unwrap();
    writeln!(file, "# synthetic room").unwrap();
    for s in 0..scans {
        let theta = 0.3 * s as f64;
        let ranges: Vec<String> = (0..180)
            .map(|i| {
                let a = theta - PI / 2.0 + i as f64 * PI / 179.0;
                let (c, si) = (a.cos(), a.sin());
                let tx = if c.abs() < 1e-12 {
                    f64::INFINITY
                } else if c > 0.0 {
                    4.0 / c
                } else {
                    -3.0 / c
                };
                let ty = if si.abs() < 1e-12 {
                    f64::INFINITY
                } else if si > 0.0 {
                    2.5 / si
                } else {
                    -2.0 / si
                };
                format!("{:.4}", tx.min(ty))
            })
            .collect();
        writeln!(
            file,
            "FLASER 180 {} 0 0 {theta} 0 0 {theta} {} host {}",
            ranges.join(" "),
            s as f64,
            s as f64
        )
        .unwrap();
    }
    path
}

#[test]
fn room_log_follows_the_json_contract() {
    let dir = tempfile::tempdir().unwrap();
    let log = room_log(dir.path(), 3);
    let log = log.to_str().unwrap();
    let json = json_of(&raypath(&[
        "polylines",
        log,
        "--all",
        "--vertices",
        "8",
        "--json",
    ]));
    let scans = json["scans"].as_array().expect("scans");
    assert_eq!(scans.len(), 3);
    for (i, scan) in scans.iter().enumerate() {
        let mut keys: Vec<&str> = scan
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        keys.sort_unstable();
        assert_eq!(keys, ["f", "index", "polylines", "rmse"]);
        assert_eq!(scan["index"], i);
        let polylines = scan["polylines"].as_array().unwrap();
        let vertices: usize = polylines.iter().map(|p| p.as_array().unwrap().len()).sum();
        assert!((2..=8).contains(&vertices), "{vertices} vertices");
        for p in polylines {
            for v in p.as_array().unwrap() {
                let xy = v.as_array().unwrap();
                assert_eq!(xy.len(), 2);
                // Inside the room (in the scan frame, within its diagonal).
                let (x, y) = (xy[0].as_f64().unwrap(), xy[1].as_f64().unwrap());
                assert!(x.hypot(y) <= 5.0 + 1e-6);
            }
        }
        // A noise-free room: every ray explained, millimetre-level error with 8 vertices.
        assert_eq!(scan["f"].as_f64().unwrap(), 1.0);
        assert!(scan["rmse"].as_f64().unwrap() < 0.05);
    }
    assert_eq!(json["closed"].as_array().unwrap().len(), 3);
    assert_eq!(json["method"], "PLE");
}

#[test]
fn optimize_is_never_worse_and_svg_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let log = room_log(dir.path(), 2);
    let log = log.to_str().unwrap();
    let svg = dir.path().join("room.svg");
    let plain = json_of(&raypath(&[
        "polylines",
        log,
        "--scans",
        "1",
        "--vertices",
        "5",
        "--json",
    ]));
    let optimized = json_of(&raypath(&[
        "polylines",
        log,
        "--scans",
        "1",
        "--vertices",
        "5",
        "--optimize",
        "--svg",
        svg.to_str().unwrap(),
        "--json",
    ]));
    let rmse = |j: &serde_json::Value| j["scans"][0]["rmse"].as_f64().unwrap();
    assert!(rmse(&optimized) <= rmse(&plain) + 1e-12);
    assert_eq!(optimized["scans"][0]["f"], plain["scans"][0]["f"]);
    assert_eq!(optimized["method"], "PLE+");
    assert_eq!(optimized["optimizer"], "levenberg-marquardt");
    let picture = std::fs::read_to_string(&svg).unwrap();
    assert!(picture.starts_with("<svg") && picture.contains("<polyline"));
}

#[test]
fn intel_scans() {
    let Some(path) = require("carmen/corrected/intel-corrected.log.gz") else {
        return;
    };
    let path = path.to_str().expect("UTF-8 path");
    for extra in [&[][..], &["--optimize"][..], &["--method", "vvl"][..]] {
        let mut args = vec!["polylines", path, "--scans", "0,400,909", "--json"];
        args.extend_from_slice(extra);
        let json = json_of(&raypath(&args));
        let scans = json["scans"].as_array().unwrap();
        let indices: Vec<u64> = scans.iter().map(|s| s["index"].as_u64().unwrap()).collect();
        assert_eq!(indices, [0, 400, 909]);
        for s in scans {
            let f = s["f"].as_f64().unwrap();
            assert!(f > 0.3 && f <= 1.0, "f = {f}");
            let rmse = s["rmse"].as_f64().unwrap();
            assert!(rmse > 0.0 && rmse < 0.5, "rmse = {rmse}");
            let vertices: usize = s["polylines"]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| p.as_array().unwrap().len())
                .sum();
            assert!(vertices <= 20);
        }
    }
}

#[test]
fn bad_input_exits_2_with_the_place() {
    let dir = tempfile::tempdir().unwrap();
    let log = room_log(dir.path(), 2);
    let log_str = log.to_str().unwrap();

    let out = raypath(&["polylines", log_str, "--scans", "7"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("room.log") && err.contains("scan 7"), "{err}");

    let out = raypath(&["polylines", log_str, "--vertices", "1", "--json"]);
    assert_eq!(out.status.code(), Some(2));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("error JSON");
    assert!(json["error"].as_str().unwrap().contains("max_vertices"));

    for args in [
        &["--method", "hough"][..],
        &["--solver", "bfgs"][..],
        &["--method", "ief", "--optimize"][..],
    ] {
        let mut all = vec!["polylines", log_str];
        all.extend_from_slice(args);
        assert_eq!(raypath(&all).status.code(), Some(2), "{args:?}");
    }

    let bad = dir.path().join("bad.log");
    let mut text = std::fs::read_to_string(&log).unwrap();
    text.push_str("FLASER 180 1.0 2.0 oops\n");
    std::fs::write(&bad, text).unwrap();
    let out = raypath(&["polylines", bad.to_str().unwrap(), "--all"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.log:4"), "{err}");
}
