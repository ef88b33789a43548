//! NCLT readers on synthetic files: decoding, frames, sessions, error places, no panic.

// Test helpers (outside #[test] functions) panic on setup failures too.
#![allow(clippy::unwrap_used)]

use std::io::Cursor;
use std::path::Path;

use nalgebra::Vector3;
use proptest::prelude::*;
use raypath_io::nclt::{self, HITS_MAGIC, HitsReader, NcltSession};
use raypath_io::{Format, Location};

/// One 8-byte record.
fn record(x: u16, y: u16, z: u16, intensity: u8, laser: u8) -> [u8; 8] {
    let mut r = [0u8; 8];
    r[0..2].copy_from_slice(&x.to_le_bytes());
    r[2..4].copy_from_slice(&y.to_le_bytes());
    r[4..6].copy_from_slice(&z.to_le_bytes());
    r[6] = intensity;
    r[7] = laser;
    r
}

fn sync_bytes() -> Vec<u8> {
    [
        record(20000, 20000, 20000, 0, 0),
        record(0, 65535, 20200, 255, 31),
        record(20400, 19800, 21000, 17, 5),
    ]
    .concat()
}

/// A packet stream: packets of `counts[i]` hits at utime 1000 + i.
fn hits_bytes(counts: &[u16]) -> Vec<u8> {
    let mut bytes = Vec::new();
    for (i, &n) in counts.iter().enumerate() {
        bytes.extend_from_slice(&HITS_MAGIC.to_le_bytes());
        bytes.extend_from_slice(&u32::from(n).to_le_bytes());
        bytes.extend_from_slice(&(1000 + i as u64).to_le_bytes());
        bytes.extend_from_slice(&[0xee; 4]);
        for k in 0..n {
            bytes.extend_from_slice(&record(
                20000 + k,
                20000,
                20000 - k,
                k as u8,
                (k % 32) as u8,
            ));
        }
    }
    bytes
}

#[test]
fn coordinates_decode_with_scale_and_offset() {
    assert_eq!(nclt::decode_coordinate(20000), 0.0);
    assert_eq!(nclt::decode_coordinate(0), -100.0);
    assert!((nclt::decode_coordinate(65535) - 227.675).abs() < 1e-9);
    let cloud = nclt::parse_velodyne_sync(&sync_bytes(), "1326030975726043.bin").unwrap();
    assert_eq!(cloud.len(), 3);
    assert_eq!(cloud.points[0], nalgebra::Point3::new(0.0, 0.0, 0.0));
    assert_eq!(cloud.points[1], nalgebra::Point3::new(-100.0, 227.675, 1.0));
    assert_eq!(cloud.points[2], nalgebra::Point3::new(2.0, -1.0, 5.0));
    assert_eq!(cloud.intensity.as_deref(), Some(&[0.0, 255.0, 17.0][..]));
    assert_eq!(cloud.label.as_deref(), Some(&[0, 31, 5][..]));
    let err = nclt::parse_velodyne_sync(&sync_bytes()[..20], "s.bin").unwrap_err();
    assert_eq!(err.location(), Location::Byte(16));
    // flu_from_frd negates y and z.
    let mut flu = cloud.clone();
    nclt::flu_from_frd(&mut flu);
    assert_eq!(flu.points[2], nalgebra::Point3::new(2.0, 1.0, -5.0));
    assert_eq!(
        nclt::utime_from_path(Path::new("a/velodyne_sync/1326030975726043.bin")),
        Some(1_326_030_975_726_043)
    );
}

