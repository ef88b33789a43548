//! `raypath loop-closure` end to end: a generated image folder that revisits its first frames
//! (with a TUM pose file), a small real CARMEN log with itself as ground truth when
//! RAYPATH_DATA has it, the JSON contract, and bad input exiting with 2.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use std::fmt::Write as _;
use std::path::Path;

use image::{GrayImage, Luma};
use raypath_io::data::require;

mod common;
use common::{json_of, raypath};

/// A textured image: seeded pseudo-random blocks of 4×4 pixels.
fn texture(seed: u64) -> GrayImage {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut blocks = [0u8; 16 * 12];
    for b in &mut blocks {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        *b = (state >> 56) as u8;
    }
    GrayImage::from_fn(64, 48, |x, y| Luma([blocks[(y / 4 * 16 + x / 4) as usize]]))
}

/// Twelve frames: places 0..6 at x = 0, 10, …, 50 m, then the same places again. Writes the
/// images and a TUM pose file; returns the pose file.
fn write_folder(dir: &Path) -> std::path::PathBuf {
    let images = dir.join("images");
    std::fs::create_dir_all(&images).unwrap();
    let mut tum = String::new();
    for i in 0..12u64 {
        let place = i % 6;
        texture(place)
            .save(images.join(format!("frame{i:03}.png")))
            .unwrap();
        writeln!(tum, "{i} {} 0 0 0 0 0 1", 10 * place).unwrap();
    }
    let poses = dir.join("poses.tum");
    std::fs::write(&poses, tum).unwrap();
    poses
}

const KEYS: [&str; 5] = ["method", "frames", "ms_per_query", "loops", "candidates"];

fn check_keys(doc: &serde_json::Value, summary: bool) {
    let obj = doc.as_object().expect("an object");
    let mut expected: Vec<&str> = KEYS.to_vec();
    if summary {
        expected.push("summary");
    }
    let mut got: Vec<&str> = obj.keys().map(String::as_str).collect();
    got.sort_unstable();
    expected.sort_unstable();
    assert_eq!(got, expected);
    for entry in doc["loops"]
        .as_array()
        .unwrap()
        .iter()
        .chain(doc["candidates"].as_array().unwrap())
    {
        let mut k: Vec<&str> = entry
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        k.sort_unstable();
        assert_eq!(k, ["match", "query", "score"]);
    }
    if summary {
        let mut k: Vec<&str> = doc["summary"]
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        k.sort_unstable();
        assert_eq!(
            k,
            [
                "max_f1",
                "precision_at_100_recall",
                "recall_at_100_precision"
            ]
        );
    }
}

#[test]
fn image_folder_revisits_are_found_online_and_kidnapped() {
    let dir = tempfile::tempdir().unwrap();
    let poses = write_folder(dir.path());
    let images = dir.path().join("images");
    let (images, poses) = (images.to_str().unwrap(), poses.to_str().unwrap());
    // Identical images score 1 (up to rounding); different textures less.
    let common = [
        "--method",
        "hog",
        "--exclusion-frames",
        "3",
        "--min-score",
        "0.999",
        "--ground-truth",
        poses,
        "--json",
    ];
    let online = json_of(&raypath(
        &[&["loop-closure", images][..], &common[..]].concat(),
    ));
    check_keys(&online, true);
    assert_eq!(online["method"], "hog");
    assert_eq!(online["frames"], 12);
    // Frames 6..12 revisit 0..6 exactly: each closes a loop with its twin.
    let loops: Vec<(u64, u64)> = online["loops"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| (l["query"].as_u64().unwrap(), l["match"].as_u64().unwrap()))
        .collect();
    assert_eq!(loops, (6..12).map(|q| (q, q - 6)).collect::<Vec<_>>());
    assert_eq!(online["summary"]["recall_at_100_precision"], 1.0);
    assert_eq!(online["summary"]["max_f1"], 1.0);

    let args = [
        &["loop-closure", images, "--mode", "kidnapped"][..],
        &common[..],
    ]
    .concat();
    let kidnapped = json_of(&raypath(&args));
    check_keys(&kidnapped, true);
    // Every frame finds its twin (in either direction), never itself.
    for c in kidnapped["candidates"].as_array().unwrap() {
        let (q, m) = (c["query"].as_u64().unwrap(), c["match"].as_u64().unwrap());
        assert_eq!(q % 6, m % 6);
        assert_ne!(q, m);
    }
    assert_eq!(kidnapped["summary"]["recall_at_100_precision"], 1.0);
}

