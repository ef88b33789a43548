//! The SynPEB-style generator: files readable as organized 500 × 500 labelled PCDs, bytes
//! identical across runs and thread counts, labels that match the planar faces hit, the
//! configured radial noise, and statistics against the thesis and the real sample.

#![allow(clippy::unwrap_used)]

use std::collections::HashMap;
use std::path::Path;

use nalgebra::{Matrix3, Vector3};
use raypath_geometry::PointCloud;
use raypath_io::pcd::{self, ReadOptions};
use raypath_sim::no_progress;
use raypath_sim::synpeb::{self, MIN_PLANE_LABEL, SynpebConfig};

/// A small set: 1 training and 2 test scans at 0.0 and 2.0 cm, full 500 × 500 resolution.
fn small() -> SynpebConfig {
    SynpebConfig {
        train_scans: 1,
        test_scans: 2,
        noise_levels_cm: vec![0.0, 2.0],
        ..SynpebConfig::default()
    }
}

fn generate_in(dir: &Path, threads: Option<usize>) -> raypath_sim::GeneratedSet {
    let run = || synpeb::generate(&small(), 17, dir, no_progress()).unwrap();
    match threads {
        None => run(),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
            .install(run),
    }
}

fn read(path: &Path) -> PointCloud {
    pcd::read_pcd(path, &ReadOptions::synpeb()).unwrap().cloud
}

#[test]
fn generation_is_deterministic_readable_and_labelled() {
    let (a, b, c) = (
        tempfile::tempdir().unwrap(),
        tempfile::tempdir().unwrap(),
        tempfile::tempdir().unwrap(),
    );
    let set = generate_in(a.path(), None);
    let again = generate_in(b.path(), None);
    let one_thread = generate_in(c.path(), Some(1));
    let expected: Vec<String> = [
        "test/0.0/pc_01.pcd",
        "test/0.0/pc_02.pcd",
        "test/2.0/pc_01.pcd",
    ]
    .iter()
    .chain(&[
        "test/2.0/pc_02.pcd",
        "train/0.0/pc_01.pcd",
        "train/2.0/pc_01.pcd",
    ])
    .map(|s| s.to_string())
    .collect();
    let files: Vec<String> = set
        .files
        .iter()
        .map(|f| f.to_string_lossy().into())
        .collect();
    assert_eq!(files, expected);
    assert_eq!(set.files, again.files);
    assert_eq!(set.files, one_thread.files);
    for file in &set.files {
        let bytes = std::fs::read(a.path().join(file)).unwrap();
        assert_eq!(
            bytes,
            std::fs::read(b.path().join(file)).unwrap(),
            "{file:?}"
        );
        assert_eq!(
            bytes,
            std::fs::read(c.path().join(file)).unwrap(),
            "{file:?} (1 thread)"
        );
        let summary = raypath_io::summarize(&a.path().join(file)).unwrap();
        assert_eq!(summary.format, "pcd");
        assert_eq!((summary.width, summary.height), (Some(500), Some(500)));
        assert_eq!(summary.extra["data"], "binary_compressed");
        assert_eq!(summary.extra["label_field"], "intensity");
        let labels = summary.labels.unwrap();
        assert!(
            labels.iter().filter(|&&l| l >= MIN_PLANE_LABEL).count() >= 5,
            "{labels:?}"
        );
    }
    assert_eq!(set.stats, again.stats);
    let planes = &set.stats["full_scans"]["planes_per_scan"];
    assert!(planes["min"].as_f64().unwrap() >= 5.0, "{planes}");
    assert_eq!(set.stats["thesis_planes_per_scan"], 42.6);
}

/// Per label ≥ 10, the points of a noise-free scan lie on one plane; cylinder sides (label 1)
/// and spheres (label 2) do not.
#[test]
fn plane_labels_are_planar_and_curved_labels_are_not() {
    let config = SynpebConfig {
        angular_noise_mdeg: 0.0,
        rows: 250,
        cols: 250,
        ..small()
    };
    let lidar = synpeb::scanner(&config).unwrap();
    let mut residual_checked = 0;
    let mut curved_seen = 0;
    for room_index in 0..3 {
        let room = synpeb::build_room(&config, 5, room_index).unwrap();
        assert!(room.objects >= 20, "{}", room.objects);
        for scan_index in 0..3 {
            let pose = room.sensor_pose(&config, 5, scan_index).unwrap();
            let t = pose.translation();
            assert!(t.x > 0.0 && t.y > 0.0 && t.z > 0.0);
            assert!(t.x < room.size_m.x && t.y < room.size_m.y && t.z < room.size_m.z);
            let scan = lidar.scan(&room.scene, &pose, 5, scan_index).unwrap();
            let labels = scan.cloud.label.as_ref().unwrap();
            let mut groups: HashMap<u32, Vec<Vector3<f64>>> = HashMap::new();
            for (i, p) in scan.cloud.points.iter().enumerate() {
                assert!(scan.cloud.is_valid(i), "a closed room returns every beam");
                assert!(p.coords.norm() > 0.29, "the sensor is clear of objects");
                let surface = room.scene.surface(scan.surfaces[i].unwrap()).unwrap();
                assert_eq!(surface.label, labels[i]);
                groups
                    .entry(labels[i])
                    .or_default()
                    .push(p.coords.cast::<f64>());
            }
            for (label, points) in &groups {
                if points.len() < 30 {
                    continue;
                }
                let residual = max_plane_residual(points);
                if *label >= MIN_PLANE_LABEL {
                    assert!(residual < 2e-4, "label {label}: {residual} m off its plane");
                    residual_checked += 1;
                } else if points.len() > 200 {
                    assert!(residual > 5e-3, "curved label {label} is flat: {residual}");
                    curved_seen += 1;
                }
            }
        }
    }
    assert!(residual_checked > 100, "{residual_checked}");
    assert!(curved_seen > 0);
}

