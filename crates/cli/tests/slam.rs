//! `raypath slam` end to end on the real Intel log: the JSON contract, the output files, the
//! error summary against the corrected log, and bad input.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

mod common;
use common::{json_of, raypath};

#[test]
fn intel_json_contract_outputs_and_errors() {
    let (Some(raw), Some(corrected)) = (
        raypath_io::data::require("carmen/raw/intel.clf.bz2"),
        raypath_io::data::require("carmen/corrected/intel-corrected.log.gz"),
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = raypath(&[
        "slam",
        raw.to_str().unwrap(),
        "--out",
        dir.path().to_str().unwrap(),
        "--scans",
        "2500",
        "--ground-truth",
        corrected.to_str().unwrap(),
        "--json",
    ]);
    let doc = json_of(&out);
    for key in [
        "scans",
        "nodes",
        "loop_closures",
        "seconds",
        "scans_per_second",
    ] {
        assert!(doc.get(key).is_some(), "missing {key}: {doc}");
    }
    assert_eq!(doc["scans"], 2500);
    let s = &doc["summary"];
    for key in [
        "trans_error_m",
        "trans_error_std_m",
        "rot_error_deg",
        "rot_error_std_deg",
    ] {
        assert!(s[key].as_f64().unwrap().is_finite(), "{key}: {s}");
    }
    // Better than odometry (≈ 0.05 m per relation on this stretch) and no wrong loop closure.
    assert!(s["trans_error_m"].as_f64().unwrap() < 0.045, "{s}");
    assert_eq!(doc["wrong_loop_closures"], 0, "{doc}");
    // TUM: one line per scan, 8 numbers, z = 0.
    let tum = std::fs::read_to_string(dir.path().join("trajectory.txt")).unwrap();
    let lines: Vec<&str> = tum.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(lines.len(), 2500);
    let fields: Vec<f64> = lines[10]
        .split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(fields.len(), 8);
    assert_eq!(fields[3], 0.0);
    for name in [
        "corrected.log",
        "map.pgm",
        "map.yaml",
        "map.png",
        "map.rpmap",
        "loop_closures.csv",
    ] {
        assert!(dir.path().join(name).exists(), "{name} missing");
    }
    // The corrected log reads back with the same number of scans.
    let info = json_of(&raypath(&[
        "info",
        dir.path().join("corrected.log").to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(info["scans"], 2500, "{info}");
}

#[test]
fn bad_input_is_exit_2_with_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("broken.log");
    std::fs::write(&log, "FLASER 3 1.0 2.0\n").unwrap();
    let out = raypath(&[
        "slam",
        log.to_str().unwrap(),
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("broken.log"));
    let out = raypath(&[
        "slam",
        log.to_str().unwrap(),
        "--out",
        dir.path().to_str().unwrap(),
        "--resolution",
        "-1",
    ]);
    assert_eq!(out.status.code(), Some(2));
}
