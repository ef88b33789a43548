//! `raypath map` end to end: a synthetic log and sequence written here, the real Intel log
//! when RAYPATH_DATA has it, the `.rpmap` round trip and bad inputs.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use raypath_io::data::require;
use raypath_sensor_models::export::{MapFile, MapKind, StoredStats};

mod common;
use common::raypath;

fn s(path: &Path) -> &str {
    path.to_str().expect("UTF-8 path")
}

/// Beams of the synthetic scans, and how many of them are no-returns (reading 10.0).
const BEAMS: usize = 180;
const NO_RETURNS_PER_SCAN: usize = 10;
const SCANS: usize = 3;

/// Three FLASER scans from (0, 0), (0.5, 0), (1, 0): every beam returns at 2 m except the
/// first ten, which read the stated maximum 10 m (no-returns).
fn synthetic_log(dir: &Path) -> PathBuf {
    let mut text = String::from("# synthetic\nPARAM robot_front_laser_max 10.0\n");
    for k in 0..SCANS {
        let x = 0.5 * k as f64;
        let ranges: Vec<String> = (0..BEAMS)
            .map(|i| {
                if i < NO_RETURNS_PER_SCAN {
                    "10.0"
                } else {
                    "2.0"
                }
                .to_owned()
            })
            .collect();
        writeln!(
            text,
            "FLASER {BEAMS} {} {x} 0.0 0.0 {x} 0.0 0.0 {t} host {t}",
            ranges.join(" "),
            t = 100.0 + k as f64
        )
        .expect("write to string");
    }
    let path = dir.join("tiny.log");
    std::fs::write(&path, text).expect("write log");
    path
}

