//! Criterion bench: the ML fit of a 40 × 40 DCT map (1600 coefficients, the largest size of
//! Table 9.4) on synthetic rays in a 10 m × 10 m room — pre-processing (moments) and the
//! trust-region Newton optimization, for 500 rays (the thesis's timing set) and 10⁴ rays.
#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Point2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use raypath_dct_map::{FitConfig, FitProblem, MapRay, Patch, RangeLimits, Shape, fit, initial_map};
use raypath_geometry::{Range, Ray2};

/// Rays from random poses in a 10 m room with walls at x = 1, 9 and y = 1, 9 (hits) and a
/// door gap (no-returns).
fn room_rays(n: usize) -> Vec<MapRay> {
    let mut r = ChaCha8Rng::seed_from_u64(40);
    let patch = Patch::square([0.0, 0.0], 10.0);
    let mut rays = Vec::with_capacity(n);
    while rays.len() < n {
        let o = Point2::new(r.random_range(2.0..8.0), r.random_range(2.0..8.0));
        let angle: f64 = r.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        let (c, s) = (angle.cos(), angle.sin());
        let tx = if c > 0.0 {
            (9.0 - o.x) / c
        } else {
            (1.0 - o.x) / c
        };
        let ty = if s > 0.0 {
            (9.0 - o.y) / s
        } else {
            (1.0 - o.y) / s
        };
        let t = tx.min(ty);
        let door = tx < ty && c > 0.0 && (o.y + s * t - 5.0).abs() < 1.0;
        let range = if door {
            Range::NoReturn
        } else {
            Range::Hit(t + r.random_range(0.0..0.1))
        };
        if let Some(ray) =
            patch.clip_ray(&Ray2::from_angle(o, angle, range), &RangeLimits::default())
        {
            rays.push(ray);
        }
    }
    rays
}

fn bench(c: &mut Criterion) {
    let extent = [10.0, 10.0];
    let shape = Shape { l: 40, m: 40 };
    let mut group = c.benchmark_group("dct_fit_40x40");
    group.sample_size(10);
    for n in [500, 10_000] {
        let rays = room_rays(n);
        group.bench_function(format!("moments_{n}_rays"), |b| {
            b.iter(|| FitProblem::new(extent, shape, &rays).unwrap())
        });
        let problem = FitProblem::new(extent, shape, &rays).unwrap();
        let init = initial_map(extent, shape, &rays).unwrap();
        group.bench_function(format!("newton_{n}_rays"), |b| {
            b.iter(|| fit(&problem, init.coefficients(), &FitConfig::default()).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
