//! Urban outputs: KITTI- and NCLT-style sets read back with the raypath-io readers, frames
//! and pole ground truth consistent with the scans, determinism whatever the thread count.

// Test helpers (outside #[test] functions) panic on setup failures too.
#![allow(clippy::unwrap_used)]

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Point2, Point3, Unit};
use raypath_io::nclt::{self, NcltSession};
use raypath_io::point_csv::PointCsv;
use raypath_io::sequence::{SweepOptions, SweepSequence};
use raypath_sim::lidar3::Lidar3;
use raypath_sim::no_progress;
use raypath_sim::urban::kinds::label;
use raypath_sim::urban::sessions::session_worlds;
use raypath_sim::urban::{
    PoleKind, UrbanKittiConfig, UrbanNcltConfig, generate_kitti, generate_layout, generate_nclt,
};

fn tiny_kitti(scans: usize, firings: usize) -> UrbanKittiConfig {
    let mut config = UrbanKittiConfig::quick();
    config.streets.blocks_x = 2;
    config.streets.blocks_y = 2;
    config.scans = scans;
    config.firings = firings;
    config
}

fn tiny_nclt(scans: usize, firings: usize) -> UrbanNcltConfig {
    let mut config = UrbanNcltConfig::quick();
    config.streets.blocks_x = 2;
    config.streets.blocks_y = 2;
    config.scans_per_session = scans;
    config.firings = firings;
    config
}

/// All files under `dir` with their bytes, by relative path.
fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                let rel = path.strip_prefix(dir).unwrap().display().to_string();
                out.insert(rel, std::fs::read(&path).unwrap());
            }
        }
    }
    out
}

#[test]
fn kitti_style_sequence_reads_back_with_consistent_frames_and_poles() {
    let mut config = tiny_kitti(4, raypath_sim::lidar3::HDL64E_FIRINGS_10HZ);
    config.drive.body_motion_deg = 0.0; // a level first pose: the world z is up
    let dir = tempfile::tempdir().unwrap();
    let set = generate_kitti(&config, 21, dir.path(), no_progress()).unwrap();
    let seq_dir = dir.path().join("sequences").join("00");
    // raypath info on the sequence directory.
    let summary = raypath_io::summarize(&seq_dir).unwrap();
    assert_eq!(summary.format, "kitti");
    assert_eq!(summary.scans, Some(4));
    assert_eq!(summary.poses, Some(4));
    assert_eq!(summary.extra["times"], 4);
    assert_eq!(set.stats["scans"]["points"], summary.points.unwrap());
    assert!(set.files.iter().any(|f| f.ends_with("poses/00.txt")));
    // raypath info on the set's directory (the benchmark root).
    let root = raypath_io::summarize(dir.path()).unwrap();
    assert_eq!((root.scans, root.poses), (Some(4), Some(4)));
    // The sweeps with their velodyne poses (poses.txt through the Tr of calib.txt).
    let sequence = SweepSequence::open(&seq_dir, &SweepOptions::default()).unwrap();
    let world_from_velo = sequence.require_reference().unwrap().to_vec();
    assert!(
        world_from_velo[0].translation().norm() < 1e-9,
        "first pose is the identity"
    );
    assert!((sequence.stamps_secs[3] - 0.3).abs() < 1e-12);
    // Pole ground truth.
    let poles = PointCsv::read(&seq_dir.join("poles.csv")).unwrap();
    assert_eq!(poles.columns, ["x", "y", "w", "h", "kind", "id"]);
    let by_id: BTreeMap<u32, &[f64]> = poles.rows().map(|r| (r[5] as u32, r)).collect();
    let mut pole_points: BTreeMap<u32, usize> = BTreeMap::new();
    let mut ground = (0usize, 0usize);
    for (frame, pose) in world_from_velo.iter().enumerate() {
        let points = sequence.sweep(frame).unwrap();
        let labels_path = seq_dir.join("labels").join(format!("{frame:06}.label"));
        let labels: Vec<u32> = std::fs::read(labels_path)
            .unwrap()
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        assert_eq!(labels.len(), points.len());
        let intensity = points.intensity.as_ref().unwrap();
        assert!(intensity.iter().all(|v| (0.0..=1.0).contains(v)));
        for (i, p) in points.points.iter().enumerate() {
            let w = pose.transform_point(&p.cast::<f64>());
            let class = label::class(labels[i]);
            let local = p.x.hypot(p.y);
            if class == label::ROAD && local < 20.0 {
                ground.0 += 1;
                ground.1 += usize::from((w.z + 1.73).abs() < 0.08);
            }
            if class == label::POLE || class == label::TRUNK {
                let id = label::instance(labels[i]) - 1;
                let row = by_id[&id];
                let axis = (w.x - row[0]).hypot(w.y - row[1]);
                // Within the prism (vertex radius ≤ 1.06 r) plus range noise (σ = 2 cm).
                assert!(
                    axis < row[2] / 2.0 * 1.06 + 0.1,
                    "pole {id}: {axis} m from its axis"
                );
                *pole_points.entry(id).or_default() += 1;
            }
        }
    }
    assert!(ground.1 as f64 > 0.99 * ground.0 as f64, "{ground:?}");
    // Poles near the drive have returns.
    let positions: Vec<Point2<f64>> = world_from_velo
        .iter()
        .map(|p| Point2::new(p.translation().x, p.translation().y))
        .collect();
    let near: Vec<u32> = poles
        .rows()
        .filter(|r| {
            r[3] > 1.5
                && positions
                    .iter()
                    .any(|p| (p - Point2::new(r[0], r[1])).norm() < 20.0)
        })
        .map(|r| r[5] as u32)
        .collect();
    let seen = near
        .iter()
        .filter(|id| pole_points.contains_key(id))
        .count();
    eprintln!(
        "{seen} of {} poles near the drive have returns; ground {ground:?}",
        near.len()
    );
    assert!(
        !near.is_empty() && seen as f64 >= 0.7 * near.len() as f64,
        "{seen} of {}",
        near.len()
    );
}

