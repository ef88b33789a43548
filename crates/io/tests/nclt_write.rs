//! NCLT writers: every file read back by the NCLT readers gives what was written.

// Test helpers (outside #[test] functions) panic on setup failures too.
#![allow(clippy::unwrap_used)]

use std::io::Cursor;
use std::path::Path;

use nalgebra::{Matrix6, Point3};
use raypath_geometry::{PointCloud, Pose3};
use raypath_io::nclt::{
    self, CovarianceRecord, NcltLayout, NcltPose, NcltSession, encode_coordinate,
    encode_velodyne_sync, write_covariance_csv_to, write_pose_csv_to,
};

fn name() -> &'static Path {
    Path::new("test")
}

fn pose_distance(a: &Pose3, b: &Pose3) -> f64 {
    (a.translation() - b.translation()).norm() + a.rotation().angle_to(&b.rotation())
}

#[test]
fn coordinates_encode_within_the_representable_range_only() {
    assert_eq!(encode_coordinate(-100.0), Some(0));
    assert_eq!(encode_coordinate(0.0), Some(20000));
    assert_eq!(encode_coordinate(227.675), Some(u16::MAX));
    assert_eq!(encode_coordinate(227.68), None);
    assert_eq!(encode_coordinate(-100.003), None);
    assert_eq!(encode_coordinate(f64::NAN), None);
    for v in [-99.9977, -1.2345, 0.0024, 3.7, 80.0, 150.3] {
        let back = nclt::decode_coordinate(encode_coordinate(v).unwrap());
        assert!((back - v).abs() <= 0.0025 + 1e-9, "{v} → {back}");
    }
}

#[test]
fn revolutions_round_trip_within_the_quantization() {
    let mut cloud = PointCloud::from_points(vec![
        Point3::new(12.3456, -7.891, 1.2),
        Point3::new(f32::NAN, 0.0, 0.0),
        Point3::new(-60.0, 45.5, -0.4),
    ]);
    cloud.intensity = Some(vec![17.4, 0.0, 255.0]);
    cloud.label = Some(vec![3, 0, 31]);
    let bytes = encode_velodyne_sync(&cloud, name()).unwrap();
    assert_eq!(bytes.len(), 16);
    let back = nclt::parse_velodyne_sync(&bytes, "back").unwrap();
    assert_eq!(back.len(), 2);
    for (a, b) in [cloud.points[0], cloud.points[2]].iter().zip(&back.points) {
        assert!((a - b).abs().max() <= 0.0026, "{a:?} {b:?}");
    }
    assert_eq!(back.intensity, Some(vec![17.0, 255.0]));
    assert_eq!(back.label, Some(vec![3, 31]));
    // Points outside the u16 range are refused, naming the point and axis.
    cloud.points[2].z = -120.0;
    let err = encode_velodyne_sync(&cloud, name())
        .unwrap_err()
        .to_string();
    assert!(err.contains("point 2") && err.contains("z = -120"), "{err}");
    cloud.points[2].z = 0.0;
    cloud.label = Some(vec![3, 0, 300]);
    assert!(encode_velodyne_sync(&cloud, name()).is_err());
    cloud.label = None;
    cloud.intensity = Some(vec![0.0, 0.0, 256.0]);
    assert!(encode_velodyne_sync(&cloud, name()).is_err());
}

#[test]
fn poses_round_trip_through_the_ned_convention() {
    let poses: Vec<Pose3> = (0..40)
        .map(|i| {
            let t = i as f64 * 0.37;
            Pose3::from_xyz_rpy(
                50.0 * t.cos(),
                -20.0 * t,
                0.3 * t,
                0.02 * t.sin(),
                -0.03,
                2.9 * t,
            )
        })
        .collect();
    let rows: Vec<NcltPose> = poses
        .iter()
        .enumerate()
        .map(|(i, p)| NcltPose::from_world_from_body(1_326_030_975_726_043 + i as u64 * 100_000, p))
        .collect();
    let mut bytes = Vec::new();
    write_pose_csv_to(&mut bytes, &rows, name()).unwrap();
    let text = String::from_utf8(bytes.clone()).unwrap();
    assert!(text.starts_with("1326030975726043,"), "{text}");
    let table = nclt::parse_pose_csv(Cursor::new(bytes), "back").unwrap();
    assert_eq!(table.poses.len(), poses.len());
    for ((row, back), pose) in rows.iter().zip(&table.poses).zip(&poses) {
        assert_eq!(row.utime, back.utime);
        assert!(pose_distance(&back.world_from_body(), pose) < 1e-5);
        // NED: north is REP-103 y, down is −z.
        let t = pose.translation();
        assert!((back.xyz[0] - t.y).abs() < 1e-6 && (back.xyz[2] + t.z).abs() < 1e-6);
    }
    let bad = [NcltPose {
        utime: 0,
        xyz: [0.0, f64::NAN, 0.0],
        rpy: [0.0; 3],
    }];
    assert!(write_pose_csv_to(Vec::new(), &bad, name()).is_err());
}