#[test]
fn hits_stream_packet_by_packet() {
    let bytes = hits_bytes(&[3, 0, 384]);
    let packets: Vec<_> = HitsReader::new(&bytes[..], "h.bin", Some(bytes.len() as u64))
        .map(Result::unwrap)
        .collect();
    assert_eq!(packets.len(), 3);
    assert_eq!(packets[0].header.offset, 0);
    assert_eq!(packets[1].header.offset, 24 + 3 * 8);
    assert_eq!(packets[2].header.utime, 1002);
    assert_eq!(packets[2].points.len(), 384);
    assert_eq!(
        packets[0].points.points[2],
        nalgebra::Point3::new(0.01, 0.0, -0.01)
    );
    assert_eq!(packets[2].points.label.as_ref().unwrap()[33], 1);
    // Header-only scan agrees.
    let mut reader = HitsReader::new(&bytes[..], "h.bin", None);
    let mut counts = Vec::new();
    while let Some(header) = reader.next_header_skip_points().unwrap() {
        counts.push(header.num_hits);
    }
    assert_eq!(counts, [3, 0, 384]);
    // A bad magic number stops the stream with the header's offset.
    let mut bad = bytes.clone();
    bad[48] ^= 1;
    let results: Vec<_> = HitsReader::new(&bad[..], "h.bin", None).collect();
    assert_eq!(results.len(), 2);
    let err = results[1].as_ref().unwrap_err();
    assert_eq!(err.location(), Location::Byte(48));
    assert!(err.to_string().contains("magic"), "{err}");
    // A count beyond the data: refused from the header when the length is known …
    let mut long = hits_bytes(&[3]);
    long[8..12].copy_from_slice(&300u32.to_le_bytes());
    let err = HitsReader::new(&long[..], "h.bin", Some(long.len() as u64))
        .next()
        .unwrap()
        .unwrap_err();
    assert_eq!(err.location(), Location::Byte(0));
    // … and by the truncation otherwise; absurd counts are refused outright.
    assert!(
        HitsReader::new(&long[..], "h.bin", None)
            .next()
            .unwrap()
            .is_err()
    );
    long[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    let err = HitsReader::new(&long[..], "h.bin", None)
        .next()
        .unwrap()
        .unwrap_err();
    assert!(err.to_string().contains("hits"), "{err}");
    // A partial header.
    let err = HitsReader::new(&bytes[..10], "h.bin", None)
        .next()
        .unwrap()
        .unwrap_err();
    assert_eq!(err.location(), Location::Byte(0));
}

const GROUND_TRUTH: &str = "1326030975726043,1.0,2.0,3.0,0.0,0.0,0.0\n\
    1326030975736043,nan,nan,nan,nan,nan,nan\n\
    1326030975746043,4.0,5.0,-6.0,0.01,-0.02,1.5707963267948966\n";

fn covariance_line(utime: u64) -> String {
    let values: Vec<String> = (1..=21)
        .map(|v| format!("{}", f64::from(v) * 0.5))
        .collect();
    format!("{utime},{}\n", values.join(","))
}

#[test]
fn pose_csv_skips_and_counts_nan_rows() {
    let table =
        nclt::parse_pose_csv(Cursor::new(GROUND_TRUTH.as_bytes().to_vec()), "gt.csv").unwrap();
    assert_eq!(table.poses.len(), 2);
    assert_eq!(table.nan_rows, 1);
    assert_eq!(table.first_nan_line, Some(2));
    assert_eq!(table.poses[1].xyz, [4.0, 5.0, -6.0]);
    assert_eq!(table.poses[0].utime, 1_326_030_975_726_043);
    let span = table.time_span().unwrap();
    assert!((span.duration - 0.02).abs() < 1e-6);
    // ENU positions: (east, north, up) = (y, x, −z).
    let bbox = table.bbox().unwrap();
    assert_eq!(bbox.min, [2.0, 1.0, -3.0]);
    assert_eq!(bbox.max, [5.0, 4.0, 6.0]);
    // A header row is skipped.
    let with_header = format!("utime,x,y,z,roll,pitch,yaw\n{GROUND_TRUTH}");
    let table = nclt::parse_pose_csv(Cursor::new(with_header.into_bytes()), "gt.csv").unwrap();
    assert_eq!(table.poses.len(), 2);
    // Errors name the line.
    for (text, line) in [
        ("1,2,3\n", 1),
        ("1,2,3,4,5,6,7,8\n", 1),
        ("1,0,0,0,0,0,0\n-5,0,0,0,0,0,0\n", 2),
        ("1,0,0,inf,0,0,0\n", 1),
        ("1,0,0,0,0,0,0\n2,0,0,zero,0,0,0\n", 2),
    ] {
        let err =
            nclt::parse_pose_csv(Cursor::new(text.as_bytes().to_vec()), "gt.csv").unwrap_err();
        assert_eq!(err.location(), Location::Line(line), "{text:?}: {err}");
    }
}

#[test]
fn ned_poses_convert_to_rep103() {
    let table =
        nclt::parse_pose_csv(Cursor::new(GROUND_TRUTH.as_bytes().to_vec()), "gt.csv").unwrap();
    // Heading north (yaw 0): forward is ENU +y, left is ENU −x (west), up is up.
    let pose = table.poses[0].world_from_body();
    assert!((pose.translation() - Vector3::new(2.0, 1.0, -3.0)).norm() < 1e-12);
    let forward = pose.transform_vector(&Vector3::x());
    let left = pose.transform_vector(&Vector3::y());
    let up = pose.transform_vector(&Vector3::z());
    assert!((forward - Vector3::y()).norm() < 1e-12, "{forward:?}");
    assert!((left + Vector3::x()).norm() < 1e-12, "{left:?}");
    assert!((up - Vector3::z()).norm() < 1e-12, "{up:?}");
    // Yaw +90° in NED heads east: forward is ENU +x.
    let east = table.poses[1].world_from_body();
    let forward = east.transform_vector(&Vector3::x());
    assert!((forward - Vector3::x()).norm() < 0.03, "{forward:?}");
    // The reference implementation's pose: T_wo · stored pose.
    let reference = nclt::enu_from_ned() * table.poses[1].world_from_body_ned();
    assert!((reference.translation() - east.translation()).norm() < 1e-12);
}

#[test]
fn covariance_rows_are_symmetric() {
    let text = format!("{}{}", covariance_line(5), covariance_line(6));
    let table = nclt::parse_covariance(Cursor::new(text.into_bytes()), "cov.csv").unwrap();
    assert_eq!(table.records.len(), 2);
    let m = table.records[0].matrix;
    assert_eq!(m, m.transpose());
    // Upper triangle, row by row: (0,0)=v1 … (0,5)=v6, (1,1)=v7, (2,2)=v12, (5,5)=v21.
    assert_eq!((m[(0, 0)], m[(0, 5)], m[(5, 0)]), (0.5, 3.0, 3.0));
    assert_eq!((m[(1, 1)], m[(2, 2)], m[(5, 5)]), (3.5, 6.0, 10.5));
    let err = nclt::parse_covariance(Cursor::new(b"5,1,2,3\n".to_vec()), "cov.csv").unwrap_err();
    assert_eq!(err.location(), Location::Line(1));
}

/// Writes a session in the data set's layout under `root`.
fn write_session(root: &Path, date: &str) {
    let vel = root.join("velodyne_data").join(format!("{date}_vel"));
    std::fs::create_dir_all(vel.join("velodyne_sync")).unwrap();
    for utime in [1_326_030_975_900_000u64, 1_326_030_975_800_000] {
        std::fs::write(
            vel.join("velodyne_sync").join(format!("{utime}.bin")),
            sync_bytes(),
        )
        .unwrap();
    }
    std::fs::write(vel.join("velodyne_hits.bin"), hits_bytes(&[2, 2])).unwrap();
    std::fs::create_dir_all(root.join("ground_truth")).unwrap();
    std::fs::write(
        root.join("ground_truth")
            .join(format!("groundtruth_{date}.csv")),
        GROUND_TRUTH,
    )
    .unwrap();
    std::fs::create_dir_all(root.join("ground_truth_cov")).unwrap();
    std::fs::write(
        root.join("ground_truth_cov")
            .join(format!("cov_{date}.csv")),
        covariance_line(1_326_030_975_726_043),
    )
    .unwrap();
    let sen = root.join("sensor_data").join(format!("{date}_sen"));
    std::fs::create_dir_all(&sen).unwrap();
    std::fs::write(sen.join("odometry_mu_100hz.csv"), GROUND_TRUTH).unwrap();
    std::fs::write(sen.join("odometry_mu.csv"), GROUND_TRUTH).unwrap();
    std::fs::write(sen.join("odometry_cov.csv"), covariance_line(7)).unwrap();
}

#[test]
fn session_in_the_documented_layout() {
    let tmp = tempfile::tempdir().unwrap();
    write_session(tmp.path(), "2012-01-08");
    let session = NcltSession::open(tmp.path()).unwrap();
    assert_eq!(session.date.as_deref(), Some("2012-01-08"));
    let utimes: Vec<u64> = session.sync_files.iter().map(|f| f.utime).collect();
    assert_eq!(utimes, [1_326_030_975_800_000, 1_326_030_975_900_000]);
    assert!(session.hits_path.is_some() && session.ground_truth_cov_path.is_some());
    assert!(session.relative_odometry_path.is_some());
    assert!(session.relative_odometry_cov_path.is_some());
    let scans: Vec<_> = session.scans().map(Result::unwrap).collect();
    assert_eq!(scans.len(), 2);
    assert_eq!(scans[0].utime, 1_326_030_975_800_000);
    assert_eq!(scans[1].points.len(), 3);
    assert_eq!(session.count_points().unwrap(), 6);
    assert_eq!(session.ground_truth().unwrap().nan_rows, 1);
    assert_eq!(session.ground_truth_cov().unwrap().records.len(), 1);
    assert_eq!(session.odometry().unwrap().poses.len(), 2);
    assert_eq!(session.relative_odometry_cov().unwrap().records.len(), 1);
    let packets = session.hits().unwrap().unwrap().count();
    assert_eq!(packets, 2);

    assert_eq!(Format::detect(tmp.path()).unwrap(), Format::NcltSession);
    let summary = raypath_io::summarize(tmp.path()).unwrap();
    assert_eq!(summary.format, "nclt");
    assert_eq!(summary.scans, Some(2));
    assert_eq!(summary.points, Some(6));
    assert_eq!(summary.poses, Some(2));
    assert_eq!(summary.odometry, Some(2));
    assert_eq!(summary.extra["ground_truth_nan_rows_skipped"], 1);
    assert_eq!(summary.extra["session"], "2012-01-08");

    let vel = tmp.path().join("velodyne_data/2012-01-08_vel");
    let sync = vel.join("velodyne_sync/1326030975800000.bin");
    let s = raypath_io::summarize(&sync).unwrap();
    assert_eq!(s.format, "nclt-velodyne-sync");
    assert_eq!(s.points, Some(3));
    assert_eq!(s.labels, Some(vec![0, 5, 31]));
    let s = raypath_io::summarize(&vel.join("velodyne_hits.bin")).unwrap();
    assert_eq!(s.format, "nclt-velodyne-hits");
    assert_eq!((s.points, s.extra["packets"].as_u64()), (Some(4), Some(2)));
    let s =
        raypath_io::summarize(&tmp.path().join("ground_truth/groundtruth_2012-01-08.csv")).unwrap();
    assert_eq!(s.format, "nclt-groundtruth");
    assert_eq!(
        (s.poses, s.extra["nan_rows_skipped"].as_u64()),
        (Some(2), Some(1))
    );
    let s = raypath_io::summarize(&tmp.path().join("ground_truth_cov/cov_2012-01-08.csv")).unwrap();
    assert_eq!(s.format, "nclt-covariance");
    let s = raypath_io::summarize(
        &tmp.path()
            .join("sensor_data/2012-01-08_sen/odometry_mu_100hz.csv"),
    )
    .unwrap();
    assert_eq!((s.format.as_str(), s.odometry), ("nclt-odometry", Some(2)));

    // A second session in the same tree must be chosen by date.
    write_session(tmp.path(), "2012-01-15");
    assert!(NcltSession::open(tmp.path()).is_err());
    let other = NcltSession::open_date(tmp.path(), Some("2012-01-15")).unwrap();
    assert!(
        other
            .ground_truth_path
            .unwrap()
            .ends_with("groundtruth_2012-01-15.csv")
    );
}

#[test]
fn session_with_files_side_by_side() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    std::fs::create_dir_all(dir.join("velodyne_sync")).unwrap();
    std::fs::write(dir.join("velodyne_sync/1000.bin"), sync_bytes()).unwrap();
    std::fs::write(dir.join("groundtruth_2013-04-05.csv"), GROUND_TRUTH).unwrap();
    std::fs::write(dir.join("odometry_mu_100hz.csv"), GROUND_TRUTH).unwrap();
    let session = NcltSession::open(dir).unwrap();
    assert_eq!(session.date.as_deref(), Some("2013-04-05"));
    assert_eq!(session.sync_files.len(), 1);
    assert!(session.ground_truth_path.is_some() && session.odometry_path.is_some());
    assert!(session.hits_path.is_none());
    let empty = tempfile::tempdir().unwrap();
    assert!(NcltSession::open(empty.path()).is_err());
}

