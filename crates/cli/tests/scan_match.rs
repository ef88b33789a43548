//! `raypath scan-match` and `raypath calibrate-intensity` end to end: the JSON contract, TUM
//! and map outputs on a synthetic log whose logged poses are the truth, Intel against its
//! corrected log, the LUT round trip, and bad input (exit 2 with file and place).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use std::f64::consts::PI;
use std::io::Write;
use std::path::{Path, PathBuf};

mod common;
use common::{json_of, raypath};

/// Range from `(x, y)` along `a` to the walls of [−3, 4] × [−2, 2.5] m or the pillar
/// [1, 1.5] × [0.8, 1.2] m.
fn range(x: f64, y: f64, a: f64) -> f64 {
    let (c, s) = (a.cos(), a.sin());
    let tx = if c > 1e-12 {
        (4.0 - x) / c
    } else if c < -1e-12 {
        (-3.0 - x) / c
    } else {
        f64::INFINITY
    };
    let ty = if s > 1e-12 {
        (2.5 - y) / s
    } else if s < -1e-12 {
        (-2.0 - y) / s
    } else {
        f64::INFINITY
    };
    let mut t = tx.min(ty);
    // Slab test against the pillar.
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for (o, d, lo, hi) in [(x, c, 1.0, 1.5), (y, s, 0.8, 1.2)] {
        if d.abs() < 1e-12 {
            if o < lo || o > hi {
                t1 = -1.0;
            }
        } else {
            let (a0, a1) = ((lo - o) / d, (hi - o) / d);
            t0 = t0.max(a0.min(a1));
            t1 = t1.min(a0.max(a1));
        }
    }
    if t1 >= t0 && t0 > 0.0 {
        t = t.min(t0);
    }
    t
}

/// A FLASER log of `n` scans (180 beams, 1° apart from −90°) along a gentle S-curve; the
/// logged poses are the truth.
fn synthetic_log(dir: &Path, n: usize) -> PathBuf {
    let path = dir.join("room.log");
    let mut file = std::fs::File::create(&path).unwrap();
    writeln!(file, "# synthetic room").unwrap();
    for k in 0..n {
        let t = k as f64 * 0.05;
        let (x, y, th) = (
            -1.5 + t,
            -0.5 + 0.3 * (t * 1.2).sin(),
            0.3 * (t * 0.8).sin(),
        );
        let ranges: Vec<String> = (0..180)
            .map(|i| format!("{:.3}", range(x, y, th - PI / 2.0 + i as f64 * PI / 180.0)))
            .collect();
        writeln!(
            file,
            "FLASER 180 {} {x} {y} {th} {x} {y} {th} {} host {}",
            ranges.join(" "),
            100.0 + k as f64 * 0.1,
            k as f64 * 0.1
        )
        .unwrap();
    }
    path
}

#[test]
fn json_contract_tum_and_map_on_a_synthetic_log() {
    let dir = tempfile::tempdir().unwrap();
    let log = synthetic_log(dir.path(), 50);
    let traj = dir.path().join("traj.txt");
    let prefix = dir.path().join("map");
    let out = raypath(&[
        "scan-match",
        log.to_str().unwrap(),
        "--json",
        "--out",
        traj.to_str().unwrap(),
        "--map",
        prefix.to_str().unwrap(),
        "--ground-truth",
        log.to_str().unwrap(),
    ]);
    let doc = json_of(&out);
    assert_eq!(doc["scans"], 50);
    assert_eq!(doc["beams"], 180);
    assert!(doc["time_s"].as_f64().unwrap() > 0.0);
    assert!(doc["scans_per_s"].as_f64().unwrap() > 0.0);
    assert_eq!(doc["errors"]["pairs"], 50);
    // Exact synthetic scans: consecutive motions are recovered to a few millimetres.
    let rel = doc["errors"]["relative"]["translation_m"]["mean"]
        .as_f64()
        .unwrap();
    assert!(rel < 0.01, "relative error {rel}");
    let ate = doc["errors"]["aligned"]["position_m"]["max"]
        .as_f64()
        .unwrap();
    assert!(ate < 0.05, "aligned error {ate}");
    // TUM: one line per scan, the IPC timestamp first, 8 fields, unit quaternions.
    let text = std::fs::read_to_string(&traj).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 50);
    let first: Vec<f64> = lines[0].split(' ').map(|v| v.parse().unwrap()).collect();
    assert_eq!(first.len(), 8);
    assert!((first[0] - 100.0).abs() < 1e-9);
    assert!(first[1].abs() < 1e-9 && first[2].abs() < 1e-9); // the map frame starts at scan 0
    let q: f64 = first[4..8].iter().map(|v| v * v).sum();
    assert!((q - 1.0).abs() < 1e-6);
    // PGM + YAML.
    let pgm = std::fs::read(prefix.with_extension("pgm")).unwrap();
    assert!(pgm.starts_with(b"P5\n"));
    assert!(pgm.contains(&0) && pgm.contains(&254));
    let yaml = std::fs::read_to_string(prefix.with_extension("yaml")).unwrap();
    assert!(yaml.contains("image: map.pgm") && yaml.contains("resolution: 0.05"));
}

