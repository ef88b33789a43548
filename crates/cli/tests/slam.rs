//! `raypath slam` end to end on the real Intel log: the JSON contract, the output files, the
//! error summary against the corrected log, and bad input.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

mod common;
use common::{json_of, raypath};

#[test]
fn intel_json_contract_outputs_and_errors() {
    let (Some(raw), Some(corrected), Some(benchmark)) = (
        raypath_io::data::require("carmen/raw/intel.clf.bz2"),
        raypath_io::data::require("carmen/corrected/intel-corrected.log.gz"),
        raypath_io::data::require("carmen/relations/intel.relations"),
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let derived = dir.path().join("intel-derived.relations");
    write_derived_relations(&raw, &corrected, 2500, &derived);
    let out = raypath(&[
        "slam",
        raw.to_str().unwrap(),
        "--out",
        dir.path().to_str().unwrap(),
        "--scans",
        "2500",
        "--ground-truth",
        corrected.to_str().unwrap(),
        "--relations",
        benchmark.to_str().unwrap(),
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
    // The trajectory is stamped with the scans' sensor (ipc) time: joined by time alone with
    // a relation file — no scan indices — it scores what the program reports. The
    // benchmark's own file (relations past the first 2500 scans are unmatched) …
    let trajectory = dir.path().join("trajectory.txt");
    let f = &doc["relations_file"];
    let (joined, unmatched) = join_by_time(&trajectory, &benchmark);
    assert!(joined.relations > 100, "{joined:?}");
    assert_eq!(f["summary"]["relations"], joined.relations, "{f}");
    assert_eq!(f["unmatched"], unmatched, "{f}");
    let close = |a: f64, b: &serde_json::Value| (a - b.as_f64().unwrap()).abs() < 1e-5;
    assert!(
        close(joined.trans_error_m, &f["summary"]["trans_error_m"]),
        "{joined:?} {f}"
    );
    assert!(
        close(joined.rot_error_deg, &f["summary"]["rot_error_deg"]),
        "{joined:?} {f}"
    );
    // … and the corrected log's consecutive relations written as a relation file (scans named
    // by ipc time stamps, six decimals) give the ground-truth summary.
    let (joined, unmatched) = join_by_time(&trajectory, &derived);
    assert_eq!(unmatched, 0);
    assert_eq!(s["relations"], joined.relations, "{s}");
    assert!(
        close(joined.trans_error_m, &s["trans_error_m"]),
        "{joined:?} {s}"
    );
    assert!(
        close(joined.rot_error_deg, &s["rot_error_deg"]),
        "{joined:?} {s}"
    );
    // TUM: one line per scan, 8 numbers, z = 0.
    let tum = std::fs::read_to_string(&trajectory).unwrap();
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

/// Relation errors of a TUM trajectory against a relation file, joined by time stamps alone
/// (as the SLAM benchmark's own evaluator and `evo` join), and the relations not found.
fn join_by_time(
    trajectory: &std::path::Path,
    relations: &std::path::Path,
) -> (raypath_slam::benchmark::ErrorSummary, usize) {
    use raypath_slam::benchmark::{file_relation_errors, match_relation_file};
    let tum = raypath_io::tum::read_tum(trajectory).unwrap();
    let stamps: Vec<Option<f64>> = tum.iter().map(|p| Some(p.time_s)).collect();
    let poses: Vec<_> = tum.iter().map(|p| p.pose.to_planar()).collect();
    let relations = raypath_io::relations::read_relations(relations).unwrap();
    let matched = match_relation_file(&stamps, &relations);
    (file_relation_errors(&poses, &matched), matched.unmatched)
}

/// Consecutive relations between the first `scans` raw scans that pair with the corrected log,
/// written in the SLAM benchmark's relation format.
fn write_derived_relations(
    raw: &std::path::Path,
    corrected: &std::path::Path,
    scans: usize,
    path: &std::path::Path,
) {
    use raypath_io::sequence::{PlanarOptions, pair_reference, read_planar};
    use raypath_slam::benchmark::{consecutive_relations, relations_from_reference};
    let options = PlanarOptions::default();
    let mut frames = read_planar(raw, &options).unwrap();
    frames.truncate(scans);
    pair_reference(&mut frames, &read_planar(corrected, &options).unwrap());
    let truth: Vec<_> = frames.iter().map(|f| f.reference).collect();
    let stamps: Vec<_> = frames.iter().map(|f| f.ipc_stamp_secs).collect();
    let referenced: Vec<usize> = (0..frames.len()).filter(|&i| truth[i].is_some()).collect();
    let relations = relations_from_reference(&stamps, &truth, &consecutive_relations(&referenced));
    assert!(relations.len() > 10);
    raypath_io::relations::write_relations(path, &relations).unwrap();
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