#[test]
fn increments_use_the_stored_body_axes() {
    // Forward 1 m and a left turn (REP-103) is forward 1 m and a negative yaw with y right.
    let step = Pose3::from_xyz_rpy(1.0, 0.5, 0.0, 0.0, 0.0, 0.1);
    let row = NcltPose::from_increment(7, &step);
    assert!((row.xyz[0] - 1.0).abs() < 1e-12 && (row.xyz[1] + 0.5).abs() < 1e-12);
    assert!((row.rpy[2] + 0.1).abs() < 1e-12);
}

#[test]
fn covariances_round_trip() {
    let records: Vec<CovarianceRecord> = (0..5u64)
        .map(|i| {
            let a = Matrix6::from_fn(|r, c| ((r * 6 + c) as f64 + i as f64) * 1e-4);
            CovarianceRecord {
                utime: 1000 + i,
                matrix: a * a.transpose(),
            }
        })
        .collect();
    let mut bytes = Vec::new();
    write_covariance_csv_to(&mut bytes, &records, name()).unwrap();
    let table = nclt::parse_covariance(Cursor::new(bytes), "back").unwrap();
    for (a, b) in records.iter().zip(&table.records) {
        assert_eq!(a.utime, b.utime);
        assert!((a.matrix - b.matrix).abs().max() <= 1e-9 * a.matrix.abs().max());
    }
}

#[test]
fn a_written_session_is_discovered_and_summarized() {
    let dir = tempfile::tempdir().unwrap();
    let layout = NcltLayout::new(dir.path(), "2012-01-08");
    layout.create_dirs().unwrap();
    let utimes = [1_326_030_975_726_043u64, 1_326_030_975_826_043];
    for &utime in &utimes {
        let points = vec![Point3::new(1.0, 2.0, -1.0); 5];
        nclt::write_velodyne_sync(&layout.scan_path(utime), &PointCloud::from_points(points))
            .unwrap();
    }
    let rows: Vec<NcltPose> = utimes
        .iter()
        .map(|&u| NcltPose::from_world_from_body(u, &Pose3::identity()))
        .collect();
    nclt::write_pose_csv(&layout.ground_truth_path(), &rows).unwrap();
    nclt::write_pose_csv(&layout.odometry_path(), &rows).unwrap();
    nclt::write_pose_csv(&layout.relative_odometry_path(), &rows).unwrap();
    let cov: Vec<CovarianceRecord> = utimes
        .iter()
        .map(|&utime| CovarianceRecord {
            utime,
            matrix: Matrix6::identity() * 1e-4,
        })
        .collect();
    nclt::write_covariance_csv(&layout.relative_odometry_cov_path(), &cov).unwrap();
    nclt::write_covariance_csv(&layout.ground_truth_cov_path(), &cov).unwrap();
    let session = NcltSession::open(&layout.session_dir()).unwrap();
    assert_eq!(session.date.as_deref(), Some("2012-01-08"));
    assert_eq!(session.sync_files.len(), 2);
    assert_eq!(session.ground_truth().unwrap().poses.len(), 2);
    assert_eq!(session.odometry().unwrap().poses.len(), 2);
    assert_eq!(session.relative_odometry_cov().unwrap().records.len(), 2);
    assert_eq!(session.ground_truth_cov().unwrap().records.len(), 2);
    let summary = raypath_io::summarize(&layout.session_dir()).unwrap();
    assert_eq!(summary.format, "nclt");
    assert_eq!(summary.scans, Some(2));
    assert_eq!(summary.points, Some(10));
    assert_eq!(summary.poses, Some(2));
    assert_eq!(summary.odometry, Some(2));
    // A folder of sessions sums them.
    let later = NcltLayout::new(dir.path(), "2012-02-04");
    later.create_dirs().unwrap();
    nclt::write_pose_csv(&later.ground_truth_path(), &rows[..1]).unwrap();
    let summary = raypath_io::summarize(dir.path()).unwrap();
    assert_eq!(summary.format, "nclt");
    assert_eq!(summary.scans, Some(2));
    assert_eq!(summary.poses, Some(3));
    assert_eq!(
        summary.extra["sessions"],
        serde_json::json!(["2012-01-08", "2012-02-04"])
    );
}

#[test]
fn values_rounding_to_zero_have_no_sign() {
    let rows = [NcltPose {
        utime: 5,
        xyz: [-1e-9, -0.0, 2.0],
        rpy: [-1e-12, 0.0, -0.25],
    }];
    let mut bytes = Vec::new();
    write_pose_csv_to(&mut bytes, &rows, name()).unwrap();
    assert_eq!(
        String::from_utf8(bytes).unwrap(),
        "5,0.000000,0.000000,2.000000,0.000000000,0.000000000,-0.250000000\n"
    );
}