const ALPHABET: &[u8] = b"0123456789.-+e,\nnaifu ";

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1500))]

    #[test]
    fn binary_readers_never_panic(
        cut in prop_oneof![Just(1.0), 0.0..1.0f64],
        edits in prop::collection::vec((any::<usize>(), any::<u8>()), 0..6),
        known_len in any::<bool>(),
    ) {
        for source in [sync_bytes(), hits_bytes(&[3, 1, 5])] {
            let len = ((source.len() as f64) * cut) as usize;
            let mut bytes = source[..len].to_vec();
            for &(at, v) in &edits {
                if !bytes.is_empty() {
                    let i = at % bytes.len();
                    bytes[i] = v;
                }
            }
            if let Ok(cloud) = nclt::parse_velodyne_sync(&bytes, "s.bin") {
                prop_assert_eq!(cloud.len() * 8, bytes.len());
            }
            let len = known_len.then_some(bytes.len() as u64);
            for packet in HitsReader::new(&bytes[..], "h.bin", len).take(20) {
                if let Err(e) = packet {
                    prop_assert!(matches!(e.location(), Location::Byte(_)));
                }
            }
        }
    }

    #[test]
    fn csv_readers_never_panic(
        cut in prop_oneof![Just(1.0), 0.0..1.0f64],
        edits in prop::collection::vec((any::<usize>(), any::<usize>()), 0..5),
    ) {
        for source in [GROUND_TRUTH.to_owned(), covariance_line(3) + &covariance_line(4)] {
            let len = ((source.len() as f64) * cut) as usize;
            let mut bytes = source.as_bytes()[..len].to_vec();
            for &(at, c) in &edits {
                if !bytes.is_empty() {
                    let i = at % bytes.len();
                    bytes[i] = ALPHABET[c % ALPHABET.len()];
                }
            }
            if let Ok(table) = nclt::parse_pose_csv(Cursor::new(bytes.clone()), "gt.csv") {
                for pose in &table.poses {
                    prop_assert!(pose.world_from_body().is_finite());
                }
            }
            let _ = nclt::parse_covariance(Cursor::new(bytes), "cov.csv");
        }
    }
}
