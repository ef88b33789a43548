//! CARMEN reader on the real Radish logs under `$RAYPATH_DATA/carmen` (skipped when absent).

// Helpers of this test file unwrap too.
#![allow(clippy::unwrap_used)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use raypath_io::carmen::{CarmenReader, LaserKind, LaserMessage, Record};
use raypath_io::data::require;

/// What a pass over a log counts.
#[derive(Default)]
struct Counts {
    lasers: BTreeMap<LaserKind, u64>,
    beams: BTreeMap<usize, u64>,
    odometry: u64,
    remissions: u64,
}

fn count(path: &Path) -> Counts {
    let mut counts = Counts::default();
    for record in CarmenReader::open(path).unwrap() {
        match record.unwrap() {
            Record::Laser(laser) => {
                *counts.lasers.entry(laser.kind).or_default() += 1;
                *counts.beams.entry(laser.scan.len()).or_default() += 1;
                counts.remissions += u64::from(laser.scan.intensities.is_some());
            }
            Record::Odometry(_) => counts.odometry += 1,
            _ => {}
        }
    }
    counts
}

/// The README's table: log, scans, beams.
const CORRECTED: [(&str, u64, usize); 10] = [
    ("acapulco", 861, 181),
    ("aces", 440, 180),
    ("belgioioso", 395, 361),
    ("csail", 406, 361),
    ("fhw", 488, 180),
    ("freiburg-079", 4791, 360),
    ("freiburg-101", 292, 360),
    ("freiburg-campus", 2008, 360),
    ("infinite-corridor", 1941, 180),
    ("intel", 910, 180),
];

fn corrected(log: &str) -> Option<PathBuf> {
    require(format!("carmen/corrected/{log}-corrected.log.gz"))
}

#[test]
fn corrected_logs_have_the_published_scan_and_beam_counts() {
    for (log, scans, beams) in CORRECTED {
        let Some(path) = corrected(log) else { continue };
        let counts = count(&path);
        assert_eq!(
            counts.lasers,
            BTreeMap::from([(LaserKind::Front, scans)]),
            "{log}"
        );
        assert_eq!(counts.beams, BTreeMap::from([(beams, scans)]), "{log}");
    }
}

#[test]
fn raw_logs_have_the_published_counts() {
    let cases = [
        ("intel.clf.bz2", LaserKind::Front, 13631, 26915),
        ("fr079.clf.bz2", LaserKind::Front, 4934, 8951),
        ("mit-csail.clf.bz2", LaserKind::Front, 1988, 0),
        (
            "fr-clinic_robotlaser.clf.bz2",
            LaserKind::RobotLaser1,
            6917,
            0,
        ),
    ];
    for (file, kind, scans, odometry) in cases {
        let Some(path) = require(format!("carmen/raw/{file}")) else {
            continue;
        };
        let counts = count(&path);
        assert_eq!(counts.lasers, BTreeMap::from([(kind, scans)]), "{file}");
        assert_eq!(counts.odometry, odometry, "{file}");
        assert_eq!(counts.remissions, 0, "{file} has no remission values");
    }
}

#[test]
fn no_return_codes_match_the_readme() {
    let expected = [
        ("belgioioso", 81.91),
        ("csail", 81.91),
        ("freiburg-079", 81.91),
        ("freiburg-101", 81.91),
        ("freiburg-campus", 81.91),
        ("intel", 81.83),
        ("aces", 50.0),
    ];
    for (log, code) in expected {
        let Some(path) = corrected(log) else { continue };
        let estimate = CarmenReader::open(&path)
            .unwrap()
            .no_return(LaserKind::Front)
            .unwrap();
        assert_eq!(estimate.code_m, code, "{log}");
    }
    // The README's "top out near 51 m" logs: a cluster between 51.05 m and 51.16 m.
    for log in ["acapulco", "fhw", "infinite-corridor"] {
        let Some(path) = corrected(log) else { continue };
        let e = CarmenReader::open(&path)
            .unwrap()
            .no_return(LaserKind::Front)
            .unwrap();
        assert!((51.0..51.2).contains(&e.code_m), "{log}: {e:?}");
        assert!((51.0..=e.code_m).contains(&e.threshold_m), "{log}: {e:?}");
    }
    let raw = [
        ("intel.clf.bz2", LaserKind::Front, 81.83),
        ("fr079.clf.bz2", LaserKind::Front, 81.91),
        ("mit-csail.clf.bz2", LaserKind::Front, 81.91),
        (
            "fr-clinic_robotlaser.clf.bz2",
            LaserKind::RobotLaser1,
            81.91,
        ),
    ];
    for (file, kind, code) in raw {
        let Some(path) = require(format!("carmen/raw/{file}")) else {
            continue;
        };
        let estimate = CarmenReader::open(&path).unwrap().no_return(kind).unwrap();
        assert_eq!(estimate.code_m, code, "{file}");
    }
}

