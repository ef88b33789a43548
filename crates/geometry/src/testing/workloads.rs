//! Seeded traversal workloads shared by the Criterion benchmark
//! (`cargo bench -p raypath-geometry --bench traversal`) and `cargo xtask eval geometry`, so
//! both measure identical rays.
//!
//! * `3d/inside`: [`grid3`], a 200³ grid of 0.1 m voxels (a 20 m cube); rays start uniformly
//!   inside it in uniformly random directions and hit at 0.5–30 m (10 % no-returns, traced to
//!   30 m).
//! * `3d/outside`: the same grid; rays start on a sphere of radius 25 m around it, aimed at
//!   random points inside; no-returns traced to 60 m (every ray is clipped twice).
//! * `2d/inside`: [`grid2`], a 2000² grid of 0.1 m cells (200 m square); rays start in its
//!   central 100 m square and hit at 0.5–50 m (10 % no-returns, traced to 50 m).

use nalgebra::{Point2, Point3, Vector2, Vector3};

use crate::{Grid2, Grid3, Range, Ray2, Ray3};

/// The workloads' generator: SplitMix64 (Steele, Lea & Flood 2014, from `rand_xoshiro`)
/// started at the given state, with the two draws the workloads need.
#[derive(Clone, Debug)]
pub struct SplitMix64(rand_xoshiro::SplitMix64);

impl SplitMix64 {
    /// The generator at state `state`.
    pub fn new(state: u64) -> Self {
        use rand_xoshiro::rand_core::SeedableRng;
        Self(rand_xoshiro::SplitMix64::seed_from_u64(state))
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        use rand_xoshiro::rand_core::RngCore;
        self.0.next_u64()
    }

    /// Uniform in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A uniformly distributed unit vector in 3-D.
    pub fn unit3(&mut self) -> Vector3<f64> {
        let z = self.uniform(-1.0, 1.0);
        let phi = self.uniform(0.0, std::f64::consts::TAU);
        let r = (1.0 - z * z).sqrt();
        Vector3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// The 3-D workload grid: 200³ voxels of 0.1 m from (−10, −10, −10) m.
pub fn grid3() -> Grid3 {
    Grid3::new(Point3::new(-10.0, -10.0, -10.0), 0.1, [200, 200, 200])
        .unwrap_or_else(|_| unreachable!("constant grid parameters are valid"))
}

/// The 2-D workload grid: 2000² cells of 0.1 m from (−100, −100) m.
pub fn grid2() -> Grid2 {
    Grid2::new(Point2::new(-100.0, -100.0), 0.1, [2000, 2000])
        .unwrap_or_else(|_| unreachable!("constant grid parameters are valid"))
}

fn hit_or_no_return(rng: &mut SplitMix64, max_hit_m: f64) -> Range {
    if rng.uniform(0.0, 1.0) < 0.1 {
        Range::NoReturn
    } else {
        Range::Hit(rng.uniform(0.5, max_hit_m))
    }
}

/// `n` rays starting inside [`grid3`] (max range 30 m).
pub fn rays_inside_3d(n: usize, seed: u64) -> Vec<Ray3> {
    let mut rng = SplitMix64::new(seed);
    let mut rays = Vec::with_capacity(n);
    while rays.len() < n {
        let origin = Point3::new(
            rng.uniform(-10.0, 10.0),
            rng.uniform(-10.0, 10.0),
            rng.uniform(-10.0, 10.0),
        );
        let range = hit_or_no_return(&mut rng, 30.0);
        rays.extend(Ray3::new(origin, rng.unit3(), range));
    }
    rays
}

/// `n` no-return rays from a 25 m sphere through [`grid3`] (max range 60 m).
pub fn rays_outside_3d(n: usize, seed: u64) -> Vec<Ray3> {
    let mut rng = SplitMix64::new(seed);
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

/// `n` rays starting in the central 100 m square of [`grid2`] (max range 50 m).
pub fn rays_inside_2d(n: usize, seed: u64) -> Vec<Ray2> {
    let mut rng = SplitMix64::new(seed);
    let mut rays = Vec::with_capacity(n);
    while rays.len() < n {
        let origin = Point2::new(rng.uniform(-50.0, 50.0), rng.uniform(-50.0, 50.0));
        let angle = rng.uniform(0.0, std::f64::consts::TAU);
        let range = hit_or_no_return(&mut rng, 50.0);
        rays.extend(Ray2::new(
            origin,
            Vector2::new(angle.cos(), angle.sin()),
            range,
        ));
    }
    rays
}