#[test]
fn intel_against_its_corrected_log() {
    let (Some(raw), Some(corrected)) = (
        raypath_io::data::require("carmen/raw/intel.clf.bz2"),
        raypath_io::data::require("carmen/corrected/intel-corrected.log.gz"),
    ) else {
        return;
    };
    let out = raypath(&[
        "scan-match",
        raw.to_str().unwrap(),
        "--scans",
        "1500",
        "--odometry",
        "--ground-truth",
        corrected.to_str().unwrap(),
        "--json",
    ]);
    let doc = json_of(&out);
    assert_eq!(doc["scans"], 1500);
    let pairs = doc["errors"]["pairs"].as_u64().unwrap();
    assert!(pairs > 50, "{pairs} pairs");
    // Better than the odometry's 0.05 m per relation, far below the 0.22 m anchor.
    let rel = doc["errors"]["relative"]["translation_m"]["mean"]
        .as_f64()
        .unwrap();
    assert!(rel < 0.06, "relative error {rel}");
}

#[test]
fn calibrate_intensity_writes_a_lut_the_matcher_reads() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("samples.csv");
    let mut f = std::fs::File::create(&csv).unwrap();
    writeln!(f, "range_m,incidence_rad,intensity").unwrap();
    for i in 0..30 {
        for j in 0..15 {
            let (r, a) = (0.5 + 0.5 * i as f64, (j as f64 * 5.0).to_radians());
            writeln!(f, "{r},{a},{}", 800.0 * a.cos() / (1.0 + 0.1 * r)).unwrap();
        }
    }
    drop(f);
    let lut = dir.path().join("lut.json");
    let doc = json_of(&raypath(&[
        "calibrate-intensity",
        csv.to_str().unwrap(),
        "--out",
        lut.to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(doc["samples"], 450);
    assert_eq!(doc["model"], "lut");
    assert!(doc["max_sample_error"].as_f64().unwrap() < 0.01);
    // The log has no remissions: reflectivity matching is refused as bad input.
    let log = synthetic_log(dir.path(), 5);
    let out = raypath(&[
        "scan-match",
        log.to_str().unwrap(),
        "--mode",
        "reflectivity",
        "--lut",
        lut.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("remissions"));
}

#[test]
fn bad_input_exits_2_with_file_and_place() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("bad.log");
    std::fs::write(&log, "FLASER 3 1.0 2.0 x 0 0 0 0 0 0 1.0 host 1.0\n").unwrap();
    let out = raypath(&["scan-match", log.to_str().unwrap(), "--json"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.log") && err.contains('1'), "{err}");
    let csv = dir.path().join("bad.csv");
    std::fs::write(&csv, "1,0.1,5\n2,0.2,6\n3,zero,7\n").unwrap();
    let out = raypath(&[
        "calibrate-intensity",
        csv.to_str().unwrap(),
        "--out",
        dir.path().join("o.json").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("bad.csv:3"));
    let out = raypath(&["scan-match", log.to_str().unwrap(), "--mode", "nope"]);
    assert_eq!(out.status.code(), Some(2));
}

/// Ray cast in the room of [`range`] returning range, incidence angle and the hit point.
fn cast(x: f64, y: f64, a: f64) -> (f64, f64, [f64; 2]) {
    let r = range(x, y, a);
    let (px, py) = (x + r * a.cos(), y + r * a.sin());
    // The normal of the face hit: the coordinate that sits on a wall or pillar face.
    let on = |v: f64, w: f64| (v - w).abs() < 1e-6;
    let normal = if on(px, 4.0) || on(px, -3.0) || on(px, 1.0) || on(px, 1.5) {
        [1.0, 0.0]
    } else {
        [0.0, 1.0]
    };
    let alpha = (a.cos() * normal[0] + a.sin() * normal[1])
        .abs()
        .clamp(0.0, 1.0)
        .acos();
    (r, alpha, [px, py])
}

/// Reference intensity: a near-range drop and a range-dependent angular fall-off.
fn intensity(reflectivity: f64, r: f64, alpha: f64) -> f64 {
    let h = 4.0 * r * r / ((r * r + 1.0) * (r * r + 1.0));
    800.0 * reflectivity * h * alpha.cos().powf(1.0 + 0.1 * r)
}

#[test]
fn reflectivity_mode_on_a_log_with_remissions() {
    use raypath_geometry::{Pose2, Scan2};
    use raypath_io::carmen::{CarmenWriter, LaserKind, LaserMessage};

    let dir = tempfile::tempdir().unwrap();
    // Calibration samples of the reference surface (ρ = 1).
    let csv = dir.path().join("ref.csv");
    let mut f = std::fs::File::create(&csv).unwrap();
    for i in 0..60 {
        for j in 0..18 {
            let (r, a) = (0.2 + 0.12 * i as f64, (j as f64 * 5.0).to_radians());
            writeln!(f, "{r},{a},{}", intensity(1.0, r, a)).unwrap();
        }
    }
    drop(f);
    let lut = dir.path().join("lut.json");
    json_of(&raypath(&[
        "calibrate-intensity",
        csv.to_str().unwrap(),
        "--out",
        lut.to_str().unwrap(),
        "--json",
    ]));
    // A ROBOTLASER1 log with remissions; walls striped 0.3 / 0.9 every 0.5 m.
    let log = dir.path().join("refl.log");
    let mut w = CarmenWriter::create(&log).unwrap();
    for k in 0..40 {
        let t = k as f64 * 0.05;
        let pose = Pose2::new(
            -1.5 + t,
            -0.5 + 0.3 * (t * 1.2).sin(),
            0.3 * (t * 0.8).sin(),
        );
        let (mut ranges, mut remissions) = (Vec::new(), Vec::new());
        for i in 0..180 {
            let a = pose.theta() - PI / 2.0 + i as f64 * PI / 180.0;
            let (r, alpha, p) = cast(pose.x(), pose.y(), a);
            let rho = if ((p[0] + p[1] + 10.0) / 0.5).floor() as i64 % 2 == 0 {
                0.3
            } else {
                0.9
            };
            ranges.push(r);
            remissions.push(intensity(rho, r, alpha));
        }
        let scan = Scan2 {
            angle_min_rad: -PI / 2.0,
            angle_increment_rad: PI / 180.0,
            max_range_m: 30.0,
            ranges,
            intensities: Some(remissions),
        };
        w.laser(&LaserMessage {
            kind: LaserKind::RobotLaser1,
            scan,
            world_from_laser: pose,
            world_from_robot: pose,
            velocities: None,
            robot_laser: None,
            ipc_timestamp_secs: 10.0 + t,
            hostname: "sim".into(),
            logger_timestamp_secs: t,
            line: 0,
        })
        .unwrap();
    }
    w.finish().unwrap();
    let prefix = dir.path().join("m");
    let corrected = dir.path().join("corrected.log");
    for mode in ["reflectivity", "combined"] {
        let doc = json_of(&raypath(&[
            "scan-match",
            log.to_str().unwrap(),
            "--mode",
            mode,
            "--lut",
            lut.to_str().unwrap(),
            "--ground-truth",
            log.to_str().unwrap(),
            "--map",
            prefix.to_str().unwrap(),
            "--corrected-log",
            corrected.to_str().unwrap(),
            "--json",
        ]));
        assert_eq!(doc["mode"], mode);
        assert_eq!(doc["scans"], 40);
        let ate = doc["errors"]["aligned"]["position_m"]["max"]
            .as_f64()
            .unwrap();
        assert!(ate < 0.06, "{mode}: aligned error {ate}");
    }
    let png = std::fs::read(dir.path().join("m-reflectivity.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG\r\n\x1a\n") && png.len() > 100);
    // The corrected log reads back with the estimated poses (the first at the origin).
    let again = raypath(&[
        "scan-match",
        corrected.to_str().unwrap(),
        "--scans",
        "1",
        "--json",
    ]);
    assert!(again.status.success());
    let text = std::fs::read_to_string(&corrected).unwrap();
    assert_eq!(
        text.lines()
            .filter(|l| l.starts_with("ROBOTLASER1"))
            .count(),
        40
    );
}