#[test]
fn lookahead_inference_agrees_with_the_two_pass_inference() {
    for (log, _, _) in CORRECTED {
        let Some(path) = corrected(log) else { continue };
        let two_pass = CarmenReader::open(&path).unwrap();
        let stream = raypath_io::source::open(&path).unwrap();
        let lookahead = CarmenReader::new(stream, &path);
        let (a, b) = (
            two_pass.no_return(LaserKind::Front).unwrap(),
            lookahead.no_return(LaserKind::Front).unwrap(),
        );
        assert_eq!(a.code_m, b.code_m, "{log}");
        assert_eq!(a.threshold_m, b.threshold_m, "{log}");
        // Same records either way.
        let first: Vec<_> = two_pass.take(50).map(Result::unwrap).collect();
        let second: Vec<_> = lookahead.take(50).map(Result::unwrap).collect();
        assert_eq!(first, second, "{log}");
    }
}

fn find_laser(path: &Path, pick: impl Fn(&LaserMessage) -> bool) -> Option<LaserMessage> {
    CarmenReader::open(path)
        .unwrap()
        .filter_map(|r| match r.unwrap() {
            Record::Laser(laser) if pick(&laser) => Some(laser),
            _ => None,
        })
        .next()
}

#[test]
fn intel_corrected_scan_is_the_raw_scan_with_the_same_logger_time() {
    let (Some(corrected), Some(raw)) = (corrected("intel"), require("carmen/raw/intel.clf.bz2"))
    else {
        return;
    };
    let c = find_laser(&corrected, |l| l.logger_timestamp_secs == 32.9068).unwrap();
    let r = find_laser(&raw, |l| l.logger_timestamp_secs == 32.906827).unwrap();
    assert_eq!(c.ipc_timestamp_secs, 32.9068);
    assert_eq!(c.scan.ranges, r.scan.ranges);
    assert_eq!(c.scan.len(), 180);
    // Same layout and no-return threshold in both files.
    assert_eq!(c.scan.angle_min_rad, r.scan.angle_min_rad);
    assert_eq!(c.scan.angle_increment_rad, r.scan.angle_increment_rad);
    assert_eq!((c.scan.max_range_m, r.scan.max_range_m), (81.83, 81.83));
    // The raw log's IPC time is UNIX time.
    assert!(r.ipc_timestamp_secs > 9.7e8);
}

#[test]
#[allow(clippy::approx_constant)] // the angles as printed in the log
fn robotlaser_angles_and_poses_come_from_the_line() {
    let Some(path) = require("carmen/raw/fr-clinic_robotlaser.clf.bz2") else {
        return;
    };
    let first = find_laser(&path, |_| true).unwrap();
    assert_eq!(first.kind, LaserKind::RobotLaser1);
    assert_eq!(first.scan.len(), 181);
    assert_eq!(first.scan.angle_min_rad, -1.570796);
    assert_eq!(first.scan.angle_increment_rad, 0.017453);
    // Stated 81.9 m, inferred cluster down to the 81.83 m error code.
    assert_eq!(first.scan.max_range_m, 81.83);
    assert_eq!(first.world_from_laser.x(), 0.22);
    assert_eq!(first.world_from_robot.x(), 0.0);
    assert_eq!(first.logger_timestamp_secs, -0.055208);
    assert_eq!(first.hostname, "zoidberg2");
    assert_eq!(first.velocities.unwrap().tv_mps, 0.0);
    assert_eq!(first.robot_laser.unwrap().stated_max_range_m, 81.9);
}

#[test]
fn summarize_intel_corrected() {
    let Some(path) = corrected("intel") else {
        return;
    };
    let summary = raypath_io::summarize(&path).unwrap();
    assert_eq!(summary.format, "carmen");
    assert_eq!(summary.scans, Some(910));
    assert_eq!(summary.beams, Some(180));
    assert_eq!((summary.beams_min, summary.beams_max), (None, None));
    assert_eq!(summary.poses, Some(910));
    assert_eq!(summary.odometry, Some(14541));
    assert_eq!(summary.extra["no_return_range_m"], 81.83);
    assert_eq!(summary.extra["no_return_code_m"], 81.83);
    assert_eq!(summary.extra["messages"]["NEFF"], 910);
    assert_eq!(summary.extra["params"], 2);
    let bbox = summary.bbox.unwrap();
    // The Intel lab is about 30 m × 30 m.
    let (w, h) = (bbox.max[0] - bbox.min[0], bbox.max[1] - bbox.min[1]);
    assert!(
        (20.0..60.0).contains(&w) && (20.0..60.0).contains(&h),
        "{bbox:?}"
    );
    assert_eq!((bbox.min[2], bbox.max[2]), (0.0, 0.0));
    let span = summary.time_span.unwrap();
    // Over the scans' IPC timestamps (the first scan is the one at 32.9068 s).
    assert_eq!((span.start, span.end), (32.9068, 2683.77));
}

#[test]
fn summarize_fr_clinic_counts_robotlaser_beams() {
    let Some(path) = require("carmen/raw/fr-clinic_robotlaser.clf.bz2") else {
        return;
    };
    let summary = raypath_io::summarize(&path).unwrap();
    assert_eq!(summary.scans, Some(6917));
    assert_eq!(summary.beams, Some(180));
    assert_eq!(
        (summary.beams_min, summary.beams_max),
        (Some(180), Some(181))
    );
    assert_eq!(summary.odometry, Some(0));
    assert_eq!(summary.extra["messages"]["ROBOTLASER1"], 6917);
}
