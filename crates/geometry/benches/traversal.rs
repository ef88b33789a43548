//! Traversal throughput in cells per second (Criterion `Throughput::Elements` = cells
//! visited per batch of rays), single thread.
//!
//! Workloads: `raypath_geometry::testing::workloads` (seeded, identical to
//! `cargo xtask eval geometry`):
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
use raypath_geometry::testing::workloads::{
    grid2, grid3, rays_inside_2d, rays_inside_3d, rays_outside_3d,
};
use raypath_geometry::{Grid2, Grid3, Ray2, Ray3};

/// Rays per Criterion iteration.
const RAYS: usize = 10_000;

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
