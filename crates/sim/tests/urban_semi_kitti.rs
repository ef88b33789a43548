//! Semi-synthetic KITTI: a world around a given drive and pole map, read back with the KITTI
//! readers; the real sequences of RAYPATH_DATA/kitti-poles when installed.

// Test helpers (outside #[test] functions) panic on setup failures too.
#![allow(clippy::unwrap_used)]

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::Point2;
use raypath_geometry::Pose3;
use raypath_io::data::require;
use raypath_io::kitti::{self, KittiSequence};
use raypath_io::point_csv::PointCsv;
use raypath_io::sequence::{SweepOptions, SweepSequence};
use raypath_sim::no_progress;
use raypath_sim::semi_kitti::{
    SemiKittiConfig, SemiKittiDrive, SemiKittiSetConfig, generate, generate_semi_kitti,
};
use raypath_sim::urban::kinds::label;
use raypath_sim::urban::kitti_out::kitti_cam0_from_velo;

/// An L-shaped drive at 10 m/s (60 m east, a 90° left turn of radius 10 m, 40 m north) as
/// camera poses, with poles along both sides and one on the trajectory.
fn l_drive() -> SemiKittiConfig {
    let mut velo = Vec::new();
    let mut s = 0.0;
    let total = 60.0 + 10.0 * std::f64::consts::FRAC_PI_2 + 40.0;
    while s <= total {
        let (x, y, yaw) = if s < 60.0 {
            (s, 0.0, 0.0)
        } else if s < 60.0 + 10.0 * std::f64::consts::FRAC_PI_2 {
            let a = (s - 60.0) / 10.0;
            (60.0 + 10.0 * a.sin(), 10.0 - 10.0 * a.cos(), a)
        } else {
            let d = s - 60.0 - 10.0 * std::f64::consts::FRAC_PI_2;
            (70.0, 10.0 + d, std::f64::consts::FRAC_PI_2)
        };
        velo.push(Pose3::from_xyz_rpy(x, y, 0.02 * s, 0.0, -0.02, yaw));
        s += 1.0;
    }
    let poses = kitti::cam0_poses_from_velodyne(&velo, &kitti_cam0_from_velo());
    let times = (0..poses.len()).map(|i| i as f64 * 0.1).collect();
    let mut poles = vec![Point2::new(20.0, 0.3)]; // on the trajectory: left out
    for k in 0..6 {
        poles.push(Point2::new(5.0 + 10.0 * k as f64, -3.5));
        poles.push(Point2::new(8.0 + 10.0 * k as f64, 7.0));
    }
    poles.push(Point2::new(74.0, 30.0));
    let mut config = SemiKittiConfig::new(poses, times, poles);
    config.stride = 10;
    config.sequence = "09".into();
    config
}

#[test]
fn a_drive_is_simulated_along_the_given_poses_among_the_given_poles() {
    let config = l_drive();
    let dir = tempfile::tempdir().unwrap();
    let set = generate_semi_kitti(&config, 3, dir.path(), no_progress()).unwrap();
    assert_eq!(set.stats["poles_left_out_on_trajectory"], 1);
    let seq_dir = dir.path().join("sequences/09");
    let summary = raypath_io::summarize(&seq_dir).unwrap();
    assert_eq!(summary.scans, Some(config.frames().len() as u64));
    let sequence = KittiSequence::open(&seq_dir).unwrap();
    let poses = sequence.poses().unwrap();
    for (read, &frame) in poses.iter().zip(&config.frames()) {
        let given = config.poses[frame];
        assert!((read.translation() - given.translation()).norm() < 1e-6);
        assert!(read.rotation().angle_to(&given.rotation()) < 1e-7);
    }
    let times = sequence.times().unwrap();
    assert_eq!(times.len(), poses.len());
    assert!((times[1] - 1.0).abs() < 1e-12);
    // The placed poles are the given ones (ids = rows of the input map).
    let poles = PointCsv::read(&seq_dir.join("poles.csv")).unwrap();
    assert_eq!(poles.len(), config.poles.len() - 1);
    let by_id: BTreeMap<usize, &[f64]> = poles.rows().map(|r| (r[5] as usize, r)).collect();
    for (id, row) in &by_id {
        let p = config.poles[*id];
        assert!((row[0] - p.x).abs() < 1e-4 && (row[1] - p.y).abs() < 1e-4);
    }
    assert!(!by_id.contains_key(&0));
    // Pole returns lie on their poles; most poles are seen (sweeps and velodyne poses read
    // back through the source abstraction).
    let sweeps = SweepSequence::open(&seq_dir, &SweepOptions::default()).unwrap();
    let mut seen = BTreeMap::new();
    for (frame, pose) in sweeps.require_reference().unwrap().iter().enumerate() {
        let points = sweeps.sweep(frame).unwrap();
        let labels = std::fs::read(seq_dir.join(format!("labels/{frame:06}.label"))).unwrap();
        for (p, l) in points.points.iter().zip(labels.chunks_exact(4)) {
            let l = u32::from_le_bytes([l[0], l[1], l[2], l[3]]);
            let class = label::class(l);
            if class == label::POLE || class == label::TRUNK {
                let id = (label::instance(l) - 1) as usize;
                let row = by_id[&id];
                let w = pose.transform_point(&p.cast::<f64>());
                assert!((w.x - row[0]).hypot(w.y - row[1]) < row[2] / 2.0 * 1.06 + 0.1);
                *seen.entry(id).or_insert(0usize) += 1;
            }
            if class == label::ROAD && p.x.hypot(p.y) < 15.0 {
                // The road follows the drive 1.73 m below the sensor (slope 2 %).
                let w = pose.transform_point(&p.cast::<f64>());
                let expected = 0.02 * (pose.translation().xy() - Point2::origin().coords).norm();
                assert!(w.z - (pose.translation().z - 1.73) < 0.5 && w.z > expected - 2.5);
            }
        }
    }
    assert!(seen.len() >= 10, "{} poles seen", seen.len());
}

