//! Criterion benches: `extract` (pole extraction from five HDL-64E-like scans in a KITTI
//! local map, throughput in points; `trace_only` is its hit/miss counting alone) and `localize` (one predict + update of 5000 particles
//! with 15 online poles on a 500-pole map, throughput in updates).

#![allow(missing_docs, clippy::unwrap_used, clippy::expect_used)]

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use nalgebra::{Point2, Point3, Vector3};
use raypath_geometry::{PointCloud, Pose2, Pose3};
use raypath_poles::{
    FilterParams, HitMissGrid, Pole, PoleFilter, PoleParams, extract_poles, local_grid,
};

/// Cylinders (x, y, r) on a street with two facades and the ground.
const CYLINDERS: [(f64, f64, f64); 6] = [
    (5.0, 6.0, 0.1),
    (12.0, 6.0, 0.15),
    (-7.0, 6.0, 0.3),
    (3.0, -6.0, 0.05),
    (-10.0, -6.0, 0.12),
    (9.0, -6.0, 0.2),
];

fn scan(sensor: &Point3<f64>) -> PointCloud {
    let mut points = Vec::with_capacity(64 * 1800);
    for e in 0..64 {
        let elevation = (-24.8 + e as f64 * 0.42f64).to_radians();
        for k in 0..1800 {
            let azimuth = (k as f64 * 0.2).to_radians();
            let d = Vector3::new(
                elevation.cos() * azimuth.cos(),
                elevation.cos() * azimuth.sin(),
                elevation.sin(),
            );
            let mut t = 80.0f64;
            if d.z < 0.0 {
                t = t.min(-sensor.z / d.z);
            }
            for wall_y in [9.0, -9.0f64] {
                let tw = (wall_y - sensor.y) / d.y;
                if tw > 0.0 {
                    t = t.min(tw);
                }
            }
            for (cx, cy, r) in CYLINDERS {
                let (ox, oy) = (sensor.x - cx, sensor.y - cy);
                let a = d.x * d.x + d.y * d.y;
                let b = 2.0 * (ox * d.x + oy * d.y);
                let c = ox * ox + oy * oy - r * r;
                let disc = b * b - 4.0 * a * c;
                if a > 0.0 && disc >= 0.0 {
                    let tc = (-b - disc.sqrt()) / (2.0 * a);
                    if tc > 0.0 {
                        t = t.min(tc);
                    }
                }
            }
            if t < 80.0 {
                let p = t * d;
                points.push(Point3::new(p.x as f32, p.y as f32, p.z as f32));
            }
        }
    }
    PointCloud::from_points(points)
}

fn bench_extract(c: &mut Criterion) {
    let sensors: Vec<Point3<f64>> = (0..5)
        .map(|i| Point3::new(-2.0 + i as f64, 0.0, 1.73))
        .collect();
    let clouds: Vec<(Pose3, PointCloud)> = sensors
        .iter()
        .map(|s| (Pose3::from_xyz_rpy(s.x, s.y, s.z, 0.0, 0.0, 0.0), scan(s)))
        .collect();
    let scans: Vec<(Pose3, &PointCloud)> = clouds.iter().map(|(p, c)| (*p, c)).collect();
    let points: usize = clouds.iter().map(|(_, c)| c.len()).sum();
    let params = PoleParams::kitti();
    let mut group = c.benchmark_group("extract");
    group.sample_size(10);
    group.throughput(Throughput::Elements(points as u64));
    group.bench_function("kitti_local_map_5_scans", |b| {
        b.iter(|| extract_poles(&scans, &Point3::new(0.0, 0.0, 1.73), &params))
    });
    let grid = local_grid(&Point3::new(0.0, 0.0, 1.73), &params).expect("grid");
    group.bench_function("kitti_local_map_5_scans_trace_only", |b| {
        b.iter(|| {
            let mut counts = HitMissGrid::new(grid);
            counts.insert_scans_par(&scans, params.max_range_m);
            counts.rays()
        })
    });
    group.finish();
}

fn bench_localize(c: &mut Criterion) {
    let map: Vec<Pole> = (0..500)
        .map(|i| {
            let (x, y) = (
                (i % 50) as f64 * 7.3,
                (i / 50) as f64 * 9.1 + (i % 3) as f64,
            );
            Pole {
                x,
                y,
                z_start: 0.0,
                z_end: 3.0,
                width: 0.2,
                score: 0.8,
            }
        })
        .collect();
    let online: Vec<Point2<f64>> = map
        .iter()
        .filter(|p| p.x < 40.0 && p.y < 30.0)
        .take(15)
        .map(|p| Point2::new(p.x - 1.0, p.y - 1.0))
        .collect();
    let start = Pose2::new(1.0, 1.0, 0.0);
    let mut filter = PoleFilter::new(&map, FilterParams::nclt(), start, 7).expect("filter");
    let mut group = c.benchmark_group("localize");
    group.throughput(Throughput::Elements(1));
    group.bench_function("predict_update_5000_particles_15_poles", |b| {
        b.iter(|| {
            filter
                .predict(&Pose2::new(0.0, 0.0, 0.0), [0.01, 0.01, 0.001])
                .expect("predict");
            filter.update(&online).expect("update");
            filter.estimate()
        })
    });
    group.finish();
}

criterion_group!(benches, bench_extract, bench_localize);
criterion_main!(benches);
