use nalgebra::{Matrix3x4, Point3};

use super::*;

/// A sequence of `n` sweeps 1 m apart held in memory; sweep `i` holds `i + 1` points at
/// x = i, and sweep 3 fails.
fn memory_sequence(n: usize) -> Result<SweepSequence> {
    let poses: Vec<Pose3> = (0..n)
        .map(|i| Pose3::from_xyz_rpy(i as f64, 0.0, 0.0, 0.0, 0.0, 0.0))
        .collect();
    SweepSequence::from_fn(
        "memory 00",
        SweepFormat::Kitti,
        (0..n).map(|i| i as f64 * 0.1).collect(),
        Some(poses.clone()),
        Some(poses),
        Box::new(|i| {
            if i == 3 {
                return Err("simulated failure".into());
            }
            Ok(PointCloud::from_points(vec![
                Point3::new(i as f32, 0.0, 0.0);
                i + 1
            ]))
        }),
    )
}

#[test]
fn in_memory_sequence_streams_sweeps_and_names_itself_in_errors() {
    let sequence = memory_sequence(5).unwrap();
    assert_eq!(sequence.len(), 5);
    assert_eq!(sequence.format, SweepFormat::Kitti);
    assert_eq!(sequence.require_reference().unwrap().len(), 5);
    let sweep = sequence.sweep(2).unwrap();
    assert_eq!(sweep.len(), 3);
    assert_eq!(sweep.points[0].x, 2.0);
    let failed = sequence.sweep(3).unwrap_err().to_string();
    assert!(
        failed.contains("memory 00")
            && failed.contains("sweep 3")
            && failed.contains("simulated failure"),
        "{failed}"
    );
    let past = sequence.sweep(5).unwrap_err().to_string();
    assert!(
        past.contains("memory 00") && past.contains("no sweep 5"),
        "{past}"
    );
    // Counting produces every sweep: the failing one is reported.
    assert!(sequence.count_points().is_err());
    let ok = memory_sequence(3).unwrap();
    assert_eq!(ok.count_points().unwrap(), 1 + 2 + 3);
}

#[test]
fn in_memory_sequence_checks_its_parts() {
    let pose = Pose3::identity();
    let sweeps = || -> SweepFn { Box::new(|_| Ok(PointCloud::from_points(Vec::new()))) };
    let nclt = |stamps: Vec<f64>, reference: Option<Vec<Pose3>>, odometry: Vec<Pose3>| {
        SweepSequence::from_fn(
            "d",
            SweepFormat::Nclt,
            stamps,
            reference,
            Some(odometry),
            sweeps(),
        )
    };
    assert!(nclt(vec![0.0, 1.0], None, vec![pose]).is_err());
    assert!(nclt(vec![0.0, 1.0], Some(vec![pose; 3]), vec![pose; 2]).is_err());
    let not_increasing = nclt(vec![1.0, 1.0], None, vec![pose; 2])
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        not_increasing.contains("not strictly increasing"),
        "{not_increasing}"
    );
    let sequence = nclt(vec![0.0, 1.0], None, vec![pose; 2]).unwrap();
    assert!(sequence.require_reference().is_err());
}

