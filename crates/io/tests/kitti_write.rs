//! KITTI writers: every file read back by the KITTI readers gives what was written.

// Test helpers (outside #[test] functions) panic on setup failures too.
#![allow(clippy::unwrap_used)]

use std::io::Cursor;
use std::path::Path;

use nalgebra::{Matrix3x4, Point3};
use raypath_geometry::{PointCloud, Pose3};
use raypath_io::kitti::{
    self, KittiCalib, KittiLayout, KittiSequence, cam0_poses_from_velodyne, encode_velodyne,
    velodyne_poses_from_cam0, write_calib_to, write_poses_to, write_times_to,
};

fn name() -> &'static Path {
    Path::new("test")
}

/// The velodyne → cam0 transform of the KITTI odometry sequences 00–02 (calib.txt `Tr`).
fn kitti_tr() -> Pose3 {
    Pose3::from_matrix3x4(&Matrix3x4::new(
        4.276802385584e-04,
        -9.999672484946e-01,
        -8.084491683471e-03,
        -1.198459927713e-02,
        -7.210626507497e-03,
        8.081198471645e-03,
        -9.999413164504e-01,
        -5.403984729748e-02,
        9.999738645903e-01,
        4.859485810390e-04,
        -7.206933692422e-03,
        -2.921968648686e-01,
    ))
}

fn some_poses(n: usize) -> Vec<Pose3> {
    (0..n)
        .map(|i| {
            let t = i as f64;
            Pose3::from_xyz_rpy(
                10.0 * t.sin() * t,
                -3.0 * t,
                0.01 * t * t,
                0.01 * t.cos(),
                -0.02 * t.sin(),
                0.3 * t - 2.0,
            )
        })
        .collect()
}

fn pose_distance(a: &Pose3, b: &Pose3) -> f64 {
    (a.translation() - b.translation()).norm() + a.rotation().angle_to(&b.rotation())
}

#[test]
fn velodyne_bytes_round_trip_and_skip_missing_pixels() {
    let mut cloud = PointCloud::from_points(vec![
        Point3::new(1.5, -2.25, 0.125),
        Point3::new(f32::NAN, f32::NAN, f32::NAN),
        Point3::new(-80.0, 0.0, -1.73),
    ]);
    cloud.intensity = Some(vec![0.25, 0.0, 1.0]);
    let bytes = encode_velodyne(&cloud, name()).unwrap();
    assert_eq!(bytes.len(), 32);
    let back = kitti::parse_velodyne(&bytes, "back").unwrap();
    assert_eq!(back.points, vec![cloud.points[0], cloud.points[2]]);
    assert_eq!(back.intensity, Some(vec![0.25, 1.0]));
    // Without intensities the reflectance is 0.
    cloud.intensity = None;
    let back = kitti::parse_velodyne(&encode_velodyne(&cloud, name()).unwrap(), "b").unwrap();
    assert_eq!(back.intensity, Some(vec![0.0, 0.0]));
    // Bad input is refused with the point named.
    cloud.intensity = Some(vec![0.0, 0.0, f32::INFINITY]);
    let err = encode_velodyne(&cloud, name()).unwrap_err().to_string();
    assert!(err.contains("point 2"), "{err}");
    cloud.intensity = Some(vec![0.0]);
    assert!(encode_velodyne(&cloud, name()).is_err());
}

#[test]
fn poses_round_trip_with_fixed_formatting() {
    let mut poses = vec![Pose3::identity()];
    poses.extend(some_poses(50));
    let mut bytes = Vec::new();
    write_poses_to(&mut bytes, &poses, name()).unwrap();
    let text = String::from_utf8(bytes.clone()).unwrap();
    let first = text.lines().next().unwrap();
    assert_eq!(
        first,
        "1.000000000e+00 0.000000000e+00 0.000000000e+00 0.000000000e+00 \
         0.000000000e+00 1.000000000e+00 0.000000000e+00 0.000000000e+00 \
         0.000000000e+00 0.000000000e+00 1.000000000e+00 0.000000000e+00"
    );
    assert!(!text.contains("-0.000000000e+00"));
    let back = kitti::parse_poses(Cursor::new(bytes), "back").unwrap();
    assert_eq!(back.len(), poses.len());
    for (a, b) in poses.iter().zip(&back) {
        assert!(pose_distance(a, b) < 1e-7, "{a:?} {b:?}");
    }
    let bad = [Pose3::from_xyz_rpy(f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0)];
    assert!(write_poses_to(Vec::new(), &bad, name()).is_err());
}

#[test]
fn times_round_trip_and_must_not_decrease() {
    let times: Vec<f64> = (0..100).map(|i| i as f64 * 0.1036 + 1e-3).collect();
    let mut bytes = Vec::new();
    write_times_to(&mut bytes, &times, name()).unwrap();
    assert!(
        String::from_utf8(bytes.clone())
            .unwrap()
            .starts_with("1.000000000e-03\n")
    );
    let back = kitti::parse_times(Cursor::new(bytes), "back").unwrap();
    for (a, b) in times.iter().zip(&back) {
        assert!((a - b).abs() < 1e-12 * a.abs().max(1.0));
    }
    assert!(write_times_to(Vec::new(), &[1.0, 0.5], name()).is_err());
    assert!(write_times_to(Vec::new(), &[f64::INFINITY], name()).is_err());
}

