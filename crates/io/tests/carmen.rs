//! CARMEN reader on small hand-written logs with known answers.

#![allow(clippy::unwrap_used)]

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
use std::io::{Cursor, Write};

use nalgebra::Point2;
use raypath_geometry::Range;
use raypath_io::carmen::{
    CarmenConfig, CarmenReader, FanConvention, LaserKind, LaserMessage, NoReturnRange, Record,
};
use raypath_io::{Error, Location};

const LOG: &str = "\
# CARMEN Logfile
# message formats defined: PARAM SYNC ODOM FLASER RLASER
PARAM robot_use_laser on nohost 0
PARAM robot_front_laser_max 30.5 1000.0 host 0.001
ODOM 1.0 2.0 0.5 0.3 -0.1 0.0 1000.25 host 0.25

FLASER 4 1.0 2.0 3.0 4.0 10.0 20.0 1.5707963267948966 10.5 20.5 1.6 1000.5 robby 0.5
RLASER 3 1.0 31.0 2.0 0.0 0.0 0.0 0.0 0.0 0.0 1000.6 robby 0.6
NEFF 27.6 0 pippo 0
ROBOTLASER1 0 -1.0 2.0 1.0 81.9 0.01 1 3 5.0 81.91 6.0 3 100 200 300 1.0 0.0 0.0 0.8 0.0 0.0 0.25 0.1 0.5 0.3 0.2 1000.75 robby 0.75
";

fn read(text: &str) -> Vec<Result<Record, Error>> {
    CarmenReader::new(Cursor::new(text.as_bytes().to_vec()), "mem.log").collect()
}

fn lasers(records: &[Result<Record, Error>]) -> Vec<&LaserMessage> {
    records
        .iter()
        .filter_map(|r| match r {
            Ok(Record::Laser(l)) => Some(l),
            _ => None,
        })
        .collect()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-12
}