/// A KITTI sequence of three scans on disk, written with the crate's writers.
fn kitti_on_disk(dir: &Path, with_poses: bool) -> Vec<Pose3> {
    std::fs::create_dir_all(dir.join("velodyne")).unwrap();
    let world_from_velo: Vec<Pose3> = (0..3)
        .map(|i| Pose3::from_xyz_rpy(i as f64, 0.5 * i as f64, 0.0, 0.0, 0.0, 0.1 * i as f64))
        .collect();
    for i in 0..3 {
        let cloud = PointCloud::from_points(vec![Point3::new(i as f32, 1.0, 2.0); i + 2]);
        kitti::write_velodyne(&dir.join(format!("velodyne/{i:06}.bin")), &cloud).unwrap();
    }
    let cam0_from_velo = Pose3::from_matrix3x4(&Matrix3x4::new(
        0.0, -1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0,
    ));
    if with_poses {
        let cam = kitti::cam0_poses_from_velodyne(&world_from_velo, &cam0_from_velo);
        kitti::write_poses(&dir.join("poses.txt"), &cam).unwrap();
    }
    kitti::write_times(&dir.join("times.txt"), &[0.0, 0.1, 0.2]).unwrap();
    let p = "7.0 0 6.0 0 0 7.0 1.8 0 0 0 1 0";
    std::fs::write(
        dir.join("calib.txt"),
        format!("P0: {p}\nP1: {p}\nP2: {p}\nP3: {p}\nTr: 0 -1 0 0 0 0 -1 0 1 0 0 0\n"),
    )
    .unwrap();
    world_from_velo
}

#[test]
fn kitti_sequence_reads_scans_and_velodyne_poses() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = tmp.path().join("00");
    let truth = kitti_on_disk(&seq, true);
    let sequence = SweepSequence::open(&seq, &SweepOptions::default())
        .unwrap()
        .with_odometry_or_reference()
        .unwrap();
    assert_eq!(sequence.format, SweepFormat::Kitti);
    assert_eq!(sequence.stamps_secs, [0.0, 0.1, 0.2]);
    let gt = sequence.require_reference().unwrap();
    for (read, given) in gt.iter().zip(&truth) {
        assert!((read.translation() - given.translation()).norm() < 1e-6);
        assert!(read.rotation().angle_to(&given.rotation()) < 1e-6);
    }
    // KITTI has no odometry: the odometry track is the ground truth.
    assert_eq!(sequence.require_odometry().unwrap(), gt);
    assert_eq!(sequence.sweep(1).unwrap().len(), 3);
    assert_eq!(sequence.count_points().unwrap(), 2 + 3 + 4);
    assert!(
        sequence
            .sweep(3)
            .unwrap_err()
            .to_string()
            .contains("no sweep 3")
    );

    let bare = tmp.path().join("01");
    kitti_on_disk(&bare, false);
    let error = SweepSequence::open(&bare, &SweepOptions::default())
        .and_then(SweepSequence::with_odometry_or_reference)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        error.contains("01") && error.contains("poses.txt"),
        "{error}"
    );
}

#[test]
fn bags_without_odometry_fall_back_to_the_reference() {
    let reference: Vec<Pose3> = (0..2)
        .map(|i| Pose3::from_xyz_rpy(i as f64, 0.0, 0.0, 0.0, 0.0, 0.0))
        .collect();
    let bag = |reference: Option<Vec<Pose3>>| {
        SweepSequence::from_fn(
            "bag.mcap",
            SweepFormat::Bag,
            vec![0.0, 0.1],
            reference,
            None,
            Box::new(|_| Ok(PointCloud::from_points(Vec::new()))),
        )
        .unwrap()
    };
    let sequence = bag(Some(reference.clone()))
        .with_odometry_or_reference()
        .unwrap();
    assert_eq!(sequence.format, SweepFormat::Bag);
    assert_eq!(sequence.odometry.as_deref(), Some(reference.as_slice()));
    assert_eq!(sequence.reference.as_deref(), Some(reference.as_slice()));
    let error = bag(None)
        .with_odometry_or_reference()
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(error.starts_with("bag.mcap: "), "{error}");
    // NCLT records its odometry: the reference is no stand-in.
    let nclt = SweepSequence::from_fn(
        "session",
        SweepFormat::Nclt,
        vec![0.0, 0.1],
        Some(reference),
        None,
        Box::new(|_| Ok(PointCloud::from_points(Vec::new()))),
    )
    .unwrap()
    .with_odometry_or_reference()
    .err()
    .map(|e| e.to_string())
    .unwrap_or_default();
    assert!(nclt.contains("odometry_mu_100hz.csv"), "{nclt}");
}
