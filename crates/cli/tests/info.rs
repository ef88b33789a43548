//! `raypath info` end to end: the binary on real data, on broken files and on bad arguments.

use raypath_io::data::require;

mod common;
use common::raypath;

fn info_json(path: &std::path::Path) -> serde_json::Value {
    let out = raypath(&["info", path.to_str().expect("UTF-8 path"), "--json"]);
    assert!(
        out.status.success(),
        "raypath info {} failed: {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("valid JSON")
}

#[test]
fn intel_corrected_log() {
    let Some(path) = require("carmen/corrected/intel-corrected.log.gz") else {
        return;
    };
    let json = info_json(&path);
    assert_eq!(json["format"], "carmen");
    assert_eq!(json["scans"], 910);
    assert_eq!(json["beams"], 180);
    assert!(json["time_span"]["duration"].as_f64().unwrap() > 0.0);
    assert!(json["bbox"]["min"].is_array());
}

#[test]
fn every_carmen_log_matches_the_data_readme() {
    let expected = [
        ("corrected/acapulco-corrected.log.gz", 861, 181),
        ("corrected/aces-corrected.log.gz", 440, 180),
        ("corrected/belgioioso-corrected.log.gz", 395, 361),
        ("corrected/csail-corrected.log.gz", 406, 361),
        ("corrected/fhw-corrected.log.gz", 488, 180),
        ("corrected/freiburg-079-corrected.log.gz", 4791, 360),
        ("corrected/freiburg-101-corrected.log.gz", 292, 360),
        ("corrected/freiburg-campus-corrected.log.gz", 2008, 360),
        ("corrected/infinite-corridor-corrected.log.gz", 1941, 180),
        ("corrected/intel-corrected.log.gz", 910, 180),
    ];
    for (name, scans, beams) in expected {
        let Some(path) = require(format!("carmen/{name}")) else {
            return;
        };
        let json = info_json(&path);
        assert_eq!(json["scans"], scans, "{name}");
        assert_eq!(json["beams"], beams, "{name}");
    }
    let raw = [
        ("raw/intel.clf.bz2", 13631, Some(26915)),
        ("raw/fr079.clf.bz2", 4934, Some(8951)),
        ("raw/mit-csail.clf.bz2", 1988, None),
        ("raw/fr-clinic_robotlaser.clf.bz2", 6917, None),
    ];
    for (name, scans, odometry) in raw {
        let Some(path) = require(format!("carmen/{name}")) else {
            return;
        };
        let json = info_json(&path);
        assert_eq!(json["scans"], scans, "{name}");
        if let Some(odometry) = odometry {
            assert_eq!(json["odometry"], odometry, "{name}");
        }
    }
}

#[test]
fn synpeb_sample_pcd() {
    let Some(path) = require("planes/synpeb-sample-100x100.pcd") else {
        return;
    };
    let json = info_json(&path);
    assert_eq!(json["format"], "pcd");
    assert_eq!(json["width"], 100);
    assert_eq!(json["height"], 100);
    assert_eq!(json["points"], 10_000);
    let labels = json["labels"].as_array().expect("labels listed");
    assert!(
        labels.iter().any(|l| l.as_u64().unwrap() >= 10),
        "plane labels ≥ 10"
    );
}

#[test]
fn octomap_samples() {
    if let Some(path) = require("octomap/geb079.bt") {
        let json = info_json(&path);
        assert_eq!(json["format"], "octomap-bt");
        assert_eq!(json["nodes"], 532_566);
    }
    if let Some(path) = require("octomap/spherical_scan.graph") {
        let json = info_json(&path);
        assert_eq!(json["format"], "octomap-graph");
        assert_eq!(json["nodes"], 1);
        assert_eq!(json["points"], 10_201);
    }
    if let Some(path) = require("octomap/scan.dat.bz2") {
        let json = info_json(&path);
        assert_eq!(json["format"], "xyz");
        assert_eq!(json["points"], 88_206);
    }
}

#[test]
fn kitti_directory_is_one_input() {
    let Some(path) = require("kitti-poles/00") else {
        return;
    };
    let json = info_json(&path);
    assert_eq!(json["format"], "kitti");
    assert_eq!(json["poses"], 4541);
}

#[test]
fn real_kitti_sequence_lists_semantic_classes() {
    let Some(path) = require("kitti/sequences/07") else {
        return;
    };
    let json = info_json(&path);
    assert_eq!(json["scans"], 10);
    let classes = json["semantic_classes"]["classes"]
        .as_array()
        .expect("classes");
    let points: u64 = classes.iter().filter_map(|c| c["points"].as_u64()).sum();
    assert_eq!(json["points"].as_u64(), Some(points), "one label per point");
    assert!(classes.iter().any(|c| c["name"] == "traffic-sign"));
    let out = raypath(&["info", path.to_str().expect("UTF-8 path")]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("semantic labels (10 labelled frames)"),
        "{text}"
    );
    assert!(text.contains("pole"), "{text}");
}

#[test]
fn broken_file_exits_2_naming_the_place() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.log");
    std::fs::write(&path, "FLASER 3 1.0 2.0\n").unwrap();
    let out = raypath(&["info", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("broken.log:1"), "{stderr}");

    let out = raypath(&["info", path.to_str().expect("UTF-8 path"), "--json"]);
    assert_eq!(out.status.code(), Some(2));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(json["error"].as_str().unwrap().contains("broken.log:1"));
}

#[test]
fn unknown_and_missing_files_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mystery.bin.dat");
    std::fs::write(&path, [0u8, 159, 146, 150, 1, 2, 3]).unwrap();
    let out = raypath(&["info", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("mystery.bin.dat"));

    let out = raypath(&["info", "/definitely/not/here.pcd"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/definitely/not/here.pcd"));

    let out = raypath(&["info", "x", "--format", "nonsense"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown format"));
}

#[test]
fn format_override_reads_a_misnamed_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("points.weird");
    std::fs::write(&path, "1 2 3\n4 5 6\n").unwrap();
    let out = raypath(&["info", path.to_str().unwrap(), "--format", "xyz", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["points"], 2);
    assert_eq!(json["bbox"]["max"][2], 6.0);
}