#[test]
fn every_visible_pole_has_returns_at_its_position() {
    let layout = generate_layout(&tiny_kitti(1, 1).streets, 33).unwrap();
    let (world, _) = session_worlds(&layout, &[9], &Default::default(), 33).remove(0);
    let scene = world.build_scene().unwrap();
    let lidar = Lidar3::hdl64e();
    let mut checked = 0;
    // Sensor poses in the middle of a few streets.
    let grid = &layout.grid;
    let sensors = [
        Point3::new(grid.xs[1] - 1.5, (grid.ys[0] + grid.ys[1]) / 2.0, 1.73),
        Point3::new((grid.xs[1] + grid.xs[2]) / 2.0, grid.ys[1] + 1.5, 1.73),
        Point3::new(grid.xs[0] + 1.5, (grid.ys[1] + grid.ys[2]) / 2.0, 1.73),
    ];
    for (k, sensor) in sensors.iter().enumerate() {
        let pose = raypath_geometry::Pose3::from_parts(sensor.coords, Default::default());
        let scan = lidar.scan(&scene, &pose, 1, k as u64).unwrap();
        let labels = scan.cloud.label.as_ref().unwrap();
        for object in &world.poles {
            let p = object.pole;
            let center = Point3::new(p.x, p.y, (p.height_m * 0.5).min(1.5) + p.base_z);
            let distance = (center - sensor).norm();
            if distance > 15.0 || p.kind == PoleKind::Bollard && distance < 4.0 {
                continue;
            }
            // Visible: the straight line to the pole meets the pole first.
            let dir = Unit::new_normalize(center - sensor);
            let Some(hit) = scene.cast(sensor, &dir, 100.0) else {
                continue;
            };
            if label::instance(scene.surface(hit.surface).unwrap().label) != p.id + 1 {
                continue;
            }
            checked += 1;
            let returns = scan
                .cloud
                .points
                .iter()
                .zip(labels)
                .filter(|(q, l)| {
                    label::instance(**l) == p.id + 1 && {
                        let w = q.cast::<f64>() + sensor.coords;
                        (w.x - p.x).hypot(w.y - p.y) < p.radius_m * 1.06 + 0.1
                    }
                })
                .count();
            assert!(
                returns > 0,
                "{:?} pole {} at {distance:.1} m has no returns",
                p.kind,
                p.id
            );
        }
    }
    eprintln!("{checked} visible poles checked");
    assert!(checked >= 10, "only {checked} visible poles");
}

