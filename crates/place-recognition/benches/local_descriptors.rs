//! Scan Context (describe a 120 k-point cloud; query against 1 000 and 10 000 stored frames)
//! and SHOT (describe a 120 k-point cloud at ψ = 0.1 m, with and without intensity).
#![allow(missing_docs, clippy::unwrap_used)]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Point3;
use raypath_geometry::PointCloud;
use raypath_place_recognition::{
    Frame, PlaceRecognizer, ScanContext, ScanContextConfig, ShotConfig, describe_cloud,
};

/// A simulated spinning lidar (`beams` × `columns` rays, −25°…+2°, 1.8 m above the ground)
/// in a street: ground plane, a wavy façade line around the sensor (`phase` varies it) and
/// its 8 m height. Intensity depends on the surface.
fn street_scan(beams: usize, columns: usize, phase: f64) -> PointCloud {
    let mut points = Vec::with_capacity(beams * columns);
    let mut intensity = Vec::with_capacity(beams * columns);
    for b in 0..beams {
        let elevation = (-25.0 + 27.0 * b as f64 / (beams - 1) as f64).to_radians();
        for c in 0..columns {
            let azimuth = std::f64::consts::TAU * c as f64 / columns as f64;
            let (dx, dy, dz) = (
                elevation.cos() * azimuth.cos(),
                elevation.cos() * azimuth.sin(),
                elevation.sin(),
            );
            let wall = 9.0 + 4.0 * (3.0 * azimuth + phase).sin() + 2.0 * (7.0 * azimuth).cos();
            let t_wall = wall / elevation.cos();
            let t_ground = if dz < 0.0 { 1.8 / -dz } else { f64::INFINITY };
            let (t, i) = if t_ground < t_wall {
                (t_ground, 10.0 + 5.0 * ((dx * t_ground).floor() % 2.0))
            } else if dz * t_wall < 6.2 {
                (t_wall, 40.0 + 20.0 * (dz * t_wall).sin())
            } else {
                continue;
            };
            if t > 80.0 {
                continue;
            }
            points.push(Point3::new(
                (dx * t) as f32,
                (dy * t) as f32,
                (dz * t) as f32,
            ));
            intensity.push(i as f32);
        }
    }
    let mut cloud = PointCloud::from_points(points);
    cloud.intensity = Some(intensity);
    cloud
}

/// KITTI odometry scan 00/000000 (`x y z intensity` f32) under `RAYPATH_DATA`, if present.
fn kitti_scan() -> Option<PointCloud> {
    let dir = std::env::var_os("RAYPATH_DATA")?;
    let path = std::path::Path::new(&dir).join("kitti/sequences/00/velodyne/000000.bin");
    let bytes = std::fs::read(path).ok()?;
    let values: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let points = values
        .chunks_exact(4)
        .map(|v| Point3::new(v[0], v[1], v[2]))
        .collect();
    let mut cloud = PointCloud::from_points(points);
    cloud.intensity = Some(values.chunks_exact(4).map(|v| v[3]).collect());
    Some(cloud)
}

fn scan_context(c: &mut Criterion) {
    let cloud = street_scan(64, 1875, 0.0);
    let mut sc = ScanContext::new(ScanContextConfig::default()).unwrap();
    c.bench_function("scan_context/describe_120k", |b| {
        b.iter(|| sc.describe(&Frame::Cloud(black_box(&cloud))).unwrap())
    });
    let query = sc.describe(&Frame::Cloud(&cloud)).unwrap();
    for (frames, exhaustive) in [(1_000, false), (10_000, false), (1_000, true)] {
        let config = ScanContextConfig {
            num_candidates: if exhaustive { None } else { Some(10) },
            ..Default::default()
        };
        let mut db = ScanContext::new(config).unwrap();
        for k in 0..frames {
            let small = street_scan(16, 360, k as f64 * 0.01);
            let d = db.describe(&Frame::Cloud(&small)).unwrap();
            db.insert(d);
        }
        let name = if exhaustive { "exhaustive" } else { "tree10" };
        c.bench_function(&format!("scan_context/query_{frames}_{name}"), |b| {
            b.iter(|| db.query(black_box(&query), frames))
        });
    }
}

fn shot(c: &mut Criterion) {
    let cloud = street_scan(64, 1875, 0.0);
    let mut group = c.benchmark_group("shot");
    group.sample_size(10);
    for with_intensity in [false, true] {
        let config = ShotConfig {
            with_intensity,
            ..ShotConfig::default()
        };
        let name = if with_intensity {
            "describe_120k_intensity"
        } else {
            "describe_120k"
        };
        group.bench_function(name, |b| {
            b.iter(|| describe_cloud(black_box(&cloud), &config))
        });
    }
    if let Some(cloud) = kitti_scan() {
        let config = ShotConfig {
            with_intensity: true,
            ..ShotConfig::default()
        };
        group.bench_function("describe_kitti_intensity", |b| {
            b.iter(|| describe_cloud(black_box(&cloud), &config))
        });
    }
    group.finish();
}

criterion_group!(benches, scan_context, shot);
criterion_main!(benches);
