//! Traversal throughput in cells per second (Criterion `Throughput::Elements` = cells
//! visited per batch of rays), single thread.
//!
//! Workloads (seeded, identical to `cargo xtask eval geometry`):
//! * `3d/inside`: a 200³ grid of 0.1 m voxels (a 20 m cube); rays start uniformly inside it, in
//!   uniformly random directions, and hit at 0.5–30 m (10 % no-returns traced to 30 m).
//! * `3d/outside`: the same grid; rays start on a sphere of radius 25 m around it, aimed at
//!   random points inside, no-returns traced to 60 m (every ray is clipped twice).
//! * `2d/inside`: a 2000² grid of 0.1 m cells (200 m square); rays start in its central
//!   100 m square and hit at 0.5–50 m (10 % no-returns traced to 50 m).
//!
//! Run with `cargo bench -p raypath-geometry --bench traversal`.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_main};
use nalgebra::{Point2, Point3, Vector2, Vector3};
use raypath_geometry::{Grid2, Grid3, Range, Ray2, Ray3};

/// Rays per Criterion iteration.
const RAYS: usize = 10_000;

/// SplitMix64: a tiny seeded generator, the same one the xtask evaluation uses.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    fn unit3(&mut self) -> Vector3<f64> {
        let z = self.uniform(-1.0, 1.0);
        let phi = self.uniform(0.0, std::f64::consts::TAU);
        let r = (1.0 - z * z).sqrt();
        Vector3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

fn grid3() -> Grid3 {
    Grid3::new(Point3::new(-10.0, -10.0, -10.0), 0.1, [200, 200, 200]).expect("valid grid")
}

fn grid2() -> Grid2 {
    Grid2::new(Point2::new(-100.0, -100.0), 0.1, [2000, 2000]).expect("valid grid")
}

fn rays_inside_3d(n: usize, seed: u64) -> Vec<Ray3> {
    let mut rng = SplitMix64(seed);
    (0..n)
        .map(|_| {
            let origin = Point3::new(
                rng.uniform(-10.0, 10.0),
                rng.uniform(-10.0, 10.0),
                rng.uniform(-10.0, 10.0),
            );
            let range = if rng.uniform(0.0, 1.0) < 0.1 {
                Range::NoReturn
            } else {
                Range::Hit(rng.uniform(0.5, 30.0))
            };
            Ray3::new(origin, rng.unit3(), range).expect("unit direction")
        })
        .collect()
}

fn rays_outside_3d(n: usize, seed: u64) -> Vec<Ray3> {
    let mut rng = SplitMix64(seed);
    let mut rays = Vec::with_capacity(n);
    while rays.len() < n {
        let origin = Point3::from(rng.unit3() * 25.0);
        let target = Point3::new(
            rng.uniform(-10.0, 10.0),
            rng.uniform(-10.0, 10.0),
            rng.uniform(-10.0, 10.0),
        );
        rays.extend(Ray3::new(origin, target - origin, Range::NoReturn));
    }
    rays
}

fn rays_inside_2d(n: usize, seed: u64) -> Vec<Ray2> {
    let mut rng = SplitMix64(seed);
    (0..n)
        .map(|_| {
            let origin = Point2::new(rng.uniform(-50.0, 50.0), rng.uniform(-50.0, 50.0));
            let angle = rng.uniform(0.0, std::f64::consts::TAU);
            let range = if rng.uniform(0.0, 1.0) < 0.1 {
                Range::NoReturn
            } else {
                Range::Hit(rng.uniform(0.5, 50.0))
            };
            Ray2::new(origin, Vector2::new(angle.cos(), angle.sin()), range)
                .expect("unit direction")
        })
        .collect()
}

/// Sum of in-cell lengths over all rays (what a decay-rate map accumulates).
fn trace3(grid: &Grid3, rays: &[Ray3], max_range_m: f64) -> f64 {
    rays.iter()
        .map(|ray| {
            grid.traverse_ray(ray, max_range_m)
                .map(|c| c.length())
                .sum::<f64>()
        })
        .sum()
}

fn trace2(grid: &Grid2, rays: &[Ray2], max_range_m: f64) -> f64 {
    rays.iter()
        .map(|ray| {
            grid.traverse_ray(ray, max_range_m)
                .map(|c| c.length())
                .sum::<f64>()
        })
        .sum()
}

fn bench_traversal(c: &mut Criterion) {
    let mut group = c.benchmark_group("traversal");

    let grid = grid3();
    for (name, rays, max_range) in [
        ("3d/inside", rays_inside_3d(RAYS, 1), 30.0),
        ("3d/outside", rays_outside_3d(RAYS, 2), 60.0),
    ] {
        let cells: usize = rays
            .iter()
            .map(|r| grid.traverse_ray(r, max_range).len())
            .sum();
        group.throughput(Throughput::Elements(cells as u64));
        group.bench_function(name, |b| {
            b.iter(|| trace3(&grid, black_box(&rays), max_range))
        });
    }

    let grid = grid2();
    let rays = rays_inside_2d(RAYS, 3);
    let cells: usize = rays.iter().map(|r| grid.traverse_ray(r, 50.0).len()).sum();
    group.throughput(Throughput::Elements(cells as u64));
    group.bench_function("2d/inside", |b| {
        b.iter(|| trace2(&grid, black_box(&rays), 50.0))
    });

    group.finish();
}

/// The Criterion group (in a private module: the macro's function has no docs).
mod group {
    criterion::criterion_group!(benches, super::bench_traversal);
}
criterion_main!(group::benches);