#[test]
fn nclt_style_sessions_read_back_in_rep103() {
    let config = tiny_nclt(3, 1024);
    let dir = tempfile::tempdir().unwrap();
    let set = generate_nclt(&config, 5, dir.path(), no_progress()).unwrap();
    assert_eq!(set.stats["sessions"].as_array().unwrap().len(), 2);
    let root_poles = std::fs::read(dir.path().join("poles.csv")).unwrap();
    // raypath info on the set's directory (the folder of sessions).
    let root = raypath_io::summarize(dir.path()).unwrap();
    assert_eq!(root.format, "nclt");
    assert_eq!(
        (root.scans, root.poses, root.odometry),
        (Some(6), Some(6), Some(42))
    );
    for (k, date) in config.sessions.iter().enumerate() {
        let session_dir = dir.path().join(date);
        let summary = raypath_io::summarize(&session_dir).unwrap();
        assert_eq!(summary.format, "nclt");
        assert_eq!(summary.scans, Some(3));
        assert_eq!(summary.poses, Some(3));
        assert_eq!(summary.odometry, Some(21));
        let session = NcltSession::open(&session_dir).unwrap();
        assert_eq!(session.date.as_deref(), Some(date.as_str()));
        assert_eq!(session.relative_odometry().unwrap().poses.len(), 3);
        assert_eq!(session.relative_odometry_cov().unwrap().records.len(), 3);
        let gt = session.ground_truth().unwrap();
        let mut near = (0usize, 0usize, 0usize);
        for (scan, pose) in session.scans().zip(&gt.poses) {
            let mut scan = scan.unwrap();
            assert_eq!(scan.utime, pose.utime);
            assert!(scan.points.label.as_ref().unwrap().iter().all(|&l| l < 32));
            nclt::flu_from_frd(&mut scan.points);
            let world_from_body = pose.world_from_body();
            for p in &scan.points.points {
                if p.x.hypot(p.y) < 10.0 {
                    let w = world_from_body.transform_point(&p.cast::<f64>());
                    near.0 += 1;
                    // Road (z = 0), sidewalk (0.12 m), or something standing on them.
                    near.1 += usize::from(w.z > -0.05);
                    near.2 += usize::from(w.z.abs() < 0.06 || (w.z - 0.12).abs() < 0.06);
                }
            }
        }
        eprintln!("{date}: {near:?} points near the sensor above the ground");
        assert!(near.1 == near.0 && near.0 > 1000, "{near:?}");
        assert!(near.2 as f64 > 0.5 * near.0 as f64, "{near:?}");
        let poles = std::fs::read(session_dir.join("poles.csv")).unwrap();
        assert_eq!(poles == root_poles, k == 0);
    }
}

#[test]
fn outputs_are_identical_across_runs_and_thread_counts() {
    let kitti_config = tiny_kitti(3, 360);
    let nclt_config = tiny_nclt(2, 360);
    let run = |threads: usize| {
        let dir = tempfile::tempdir().unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            generate_kitti(&kitti_config, 9, &dir.path().join("kitti"), no_progress()).unwrap();
            generate_nclt(&nclt_config, 9, &dir.path().join("nclt"), no_progress()).unwrap();
        });
        snapshot(dir.path())
    };
    let a = run(1);
    let b = run(3);
    assert!(a.len() > 20);
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (name, bytes) in &a {
        assert!(bytes == &b[name], "{name} differs");
    }
    // A different seed gives different scans.
    let dir = tempfile::tempdir().unwrap();
    generate_kitti(&kitti_config, 10, dir.path(), no_progress()).unwrap();
    let other = std::fs::read(dir.path().join("sequences/00/velodyne/000000.bin")).unwrap();
    assert_ne!(&other, &a["kitti/sequences/00/velodyne/000000.bin"]);
}

#[test]
fn bad_parameters_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = tiny_kitti(0, 360);
    assert!(generate_kitti(&config, 1, dir.path(), no_progress()).is_err());
    config.scans = 2;
    config.streets.block_length_m = (50.0, 10.0);
    assert!(generate_kitti(&config, 1, dir.path(), no_progress()).is_err());
    let mut nclt_config = tiny_nclt(2, 360);
    nclt_config.sessions = vec!["2012-13-01".into()];
    let err = generate_nclt(&nclt_config, 1, dir.path(), no_progress()).unwrap_err();
    assert!(err.to_string().contains("2012-13-01"), "{err}");
}