#[test]
fn semi_kitti_output_is_deterministic_and_checks_its_input() {
    let mut config = l_drive();
    config.firings = 360;
    config.max_scans = Some(3);
    let read = |dir: &Path| {
        let mut files = BTreeMap::new();
        for rel in [
            "poses/09.txt",
            "sequences/09/times.txt",
            "sequences/09/poles.csv",
            "sequences/09/calib.txt",
        ] {
            files.insert(rel.to_owned(), std::fs::read(dir.join(rel)).unwrap());
        }
        for frame in 0..3 {
            for rel in [
                format!("sequences/09/velodyne/{frame:06}.bin"),
                format!("sequences/09/labels/{frame:06}.label"),
            ] {
                files.insert(rel.clone(), std::fs::read(dir.join(rel)).unwrap());
            }
        }
        files
    };
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    generate_semi_kitti(&config, 4, a.path(), no_progress()).unwrap();
    generate_semi_kitti(&config, 4, b.path(), no_progress()).unwrap();
    assert_eq!(read(a.path()), read(b.path()));
    // Bad inputs.
    let mut bad = config.clone();
    bad.times.pop();
    assert!(generate_semi_kitti(&bad, 4, a.path(), no_progress()).is_err());
    let mut bad = config;
    bad.stride = 0;
    assert!(generate_semi_kitti(&bad, 4, a.path(), no_progress()).is_err());
}

#[test]
fn streamed_scans_equal_the_written_ones() {
    let mut config = l_drive();
    config.firings = 360;
    config.max_scans = Some(4);
    let dir = tempfile::tempdir().unwrap();
    generate_semi_kitti(&config, 5, dir.path(), no_progress()).unwrap();
    let drive = SemiKittiDrive::new(&config, 5).unwrap();
    assert_eq!(drive.len(), 4);
    assert_eq!(drive.frames, config.frames());
    let seq_dir = dir.path().join("sequences/09");
    // Poses and times: the written sequence reads back as the drive's velodyne poses.
    let sweeps = SweepSequence::open(&seq_dir, &SweepOptions::default()).unwrap();
    let velo = sweeps.require_reference().unwrap();
    assert_eq!(velo.len(), drive.world_from_velo.len());
    for (read, streamed) in velo.iter().zip(&drive.world_from_velo) {
        assert!((read.translation() - streamed.translation()).norm() < 1e-5);
    }
    assert_eq!(sweeps.stamps_secs.len(), drive.times_s.len());
    // The placed poles are the written ones.
    let written = PointCsv::read(&seq_dir.join("poles.csv")).unwrap();
    assert_eq!(written.len(), drive.poles.len());
    for (row, pole) in written.rows().zip(&drive.poles) {
        assert!((row[0] - pole.x).abs() < 1e-4 && (row[1] - pole.y).abs() < 1e-4);
        assert_eq!(row[5] as u32, pole.id);
    }
    assert_eq!(drive.poles_left_out, vec![0]);
    // Scans in reverse order (no hidden state): bit-equal points, intensities and labels.
    for frame in (0..4).rev() {
        let streamed = drive.scan(frame).unwrap();
        let file = sweeps.sweep(frame).unwrap();
        assert!(streamed.len() > 1000, "{} points", streamed.len());
        assert_eq!(streamed.points, file.points);
        assert_eq!(streamed.intensity, file.intensity);
        let labels: Vec<u32> = std::fs::read(seq_dir.join(format!("labels/{frame:06}.label")))
            .unwrap()
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        assert_eq!(streamed.label.as_deref(), Some(labels.as_slice()));
    }
    // Different scans differ; a scan past the end is an error, not a panic.
    assert_ne!(drive.scan(0).unwrap().points, drive.scan(1).unwrap().points);
    assert!(drive.scan(4).is_err());
}

#[test]
fn real_sequence_07_with_its_pole_map() {
    let Some(dir) = require("kitti-poles/07") else {
        return;
    };
    let real_poles = PointCsv::read(&dir.join("poles.csv")).unwrap();
    let config = SemiKittiSetConfig {
        stride: 400,
        firings: 720,
        ..SemiKittiSetConfig::quick()
    };
    let out = tempfile::tempdir().unwrap();
    let set = generate(&config, 1, out.path(), no_progress()).unwrap();
    assert_eq!(set.stats["frames_in_input"], 1101);
    assert_eq!(set.stats["poles_in_input"], real_poles.len());
    let seq_dir = out.path().join("sequences/07");
    let summary = raypath_io::summarize(&seq_dir).unwrap();
    assert_eq!(summary.scans, Some(3)); // frames 0, 400, 800
    assert_eq!(summary.poses, Some(3));
    let written = PointCsv::read(&seq_dir.join("poles.csv")).unwrap();
    let left_out = set.stats["poles_left_out_on_trajectory"].as_u64().unwrap() as usize;
    assert_eq!(written.len() + left_out, real_poles.len());
    for row in written.rows() {
        let real = real_poles.row(row[5] as usize).unwrap();
        assert!((row[0] - real[0]).abs() < 1e-4 && (row[1] - real[1]).abs() < 1e-4);
    }
    let real_poses = kitti::read_poses(&dir.join("poses.txt")).unwrap();
    let poses = KittiSequence::open(&seq_dir).unwrap().poses().unwrap();
    assert!((poses[2].translation() - real_poses[800].translation()).norm() < 1e-5);
}
