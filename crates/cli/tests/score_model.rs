//! `raypath score-model` end to end: the JSON contract on a real log, determinism, and bad
//! input (exit 2 with file:line).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use std::io::Write;

use raypath_io::data::require;

mod common;
use common::raypath;

const FAST: [&str; 4] = ["--max-test-scans", "12", "--beam-step", "4"];

#[test]
fn intel_rows_follow_the_json_contract() {
    let Some(path) = require("carmen/corrected/intel-corrected.log.gz") else {
        return;
    };
    let path = path.to_str().expect("UTF-8 path");
    let mut args = vec!["score-model", path, "--json"];
    args.extend(FAST);
    let out = raypath(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("valid JSON");
    let rows = json["rows"].as_array().expect("rows");
    let expected = [
        ("decay-rate", false),
        ("decay-rate", true),
        ("reflection", false),
        ("reflection", true),
        ("endpoint", false),
        ("likelihood-field", false),
        ("log-odds", false),
    ];
    assert_eq!(rows.len(), expected.len());
    for (row, (model, posterior)) in rows.iter().zip(expected) {
        let object = row.as_object().expect("row object");
        let mut keys: Vec<&str> = object.keys().map(String::as_str).collect();
        keys.sort_unstable();
        assert_eq!(
            keys,
            ["inverse_kl", "model", "neg_log_likelihood", "posterior"]
        );
        assert_eq!(row["model"], model);
        assert_eq!(row["posterior"], posterior);
        assert!(row["neg_log_likelihood"].as_f64().unwrap().is_finite());
        assert!(row["inverse_kl"].as_f64().unwrap() >= 0.0);
    }
    // Intel: 910 scans, odd ones scored (455, thinned to 12 with step 38), 180 beams / 4.
    assert_eq!(json["scans"], 910);
    assert_eq!(json["mapping_scans"], 455);
    assert_eq!(json["test_scans"], 12);
    assert_eq!(json["test_rays"], 12 * 45);
    // The no-return threshold inferred from the log (readings of 81.83 m and above).
    let r_max = json["max_range_m"].as_f64().unwrap();
    assert!((80.0..82.0).contains(&r_max), "{r_max}");
    // At the true poses the probabilistic models assign the data more than a uniform
    // density over the range would: D' < rays · ln(r_max). (Not log-odds: an occupancy
    // map clamped at 0.12 / 0.97 is no measurement model, and on Intel it does worse.)
    let uniform = 12.0 * 45.0 * r_max.ln();
    for row in rows.iter().filter(|r| r["model"] != "log-odds") {
        assert!(
            row["neg_log_likelihood"].as_f64().unwrap() < uniform,
            "{row}"
        );
    }
    // Same seed, same figures.
    let again: serde_json::Value = serde_json::from_slice(&raypath(&args).stdout).unwrap();
    assert_eq!(json["rows"], again["rows"]);
    // The human table names every model.
    let mut text_args = vec!["score-model", path];
    text_args.extend(FAST);
    let text = String::from_utf8(raypath(&text_args).stdout).unwrap();
    for (model, _) in expected {
        assert!(text.contains(model), "{text}");
    }
}

#[test]
fn a_malformed_log_exits_2_with_file_and_line() {
    let mut file = tempfile::Builder::new().suffix(".log").tempfile().unwrap();
    writeln!(file, "# a CARMEN log").unwrap();
    writeln!(
        file,
        "FLASER 3 1.0 2.0 3.0 0.0 0.0 0.0 0.0 0.0 0.0 1.0 host 1.0"
    )
    .unwrap();
    writeln!(
        file,
        "FLASER 3 1.0 oops 3.0 0.0 0.0 0.0 0.0 0.0 0.0 2.0 host 2.0"
    )
    .unwrap();
    file.flush().unwrap();
    let path = file.path().to_str().unwrap();
    let out = raypath(&["score-model", path, "--json"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains(path) && stderr.contains(":3"), "{stderr}");
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON error");
    assert!(json["error"].as_str().unwrap().contains(path));
}

#[test]
fn bad_arguments_exit_2() {
    let mut file = tempfile::Builder::new().suffix(".log").tempfile().unwrap();
    writeln!(
        file,
        "FLASER 3 1.0 2.0 3.0 0.0 0.0 0.0 0.0 0.0 0.0 1.0 host 1.0"
    )
    .unwrap();
    file.flush().unwrap();
    let path = file.path().to_str().unwrap();
    // One scan: nothing to test.
    let out = raypath(&["score-model", path]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains(path));
    for args in [
        ["--resolution", "0"],
        ["--split", "thirds"],
        ["--poses", "1"],
        ["--beam-step", "0"],
    ] {
        let mut all = vec!["score-model", path];
        all.extend(args);
        assert_eq!(raypath(&all).status.code(), Some(2), "{args:?}");
    }
    let out = raypath(&["score-model", "/no/such/file.log"]);
    assert_eq!(out.status.code(), Some(2));
}