#[test]
fn reads_every_message_type() {
    let records = read(LOG);
    assert_eq!(records.len(), 7, "{records:?}");
    let tags: Vec<&str> = records
        .iter()
        .map(|r| match r.as_ref().unwrap() {
            Record::Laser(l) => l.kind.tag(),
            Record::Odometry(_) => "ODOM",
            Record::Param { .. } => "PARAM",
            Record::Other { tag, .. } => tag.as_str(),
        })
        .collect();
    assert_eq!(
        tags,
        [
            "PARAM",
            "PARAM",
            "ODOM",
            "FLASER",
            "RLASER",
            "NEFF",
            "ROBOTLASER1"
        ]
    );
    match records[1].as_ref().unwrap() {
        Record::Param { name, value } => {
            assert_eq!(
                (name.as_str(), value.as_str()),
                ("robot_front_laser_max", "30.5")
            );
        }
        other => panic!("{other:?}"),
    }
    match records[2].as_ref().unwrap() {
        Record::Odometry(odom) => {
            assert_eq!(odom.world_from_robot.x(), 1.0);
            assert_eq!(odom.world_from_robot.theta(), 0.5);
            assert_eq!(odom.velocities.tv_mps, 0.3);
            assert_eq!(odom.velocities.rv_radps, -0.1);
            assert_eq!(odom.ipc_timestamp_secs, 1000.25);
            assert_eq!(odom.logger_timestamp_secs, 0.25);
            assert_eq!(odom.hostname, "host");
            assert_eq!(odom.line, 5);
        }
        other => panic!("{other:?}"),
    }
    match records[5].as_ref().unwrap() {
        Record::Other { tag, line, text } => {
            assert_eq!(
                (tag.as_str(), *line, text.as_str()),
                ("NEFF", 9, "27.6 0 pippo 0")
            );
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn front_laser_angles_poses_and_hits() {
    let records = read(LOG);
    let front = lasers(&records)[0];
    assert_eq!(front.kind, LaserKind::Front);
    assert_eq!(front.line, 7);
    // Four beams (even): 45° steps from −90°, the last at +45°.
    assert!(close(front.scan.angle_min_rad, -FRAC_PI_2));
    assert!(close(front.scan.angle_increment_rad, FRAC_PI_4));
    // No repeated value, so the PARAM's maximum range applies.
    assert_eq!(front.scan.max_range_m, 30.5);
    assert_eq!(front.scan.intensities, None);
    assert_eq!(front.world_from_laser.x(), 10.0);
    assert_eq!(front.world_from_robot.x(), 10.5);
    assert_eq!(front.velocities, None);
    assert_eq!(
        (front.ipc_timestamp_secs, front.logger_timestamp_secs),
        (1000.5, 0.5)
    );
    assert_eq!(front.hostname, "robby");
    // The laser at (10, 20) looks along +y: beam 0 (−90°) points along +x.
    let points: Vec<Point2<f64>> = front.scan.points(front.world_from_laser).collect();
    assert_eq!(points.len(), 4);
    assert!((points[0] - Point2::new(11.0, 20.0)).norm() < 1e-9);
    let diagonal = 2.0 / 2f64.sqrt();
    assert!((points[1] - Point2::new(10.0 + diagonal, 20.0 + diagonal)).norm() < 1e-9);
    assert!((points[2] - Point2::new(10.0, 23.0)).norm() < 1e-9);
}

#[test]
fn rear_laser_uses_its_own_defaults() {
    let records = read(LOG);
    let rear = lasers(&records)[1];
    assert_eq!(rear.kind, LaserKind::Rear);
    // Three beams (odd): −90°, 0°, +90°.
    assert!(close(rear.scan.angle_min_rad, -FRAC_PI_2));
    assert!(close(rear.scan.angle_increment_rad, FRAC_PI_2));
    // No PARAM for the rear laser: the default 50 m, so 31 m is a hit.
    assert_eq!(rear.scan.max_range_m, 50.0);
    assert_eq!(rear.scan.range(1), Range::Hit(31.0));
}

#[test]
fn robotlaser_states_its_geometry() {
    let records = read(LOG);
    let robot = lasers(&records)[2];
    assert_eq!(robot.kind, LaserKind::RobotLaser1);
    assert_eq!(
        (robot.scan.angle_min_rad, robot.scan.angle_increment_rad),
        (-1.0, 1.0)
    );
    assert_eq!(robot.scan.max_range_m, 81.9);
    assert_eq!(robot.scan.range(1), Range::NoReturn);
    assert_eq!(robot.scan.intensities, Some(vec![100.0, 200.0, 300.0]));
    assert_eq!(robot.world_from_laser.x(), 1.0);
    assert_eq!(robot.world_from_robot.x(), 0.8);
    let v = robot.velocities.unwrap();
    assert_eq!((v.tv_mps, v.rv_radps), (0.25, 0.1));
    let info = robot.robot_laser.unwrap();
    assert_eq!(info.fov_rad, 2.0);
    assert_eq!(info.remission_mode, 1);
    assert_eq!(
        (info.forward_safety_m, info.side_safety_m, info.turn_axis),
        (0.5, 0.3, 0.2)
    );
}

/// `scans` FLASER lines of 3 beams, the middle one `code`.
fn log_with_code(scans: usize, code: &str) -> String {
    let mut text = String::new();
    for i in 0..scans {
        text.push_str(&format!(
            "FLASER 3 1.{i} {code} 2.5 0 0 0 0 0 0 {i}.0 h {i}.0\n"
        ));
    }
    text
}

#[test]
fn infers_the_no_return_code_in_the_lookahead() {
    let text = log_with_code(30, "81.91");
    let reader = CarmenReader::new(Cursor::new(text.clone().into_bytes()), "code.log");
    let estimate = reader.no_return(LaserKind::Front).unwrap();
    assert_eq!((estimate.code_m, estimate.code_count), (81.91, 30));
    let records: Vec<_> = reader.collect();
    let scans = lasers(&records);
    assert_eq!(scans.len(), 30);
    for scan in scans {
        assert_eq!(scan.scan.max_range_m, 81.91);
        assert_eq!(scan.scan.range(1), Range::NoReturn);
        assert_eq!(scan.scan.points(scan.world_from_laser).count(), 2);
    }
    // A look-ahead shorter than the log sees too few repeats, but every record still comes.
    let config = CarmenConfig {
        lookahead_scans: 5,
        ..CarmenConfig::default()
    };
    let reader =
        CarmenReader::with_config(Cursor::new(text.into_bytes()), "code.log", config).unwrap();
    assert_eq!(reader.no_return(LaserKind::Front), None);
    let records: Vec<_> = reader.collect();
    let scans = lasers(&records);
    assert_eq!(scans.len(), 30);
    assert_eq!(scans[0].scan.max_range_m, 50.0);
    let times: Vec<f64> = scans.iter().map(|s| s.ipc_timestamp_secs).collect();
    assert_eq!(times, (0..30).map(f64::from).collect::<Vec<_>>());
}

#[test]
fn the_two_pass_inference_reads_files() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("code.log.gz");
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(log_with_code(2000, "50.00").as_bytes())
        .unwrap();
    std::fs::write(&path, gz.finish().unwrap()).unwrap();
    let reader = CarmenReader::open(&path).unwrap();
    let estimate = reader.no_return(LaserKind::Front).unwrap();
    assert_eq!((estimate.code_m, estimate.threshold_m), (50.0, 50.0));
    assert_eq!(reader.filter(|r| r.is_ok()).count(), 2000);
    let summary = raypath_io::summarize(&path).unwrap();
    assert_eq!((summary.scans, summary.beams), (Some(2000), Some(3)));
    assert_eq!(summary.extra["no_return_range_m"], 50.0);
    assert_eq!(summary.extra["messages"]["FLASER"], 2000);
    let span = summary.time_span.unwrap();
    assert_eq!((span.start, span.end), (0.0, 1999.0));
    // From poses at the origin facing +x, beam 0 (−90°) hits at y = −1.0 … −1.1999 and
    // beam 2 (+90°) at y = +2.5.
    let bbox = summary.bbox.unwrap();
    assert!(close(bbox.max[1], 2.5) && bbox.min[1] < -1.0, "{bbox:?}");
}

#[test]
fn configuration_overrides() {
    let text = "PARAM laser_front_laser_resolution 0.5 nohost 0\n\
                FLASER 4 1 2 3 4 0 0 0 0 0 0 1 h 1\n";
    // The PARAM's resolution: 0.5° steps, half-open about 0 (−1° … +0.5°).
    let records = read(text);
    let scan = &lasers(&records)[0].scan;
    assert!(close(scan.angle_increment_rad, 0.5f64.to_radians()));
    assert!(close(scan.angle_min_rad, -1f64.to_radians()));
    // Explicit overrides win over PARAMs.
    let config = CarmenConfig {
        fan: FanConvention::Closed,
        angle_increment_rad: Some(0.1),
        angle_min_rad: Some(-0.2),
        no_return: NoReturnRange::Fixed(3.0),
        ..CarmenConfig::default()
    };
    let reader =
        CarmenReader::with_config(Cursor::new(text.as_bytes().to_vec()), "o.log", config).unwrap();
    let records: Vec<_> = reader.collect();
    let scan = &lasers(&records)[0].scan;
    assert_eq!((scan.angle_min_rad, scan.angle_increment_rad), (-0.2, 0.1));
    assert_eq!(scan.max_range_m, 3.0);
    assert_eq!(scan.range(2), Range::NoReturn);
    // A flipped laser counts clockwise from the left; a field of view of 90° for 3 beams.
    let config = CarmenConfig {
        flipped: Some(true),
        fov_rad: Some(FRAC_PI_2),
        ..CarmenConfig::default()
    };
    let text = "FLASER 3 1 2 3 0 0 0 0 0 0 1 h 1\n";
    let reader =
        CarmenReader::with_config(Cursor::new(text.as_bytes().to_vec()), "f.log", config).unwrap();
    let records: Vec<_> = reader.collect();
    let scan = &lasers(&records)[0].scan;
    assert!(close(scan.angle_min_rad, FRAC_PI_4));
    assert!(close(scan.angle_increment_rad, -FRAC_PI_4));
    // Invalid overrides are refused with the name.
    let bad = CarmenConfig {
        fov_rad: Some(4.0 * PI),
        ..CarmenConfig::default()
    };
    let err = CarmenReader::with_config(Cursor::new(Vec::new()), "b.log", bad)
        .err()
        .unwrap();
    assert!(
        err.to_string().starts_with("b.log: invalid CARMEN"),
        "{err}"
    );
}

#[test]
fn malformed_lines_are_reported_and_skipped() {
    let text = "FLASER 3 1 2 0 0 0 0 0 0 1 h 1\n\
                ODOM 1 2 3 4 5 6 7 h 8\n\
                b\u{0}\n\
                PARAM robot_front_laser_max far nohost 0\n\
                FLASER 2 1 2 0 0 0 0 0 0 2 h 2\n";
    let mut bytes = text.as_bytes().to_vec();
    // Line 3 is not UTF-8.
    let bad = bytes.iter().position(|&b| b == 0).unwrap();
    bytes[bad] = 0xff;
    let records: Vec<_> = CarmenReader::new(Cursor::new(bytes), "bad.log").collect();
    assert_eq!(records.len(), 5, "{records:?}");
    let err = records[0].as_ref().unwrap_err();
    assert_eq!(err.location(), Location::Line(1));
    // Three readings announced, two written: the fields shift and the host lands where the
    // IPC timestamp belongs.
    assert_eq!(
        err.to_string(),
        "bad.log:1: FLASER message: ipc timestamp \"h\" is not a number"
    );
    assert!(matches!(records[1], Ok(Record::Odometry(_))));
    let err = records[2].as_ref().unwrap_err().to_string();
    assert!(err.starts_with("bad.log:3: invalid UTF-8"), "{err}");
    let err = records[3].as_ref().unwrap_err().to_string();
    assert_eq!(
        err,
        "bad.log:4: parameter robot_front_laser_max: \"far\" is not a positive number"
    );
    assert!(matches!(records[4], Ok(Record::Laser(_))));
}

#[test]
fn empty_and_comment_only_logs_have_no_records() {
    assert!(read("").is_empty());
    assert!(read("# nothing\n\n   \n#PARAM x\n").is_empty());
}

#[test]
fn front_lasers_skip_odometry_and_rear_lasers() {
    let reader = CarmenReader::new(Cursor::new(LOG.as_bytes().to_vec()), "mem.log");
    let kinds: Vec<&str> = reader
        .front_lasers()
        .map(|m| m.unwrap().kind.tag())
        .collect();
    // FLASER and ROBOTLASER1 are front lasers; RLASER, ODOM, PARAM and NEFF are skipped.
    assert_eq!(kinds, ["FLASER", "ROBOTLASER1"]);
}

/// `LOG` cut in the middle of its last line (the `ROBOTLASER1` message).
fn cut_log() -> String {
    let end = LOG.find("ROBOTLASER1").unwrap() + 40;
    LOG[..end].to_owned()
}

#[test]
fn a_log_cut_mid_line_keeps_its_complete_records_with_a_warning() {
    let mut reader = CarmenReader::new(Cursor::new(cut_log().into_bytes()), "cut.log");
    let records: Vec<_> = reader.by_ref().collect();
    assert_eq!(records.len(), 6, "{records:?}");
    assert!(records.iter().all(Result::is_ok));
    let warnings = reader.take_warnings();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].contains("cut.log: line 10") && warnings[0].contains("mid-line"),
        "{}",
        warnings[0]
    );
    // The same line with its line break is malformed, not cut: an error as before.
    let records = read(&(cut_log() + "\n"));
    assert!(matches!(
        records.last(),
        Some(Err(Error::Malformed {
            location: Location::Line(10),
            ..
        }))
    ));
}

#[test]
fn strict_reading_refuses_a_log_cut_mid_line() {
    let config = CarmenConfig {
        strict: true,
        ..CarmenConfig::default()
    };
    let mut reader =
        CarmenReader::with_config(Cursor::new(cut_log().into_bytes()), "cut.log", config).unwrap();
    let records: Vec<_> = reader.by_ref().collect();
    assert_eq!(records.len(), 7);
    assert!(records[..6].iter().all(Result::is_ok));
    assert!(records[6].is_err());
    assert!(reader.take_warnings().is_empty());
}

#[test]
fn a_complete_last_line_without_a_line_break_is_read() {
    let records = read(LOG.trim_end());
    assert_eq!(records.len(), 7);
    assert!(records.iter().all(Result::is_ok));
}