#[test]
fn image_folder_default_method_without_ground_truth() {
    let dir = tempfile::tempdir().unwrap();
    write_folder(dir.path());
    let images = dir.path().join("images");
    let out = raypath(&[
        "loop-closure",
        images.to_str().unwrap(),
        "--exclusion-frames",
        "3",
        "--json",
    ]);
    let doc = json_of(&out);
    check_keys(&doc, false);
    assert_eq!(doc["method"], "ibuild");
    assert!(doc["ms_per_query"].as_f64().unwrap() >= 0.0);
}

#[test]
fn carmen_log_with_itself_as_ground_truth() {
    let Some(log) = require("carmen/corrected/aces-corrected.log.gz") else {
        return;
    };
    let log = log.to_str().unwrap();
    let out = raypath(&[
        "loop-closure",
        log,
        "--method",
        "polar",
        "--ground-truth",
        log,
        "--max-frames",
        "300",
        "--json",
    ]);
    let doc = json_of(&out);
    check_keys(&doc, true);
    assert_eq!(doc["frames"], 300);
    for key in [
        "recall_at_100_precision",
        "precision_at_100_recall",
        "max_f1",
    ] {
        let v = doc["summary"][key].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&v), "{key} = {v}");
    }
    // The human report names the log and the method.
    let text = raypath(&[
        "loop-closure",
        log,
        "--method",
        "polar",
        "--max-frames",
        "100",
    ]);
    assert!(text.status.success());
    let stdout = String::from_utf8_lossy(&text.stdout);
    assert!(
        stdout.contains("aces-corrected") && stdout.contains("polar"),
        "{stdout}"
    );
}

#[test]
fn bad_input_exits_2_with_file_and_place() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.log");
    let out = raypath(&["loop-closure", missing.to_str().unwrap(), "--json"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.log"));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(doc["error"].is_string());

    // Scan Context needs point clouds, not images.
    write_folder(dir.path());
    let images = dir.path().join("images");
    let out = raypath(&[
        "loop-closure",
        images.to_str().unwrap(),
        "--method",
        "scan-context",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("images") && err.contains("cannot describe"),
        "{err}"
    );

    // A pose file with the wrong number of columns names the line.
    let bad = dir.path().join("bad.txt");
    std::fs::write(&bad, "1 2 3\n").unwrap();
    let out = raypath(&[
        "loop-closure",
        images.to_str().unwrap(),
        "--ground-truth",
        bad.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("bad.txt: line 1"));
}

/// `--geometric-check` on a real log: every accepted loop's score is a support share in
/// [0.3, 1], and recall at 100 % precision is no lower than without the check.
#[test]
fn geometric_check_on_a_real_log() {
    let Some(log) = require("carmen/corrected/csail-corrected.log.gz") else {
        return;
    };
    let log = log.to_str().unwrap();
    let run = |extra: &[&str]| {
        let args = [
            &[
                "loop-closure",
                log,
                "--method",
                "polar",
                "--ground-truth",
                log,
                "--json",
            ][..],
            extra,
        ]
        .concat();
        json_of(&raypath(&args))
    };
    let (plain, checked) = (run(&[]), run(&["--geometric-check"]));
    check_keys(&checked, true);
    for l in checked["loops"].as_array().unwrap() {
        let s = l["score"].as_f64().unwrap();
        assert!((0.3..=1.0).contains(&s), "{l}");
    }
    let recall = |d: &serde_json::Value| d["summary"]["recall_at_100_precision"].as_f64().unwrap();
    assert!(recall(&checked) >= recall(&plain), "{checked} vs {plain}");
    // Images cannot be checked geometrically: exit 2 naming the reason.
    let dir = tempfile::tempdir().unwrap();
    write_folder(dir.path());
    let images = dir.path().join("images");
    let out = raypath(&[
        "loop-closure",
        images.to_str().unwrap(),
        "--method",
        "hog",
        "--geometric-check",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("geometric check"));
}

#[test]
fn scan_shapes_on_a_real_log() {
    let Some(log) = require("carmen/corrected/csail-corrected.log.gz") else {
        return;
    };
    let log = log.to_str().unwrap();
    let run = |extra: &[&str]| {
        let base = [
            "loop-closure",
            log,
            "--method",
            "ibuild",
            "--ibuild-score",
            "symmetric",
            "--ground-truth",
            log,
            "--json",
        ];
        json_of(&raypath(&[&base[..], extra].concat()))
    };
    let (raster, shapes) = (run(&[]), run(&["--scan-shapes"]));
    check_keys(&shapes, true);
    let recall = |d: &serde_json::Value| d["summary"]["recall_at_100_precision"].as_f64().unwrap();
    assert!(recall(&shapes) >= recall(&raster), "{shapes} vs {raster}");
    // Only IBuILD has a scan-shape route: exit 2 naming the flag.
    let out = raypath(&["loop-closure", log, "--method", "polar", "--scan-shapes"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--scan-shapes"));
}