fn map_json(args: &[&str]) -> serde_json::Value {
    let out = raypath(args);
    assert!(
        out.status.success(),
        "raypath {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("valid JSON")
}

#[test]
fn synthetic_log_decay_rate_map_and_round_trip() {
    let dir = tempfile::tempdir().expect("temp dir");
    let log = synthetic_log(dir.path());
    let prefix = dir.path().join("out/tiny");
    let json = map_json(&[
        "map",
        s(&log),
        "--model",
        "decay-rate",
        "--resolution",
        "0.1",
        "--out",
        s(&prefix),
        "--json",
    ]);
    let returns = SCANS * (BEAMS - NO_RETURNS_PER_SCAN);
    assert_eq!(json["rays"], SCANS * BEAMS);
    assert_eq!(json["no_returns_traced"], SCANS * NO_RETURNS_PER_SCAN);
    // Every return ends inside the grid (the grid covers all returns) and gets a hit.
    assert_eq!(json["hits"], returns);
    assert_eq!(json["model"], "decay-rate");
    assert_eq!(json["posterior"], false);
    // Returns at 2 m ahead and beside the robot: the extent spans x ∈ [0 − 2, 1 + 2] around
    // the poses and y ∈ [−2, 2] (the beams fan from −90° to +90°).
    let min = json["extent"]["min"].as_array().expect("min");
    let max = json["extent"]["max"].as_array().expect("max");
    let (x0, y0) = (min[0].as_f64().unwrap(), min[1].as_f64().unwrap());
    let (x1, y1) = (max[0].as_f64().unwrap(), max[1].as_f64().unwrap());
    assert!((-0.1..=0.0).contains(&x0), "x0 = {x0}");
    assert!(
        (y0 + 2.0).abs() < 0.11 && (y1 - 2.0).abs() < 0.11,
        "y {y0} {y1}"
    );
    assert!((x1 - 3.0).abs() < 0.11, "x1 = {x1}");
    assert!(json["rays_per_second"].as_f64().unwrap() > 0.0);

    // The binary map reads back with the kind, flag and statistics the summary reports.
    let rpmap = dir.path().join("out/tiny.rpmap");
    let file = MapFile::read_file(&rpmap).expect("readable map");
    assert_eq!(file.kind, MapKind::DecayRate);
    assert!(!file.posterior);
    assert!(file.mapping.include_no_returns);
    let StoredStats::Planar(stats) = &file.stats else {
        panic!("a CARMEN log gives a 2-D map");
    };
    assert_eq!(stats.summary().rays as usize, SCANS * BEAMS);
    let hits: u64 = stats.cells().iter().map(|c| u64::from(c.hits())).sum();
    assert_eq!(hits as usize, returns);
    assert_eq!(json["cells"], stats.cells().len());
    // Bytes → file → bytes is the identity.
    let bytes = std::fs::read(&rpmap).expect("read");
    assert_eq!(
        MapFile::from_bytes(&bytes, "tiny")
            .expect("parse")
            .to_bytes(),
        bytes
    );

    // ROS map: the PGM's size is the grid's, the YAML names it with the resolution.
    let [w, h] = stats.grid().dims();
    let pgm = std::fs::read(dir.path().join("out/tiny.pgm")).expect("pgm");
    let header = format!("P5\n# raypath map\n{w} {h}\n255\n");
    assert!(pgm.starts_with(header.as_bytes()));
    assert_eq!(pgm.len(), header.len() + w * h);
    let yaml = std::fs::read_to_string(dir.path().join("out/tiny.yaml")).expect("yaml");
    assert!(yaml.contains("image: tiny.pgm"), "{yaml}");
    assert!(yaml.contains("resolution: 0.1"), "{yaml}");
    assert!(dir.path().join("out/tiny.png").is_file());
}

#[test]
fn posterior_flag_and_models_are_recorded() {
    let dir = tempfile::tempdir().expect("temp dir");
    let log = synthetic_log(dir.path());
    for (model, kind, posterior) in [
        ("reflection", MapKind::Reflection, true),
        ("decay-rate", MapKind::DecayRate, true),
        ("log-odds", MapKind::LogOdds, false),
    ] {
        let prefix = dir.path().join(format!("{model}-{posterior}"));
        let mut args = vec![
            "map",
            s(&log),
            "--model",
            model,
            "--resolution",
            "0.2",
            "--out",
            s(&prefix),
        ];
        if posterior {
            args.push("--posterior");
        }
        let out = raypath(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains("rays: 540"), "{text}");
        let file = MapFile::read_file(&prefix.with_extension("rpmap")).expect("map");
        assert_eq!(file.kind, kind);
        assert_eq!(file.posterior, posterior);
    }
    // Skipping no-returns and subsampling rays change the counts as asked.
    let json = map_json(&[
        "map",
        s(&log),
        "--model",
        "reflection",
        "--resolution",
        "0.2",
        "--out",
        s(&dir.path().join("sub")),
        "--skip-no-returns",
        "--ray-step",
        "2",
        "--json",
    ]);
    assert_eq!(json["rays"], SCANS * BEAMS / 2);
    assert_eq!(json["no_returns_traced"], 0);
    assert_eq!(json["no_returns_skipped"], SCANS * NO_RETURNS_PER_SCAN / 2);
}

/// A KITTI-layout sequence without calib.txt: two sweeps of four points at 5 m, identity
/// and 1 m forward poses.
#[test]
fn synthetic_kitti_sequence_gives_a_3d_map() {
    let dir = tempfile::tempdir().expect("temp dir");
    let seq = dir.path().join("00");
    std::fs::create_dir_all(seq.join("velodyne")).expect("dirs");
    let points: [[f32; 4]; 4] = [
        [5.0, 0.0, 0.0, 0.5],
        [0.0, 5.0, 0.0, 0.5],
        [-5.0, 0.0, 0.0, 0.5],
        [0.0, -5.0, 1.0, 0.5],
    ];
    let bytes: Vec<u8> = points
        .iter()
        .flat_map(|p| p.iter().flat_map(|v| v.to_le_bytes()))
        .collect();
    for frame in 0..2 {
        std::fs::write(seq.join(format!("velodyne/{frame:06}.bin")), &bytes).expect("bin");
    }
    std::fs::write(
        seq.join("poses.txt"),
        "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n",
    )
    .expect("poses");
    let prefix = dir.path().join("kitti");
    let json = map_json(&[
        "map",
        s(&seq),
        "--model",
        "decay-rate",
        "--resolution",
        "0.5",
        "--out",
        s(&prefix),
        "--json",
    ]);
    assert_eq!(json["dimensions"], 3);
    assert_eq!(json["rays"], 8);
    assert_eq!(json["hits"], 8);
    let file = MapFile::read_file(&prefix.with_extension("rpmap")).expect("map");
    let StoredStats::Spatial(stats) = &file.stats else {
        panic!("a KITTI sequence gives a 3-D map");
    };
    let hits: u32 = stats.cells().iter().map(|c| c.hits()).sum();
    assert_eq!(hits, 8);
    // Sparse building stores the same map.
    let sparse_prefix = dir.path().join("kitti-sparse");
    map_json(&[
        "map",
        s(&seq),
        "--model",
        "decay-rate",
        "--resolution",
        "0.5",
        "--out",
        s(&sparse_prefix),
        "--sparse",
        "--json",
    ]);
    let sparse = MapFile::read_file(&sparse_prefix.with_extension("rpmap")).expect("map");
    assert_eq!(sparse.stats, file.stats);
}

#[test]
fn log_odds_posterior_is_rejected() {
    let dir = tempfile::tempdir().expect("temp dir");
    let log = synthetic_log(dir.path());
    let out = raypath(&[
        "map",
        s(&log),
        "--model",
        "log-odds",
        "--posterior",
        "--resolution",
        "0.1",
        "--out",
        s(&dir.path().join("x")),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--posterior") && err.contains("log-odds"),
        "{err}"
    );
    assert!(!dir.path().join("x.rpmap").exists());
}

#[test]
fn bad_inputs_exit_2_naming_file_and_place() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out_prefix = dir.path().join("out");
    let run = |input: &Path, extra: &[&str]| {
        let mut args = vec![
            "map",
            s(input),
            "--model",
            "decay-rate",
            "--resolution",
            "0.1",
            "--out",
            s(&out_prefix),
        ];
        args.extend_from_slice(extra);
        raypath(&args)
    };
    // A malformed number on line 3.
    let bad = dir.path().join("bad.log");
    std::fs::write(
        &bad,
        "# c\nFLASER 3 1.0 1.0 1.0 0 0 0 0 0 0 1.0 host 1.0\nFLASER 3 1.0 x 1.0 0 0 0 0 0 0 2.0 host 2.0\n",
    )
    .expect("write");
    let out = run(&bad, &[]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.log") && err.contains('3'), "{err}");

    // A log cut mid-line: the complete scans are mapped with a warning; --strict refuses.
    let whole = std::fs::read_to_string(synthetic_log(dir.path())).expect("read");
    let cut = dir.path().join("cut.log");
    std::fs::write(&cut, &whole[..whole.len() - 30]).expect("write");
    let out = run(&cut, &["--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("cut.log: line 5") && err.contains("mid-line"),
        "{err}"
    );
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(doc["rays"], (SCANS - 1) * BEAMS, "{doc}");
    let out = run(&cut, &["--strict"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("cut.log") && err.contains('5'), "{err}");

    // A log without laser messages.
    let empty = dir.path().join("empty.log");
    std::fs::write(&empty, "# nothing\n").expect("write");
    let out = run(&empty, &[]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no laser messages"));

    // A file that does not exist.
    let out = run(&dir.path().join("missing.log"), &[]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.log"));

    // Bad parameters, with the JSON error document.
    let log = synthetic_log(dir.path());
    let out = raypath(&[
        "map",
        s(&log),
        "--model",
        "reflection",
        "--resolution=-1",
        "--out",
        s(&out_prefix),
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON error");
    assert!(json["error"].as_str().unwrap().contains("--resolution"));
    let out = run(&log, &["--max-range", "0"]);
    assert_eq!(out.status.code(), Some(2));
    let out = run(&log, &["--ray-step", "0"]);
    assert_eq!(out.status.code(), Some(2));

    // A directory that is neither a KITTI sequence nor an NCLT session.
    let plain_dir = dir.path().join("plain");
    std::fs::create_dir_all(&plain_dir).expect("dir");
    let out = run(&plain_dir, &[]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("plain"));
}

#[test]
fn intel_corrected_log() {
    let Some(path) = require("carmen/corrected/intel-corrected.log.gz") else {
        return;
    };
    let dir = tempfile::tempdir().expect("temp dir");
    let prefix = dir.path().join("intel");
    let json = map_json(&[
        "map",
        s(&path),
        "--model",
        "decay-rate",
        "--posterior",
        "--resolution",
        "0.1",
        "--out",
        s(&prefix),
        "--json",
    ]);
    // 910 scans of 180 beams (the data README).
    assert_eq!(json["rays"], 910 * 180);
    let hits = json["hits"].as_u64().unwrap();
    let no_returns = json["no_returns_traced"].as_u64().unwrap();
    assert!(hits > 150_000, "hits {hits}");
    assert_eq!(
        hits + no_returns + json["sub_ignored"].as_u64().unwrap(),
        910 * 180
    );
    // The Intel lab is about 30 m × 30 m.
    let min = json["extent"]["min"].as_array().expect("min");
    let max = json["extent"]["max"].as_array().expect("max");
    for axis in 0..2 {
        let span = max[axis].as_f64().unwrap() - min[axis].as_f64().unwrap();
        assert!((25.0..45.0).contains(&span), "axis {axis}: {span} m");
    }
    let file = MapFile::read_file(&prefix.with_extension("rpmap")).expect("map");
    assert_eq!(file.kind, MapKind::DecayRate);
    assert!(file.posterior);
}