/// Largest distance of `points` from their least-squares plane.
fn max_plane_residual(points: &[Vector3<f64>]) -> f64 {
    let n = points.len() as f64;
    let mean = points.iter().sum::<Vector3<f64>>() / n;
    let cov = points
        .iter()
        .map(|p| (p - mean) * (p - mean).transpose())
        .sum::<Matrix3<f64>>();
    let eig = cov.symmetric_eigen();
    let k = eig.eigenvalues.imin();
    let normal = eig.eigenvectors.column(k).into_owned();
    points
        .iter()
        .map(|p| (p - mean).dot(&normal).abs())
        .fold(0.0, f64::max)
}

/// The 2.0 cm files differ from the 0.0 cm files of the same scan by radial noise of σ = 2 cm.
#[test]
fn radial_noise_of_a_level_has_its_sigma() {
    let dir = tempfile::tempdir().unwrap();
    let config = SynpebConfig {
        train_scans: 0,
        test_scans: 1,
        noise_levels_cm: vec![0.0, 2.0],
        ..SynpebConfig::default()
    };
    synpeb::generate(&config, 3, dir.path(), no_progress()).unwrap();
    let clean = read(&dir.path().join("test/0.0/pc_01.pcd"));
    let noisy = read(&dir.path().join("test/2.0/pc_01.pcd"));
    assert_eq!(clean.label, noisy.label);
    let mut errors = Vec::new();
    for (c, n) in clean.points.iter().zip(&noisy.points) {
        let (c, n) = (c.coords.cast::<f64>(), n.coords.cast::<f64>());
        // Same direction, different range.
        assert!((c.normalize() - n.normalize()).norm() < 1e-5);
        errors.push(n.norm() - c.norm());
    }
    let count = errors.len() as f64;
    let mean = errors.iter().sum::<f64>() / count;
    let std = (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / count).sqrt();
    assert_eq!(errors.len(), 250_000);
    assert!(mean.abs() < 3.0 * 0.02 / count.sqrt() + 1e-5, "{mean}");
    assert!((std / 0.02 - 1.0).abs() < 0.01, "{std}");
    // The points lie on the nominal grid: row 0 at +30°, column 0 at −35°.
    let p = clean.points[0].coords.cast::<f64>();
    let elevation = p.z.atan2(p.xy().norm()).to_degrees();
    let azimuth = p.y.atan2(p.x).to_degrees();
    assert!((elevation - 30.0).abs() < 1e-3 && (azimuth + 35.0).abs() < 1e-3);
}

#[test]
fn real_sample_statistics_when_installed() {
    if raypath_io::data::require(synpeb::REAL_SAMPLE).is_none() {
        return;
    }
    let Some(result) = synpeb::real_sample_stats() else {
        panic!("{} present but not readable", synpeb::REAL_SAMPLE);
    };
    let stats = result.unwrap();
    assert_eq!(stats.pixels, 10_000);
    assert_eq!(stats.planes, 12);
    assert!((stats.plane_pixel_fraction - 0.998).abs() < 1e-9);
    assert!((stats.range_min_m - 1.987).abs() < 1e-3 && (stats.range_max_m - 4.845).abs() < 1e-3);
}

#[test]
fn invalid_configurations_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let bad = [
        SynpebConfig {
            noise_levels_cm: vec![],
            ..small()
        },
        SynpebConfig {
            noise_levels_cm: vec![f64::NAN],
            ..small()
        },
        SynpebConfig {
            noise_levels_cm: vec![2.0, 2.04],
            ..small()
        },
        SynpebConfig {
            train_scans: 0,
            test_scans: 0,
            ..small()
        },
        SynpebConfig { rows: 0, ..small() },
        SynpebConfig {
            sensor_height_m: [2.0, 5.0],
            ..small()
        },
        SynpebConfig {
            room_size_m: [1.0, 6.0, 3.0],
            ..small()
        },
    ];
    for config in bad {
        assert!(
            synpeb::generate(&config, 0, dir.path(), no_progress()).is_err(),
            "{config:?}"
        );
    }
}