#[test]
fn calibration_round_trips() {
    let p0 = Matrix3x4::new(
        718.856, 0.0, 607.1928, 0.0, 0.0, 718.856, 185.2157, 0.0, 0.0, 0.0, 1.0, 0.0,
    );
    let mut p1 = p0;
    p1[(0, 3)] = -386.1448;
    let mut calib = KittiCalib::odometry(&[p0, p1, p0, p0], &kitti_tr());
    calib
        .text
        .insert("calib_time".into(), "09-Jan-2012 13:57:47".into());
    let mut bytes = Vec::new();
    write_calib_to(&mut bytes, &calib, name()).unwrap();
    let text = String::from_utf8(bytes.clone()).unwrap();
    let keys: Vec<&str> = text.lines().map(|l| l.split(':').next().unwrap()).collect();
    assert_eq!(keys, ["P0", "P1", "P2", "P3", "Tr", "calib_time"]);
    let back = kitti::parse_calib(Cursor::new(bytes), "back").unwrap();
    assert_eq!(back.text, calib.text);
    assert_eq!(back.projection(1).unwrap(), p1);
    let tr = back.cam0_from_velo().unwrap();
    assert!(pose_distance(&tr, &kitti_tr()) < 1e-11);
    // Entries that would not read back are refused.
    let mut bad = calib.clone();
    bad.numeric.insert("Tr".into(), vec![1.0, 2.0]);
    assert!(write_calib_to(Vec::new(), &bad, name()).is_err());
    let mut bad = calib;
    bad.text.insert("note".into(), "1 2 3".into());
    assert!(write_calib_to(Vec::new(), &bad, name()).is_err());
}

#[test]
fn camera_poses_start_at_identity_and_invert_exactly() {
    let tr = kitti_tr();
    let world_from_velo = some_poses(20);
    // Express the trajectory in the frame of the first velodyne pose.
    let first_inv = world_from_velo[0].inverse();
    let velo0_from_velo: Vec<Pose3> = world_from_velo.iter().map(|p| first_inv * *p).collect();
    let cam = cam0_poses_from_velodyne(&velo0_from_velo, &tr);
    assert!(pose_distance(&cam[0], &Pose3::identity()) < 1e-12);
    let back = velodyne_poses_from_cam0(&cam, &tr);
    for (a, b) in velo0_from_velo.iter().zip(&back) {
        assert!(pose_distance(a, b) < 1e-9);
    }
    // The reader's velodyne_poses gives the same trajectory in camera-0 axes.
    let placed = kitti::velodyne_poses(&cam, &tr);
    for (a, b) in placed.iter().zip(&back) {
        assert!(pose_distance(&(tr * *b), a) < 1e-9);
    }
}

#[test]
fn a_written_sequence_is_discovered_and_summarized() {
    let dir = tempfile::tempdir().unwrap();
    let layout = KittiLayout::new(dir.path().join("dataset"), "07");
    layout.create_dirs().unwrap();
    let poses = some_poses(3);
    let mut total = 0;
    for frame in 0..3u64 {
        let points = (0..10 + frame)
            .map(|i| Point3::new(i as f32, 1.0, -1.0))
            .collect();
        total += kitti::write_velodyne(&layout.scan_path(frame), &PointCloud::from_points(points))
            .unwrap();
    }
    assert_eq!(total, 33);
    kitti::write_poses(&layout.poses_path(), &poses).unwrap();
    kitti::write_times(&layout.times_path(), &[0.0, 0.1, 0.2]).unwrap();
    kitti::write_calib(
        &layout.calib_path(),
        &KittiCalib::odometry(&[Matrix3x4::identity()], &kitti_tr()),
    )
    .unwrap();
    let sequence = KittiSequence::open(&layout.sequence_dir()).unwrap();
    assert_eq!(sequence.name.as_deref(), Some("07"));
    assert_eq!(sequence.scan_files.len(), 3);
    assert_eq!(
        sequence.poses_path.as_deref(),
        Some(layout.poses_path().as_path())
    );
    assert_eq!(sequence.scan(2).unwrap().unwrap().len(), 12);
    let summary = raypath_io::summarize(&layout.sequence_dir()).unwrap();
    assert_eq!(summary.format, "kitti");
    assert_eq!(summary.scans, Some(3));
    assert_eq!(summary.points, Some(33));
    assert_eq!(summary.poses, Some(3));
    assert_eq!(summary.extra["times"], 3);
    // The benchmark root sums its sequences.
    let second = KittiLayout::new(dir.path().join("dataset"), "08");
    second.create_dirs().unwrap();
    kitti::write_velodyne(
        &second.scan_path(0),
        &PointCloud::from_points(vec![Point3::origin()]),
    )
    .unwrap();
    kitti::write_poses(&second.poses_path(), &poses[..1]).unwrap();
    let root = dir.path().join("dataset");
    assert_eq!(
        raypath_io::Format::detect(&root).unwrap(),
        raypath_io::Format::KittiSequence
    );
    let summary = raypath_io::summarize(&root).unwrap();
    assert_eq!(summary.scans, Some(4));
    assert_eq!(summary.points, Some(34));
    assert_eq!(summary.poses, Some(4));
    assert_eq!(summary.extra["times"], 3);
    assert_eq!(summary.extra["sequences"], serde_json::json!(["07", "08"]));
}
