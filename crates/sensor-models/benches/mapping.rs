//! Map-building throughput (rays per second), `cargo bench -p raypath-sensor-models --bench mapping`.
//!
//! * `3d`: a 200 m × 200 m × 20 m region of 0.5 m voxels (400 × 400 × 40, 102 MB dense);
//!   48 scans of 20 000 rays (one HDL-64E revolution subsampled) from poses along a loop,
//!   elevations −24.8° to +2°, ranges uniform in 20–60 m (5 % no-returns traced to 60 m).
//!   Dense and sparse storage, all threads; dense also on one thread.
//! * `2d`: the same idea in the plane: a 200 m square of 0.1 m cells, 180-beam scans,
//!   ranges 1–30 m (10 % no-returns traced to 30 m).

#![allow(clippy::unwrap_used)] // benchmark set-up on fixed, valid inputs

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_main};
use nalgebra::{Point2, Point3, Vector3};
use raypath_geometry::{Grid2, Grid3, Range, Ray2, Ray3};
use raypath_sensor_models::{DenseStats2, DenseStats3, MappingConfig, SensorRange, SparseStats3};

/// Uniform numbers in `[0, 1)` from SplitMix64 (53 bits).
struct Rng(rand_xoshiro::SplitMix64);
impl Rng {
    fn new(state: u64) -> Self {
        use rand_xoshiro::rand_core::SeedableRng;
        Self(rand_xoshiro::SplitMix64::seed_from_u64(state))
    }

    fn next(&mut self) -> f64 {
        use rand_xoshiro::rand_core::RngCore;
        (self.0.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Scans of rays in the map frame.
fn scans_3d() -> Vec<Vec<Ray3>> {
    let mut rng = Rng::new(2020);
    (0..48)
        .map(|s| {
            let phase = s as f64 / 48.0 * std::f64::consts::TAU;
            let origin = Point3::new(60.0 * phase.cos(), 60.0 * phase.sin(), 1.8);
            (0..20_000)
                .map(|_| {
                    let azimuth = rng.next() * std::f64::consts::TAU;
                    let elevation = (-24.8 + 26.8 * rng.next()).to_radians();
                    let direction = Vector3::new(
                        elevation.cos() * azimuth.cos(),
                        elevation.cos() * azimuth.sin(),
                        elevation.sin(),
                    );
                    let range = if rng.next() < 0.05 {
                        Range::NoReturn
                    } else {
                        Range::Hit(20.0 + 40.0 * rng.next())
                    };
                    Ray3::new(origin, direction, range).unwrap()
                })
                .collect()
        })
        .collect()
}

fn scans_2d() -> Vec<Vec<Ray2>> {
    let mut rng = Rng::new(2017);
    (0..2000)
        .map(|s| {
            let phase = s as f64 / 2000.0 * std::f64::consts::TAU;
            let origin = Point2::new(50.0 * phase.cos(), 50.0 * phase.sin());
            (0..180)
                .map(|i| {
                    let angle = phase + (i as f64 - 90.0).to_radians();
                    let range = if rng.next() < 0.1 {
                        Range::NoReturn
                    } else {
                        Range::Hit(1.0 + 29.0 * rng.next())
                    };
                    Ray2::from_angle(origin, angle, range)
                })
                .collect()
        })
        .collect()
}

fn mapping(c: &mut Criterion) {
    let grid3 = Grid3::new(Point3::new(-100.0, -100.0, -5.0), 0.5, [400, 400, 40]).unwrap();
    let config3 = MappingConfig {
        range: SensorRange::new(0.0, 60.0).unwrap(),
        ..Default::default()
    };
    let scans = scans_3d();
    let rays: u64 = scans.iter().map(|s| s.len() as u64).sum();
    let mut group = c.benchmark_group("mapping/3d");
    group.sample_size(10);
    group.throughput(Throughput::Elements(rays));
    group.bench_function("dense", |b| {
        b.iter(|| {
            let mut stats = DenseStats3::new(grid3);
            stats.insert_par(&scans, &config3, |scan, sink| {
                scan.iter().for_each(&mut *sink)
            });
            black_box(stats.summary().crossings)
        })
    });
    group.bench_function("sparse", |b| {
        b.iter(|| {
            let mut stats = SparseStats3::new(grid3);
            stats.insert_par(&scans, &config3, |scan, sink| {
                scan.iter().for_each(&mut *sink)
            });
            black_box(stats.num_blocks())
        })
    });
    let single = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    group.bench_function("dense-1-thread", |b| {
        b.iter(|| {
            single.install(|| {
                let mut stats = DenseStats3::new(grid3);
                stats.insert_par(&scans, &config3, |scan, sink| {
                    scan.iter().for_each(&mut *sink)
                });
                black_box(stats.summary().crossings)
            })
        })
    });
    group.finish();

    let mut sparse = SparseStats3::new(grid3);
    sparse.insert_par(&scans, &config3, |scan, sink| {
        scan.iter().for_each(&mut *sink)
    });
    eprintln!(
        "3d: {} rays, {} crossings; sparse blocks {} ({:.1} MB) vs dense {:.1} MB",
        rays,
        sparse.summary().crossings,
        sparse.num_blocks(),
        sparse.memory_bytes() as f64 / 1e6,
        grid3.num_cells() as f64 * 16.0 / 1e6
    );

    let grid2 = Grid2::new(Point2::new(-100.0, -100.0), 0.1, [2000, 2000]).unwrap();
    let config2 = MappingConfig {
        range: SensorRange::new(0.0, 30.0).unwrap(),
        ..Default::default()
    };
    let scans2 = scans_2d();
    let rays2: u64 = scans2.iter().map(|s| s.len() as u64).sum();
    let mut group = c.benchmark_group("mapping/2d");
    group.sample_size(10);
    group.throughput(Throughput::Elements(rays2));
    group.bench_function("dense", |b| {
        b.iter(|| {
            let mut stats = DenseStats2::new(grid2);
            stats.insert_par(&scans2, &config2, |scan, sink| {
                scan.iter().for_each(&mut *sink)
            });
            black_box(stats.summary().crossings)
        })
    });
    group.finish();
}

/// The Criterion group (in a private module: the macro's function has no docs).
mod group {
    criterion::criterion_group!(benches, super::mapping);
}
criterion_main!(group::benches);
