//! A synthetic street for registration tests: ground, house fronts, a wall ahead, parked cars
//! and poles, sampled at random with noise and seen from a sensor pose.

#![allow(dead_code)]

use nalgebra::{Point3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use raypath_geometry::{PointCloud, Pose3};

/// A rectangle: corner, two edge vectors.
struct Patch {
    corner: Point3<f64>,
    u: Vector3<f64>,
    v: Vector3<f64>,
}

impl Patch {
    fn area(&self) -> f64 {
        self.u.cross(&self.v).norm()
    }
}

fn boxes(corner: Point3<f64>, size: Vector3<f64>) -> Vec<Patch> {
    let (x, y, z) = (
        Vector3::x() * size.x,
        Vector3::y() * size.y,
        Vector3::z() * size.z,
    );
    vec![
        Patch { corner, u: x, v: z },
        Patch {
            corner: corner + y,
            u: x,
            v: z,
        },
        Patch { corner, u: y, v: z },
        Patch {
            corner: corner + x,
            u: y,
            v: z,
        },
        Patch {
            corner: corner + z,
            u: x,
            v: y,
        },
    ]
}

fn street() -> Vec<Patch> {
    let mut patches = vec![
        // Ground, 60 m × 20 m, 1.7 m below the sensor.
        Patch {
            corner: Point3::new(-30.0, -10.0, -1.7),
            u: Vector3::x() * 60.0,
            v: Vector3::y() * 20.0,
        },
        // House fronts, 9 m high, with a recess.
        Patch {
            corner: Point3::new(-30.0, 10.0, -1.7),
            u: Vector3::x() * 35.0,
            v: Vector3::z() * 9.0,
        },
        Patch {
            corner: Point3::new(5.0, 11.5, -1.7),
            u: Vector3::x() * 25.0,
            v: Vector3::z() * 9.0,
        },
        Patch {
            corner: Point3::new(5.0, 10.0, -1.7),
            u: Vector3::y() * 1.5,
            v: Vector3::z() * 9.0,
        },
        Patch {
            corner: Point3::new(-30.0, -10.0, -1.7),
            u: Vector3::x() * 60.0,
            v: Vector3::z() * 7.0,
        },
        // A wall ahead.
        Patch {
            corner: Point3::new(30.0, -10.0, -1.7),
            u: Vector3::y() * 20.0,
            v: Vector3::z() * 5.0,
        },
    ];
    // Parked cars.
    for (x, y) in [(-12.0, 7.0), (-4.0, 7.2), (8.0, -8.5), (16.0, 7.0)] {
        patches.extend(boxes(Point3::new(x, y, -1.7), Vector3::new(4.2, 1.8, 1.5)));
    }
    patches
}

/// `n` points sampled uniformly over the street's surfaces plus 3 % clutter (poles and
/// scattered "foliage" points), in the world frame, with Gaussian noise of `sigma_m`.
pub fn world_points(seed: u64, n: usize, sigma_m: f64) -> Vec<Point3<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, sigma_m.max(1e-12)).unwrap();
    let patches = street();
    let total: f64 = patches.iter().map(Patch::area).sum();
    let mut points = Vec::with_capacity(n);
    let clutter = n * 3 / 100;
    for _ in 0..n - clutter {
        let mut pick = rng.random::<f64>() * total;
        let patch = patches
            .iter()
            .find(|p| {
                pick -= p.area();
                pick <= 0.0
            })
            .unwrap_or(&patches[0]);
        let (a, b): (f64, f64) = (rng.random(), rng.random());
        let p = patch.corner + patch.u * a + patch.v * b;
        points.push(p + Vector3::from_fn(|_, _| noise.sample(&mut rng)));
    }
    for k in 0..clutter {
        let p = if k % 2 == 0 {
            // Poles of radius 0.12 m, 6 m high, every 8 m along the left kerb.
            let x = -28.0 + 8.0 * (rng.random_range(0..7) as f64);
            let a = rng.random::<f64>() * std::f64::consts::TAU;
            Point3::new(
                x + 0.12 * a.cos(),
                8.5 + 0.12 * a.sin(),
                -1.7 + 6.0 * rng.random::<f64>(),
            )
        } else {
            // Foliage: points scattered in two 3 m blobs.
            let c = if rng.random::<bool>() {
                Point3::new(-20.0, -7.0, 3.0)
            } else {
                Point3::new(22.0, 8.0, 4.0)
            };
            c + Vector3::from_fn(|_, _| rng.random_range(-1.5..1.5))
        };
        points.push(p);
    }
    points
}

/// A scan of the street from `world_from_sensor`: an independent sample of `n` points in the
/// sensor frame.
pub fn scan(seed: u64, n: usize, sigma_m: f64, world_from_sensor: &Pose3) -> PointCloud {
    let sensor_from_world = world_from_sensor.inverse();
    PointCloud::from_points(
        world_points(seed, n, sigma_m)
            .iter()
            .map(|p| sensor_from_world.transform_point(p).cast::<f32>())
            .collect(),
    )
}

/// Translation (m) and rotation (rad) of `a⁻¹ b`.
pub fn pose_error(a: &Pose3, b: &Pose3) -> (f64, f64) {
    let d = a.inverse() * *b;
    (d.translation().norm(), d.rotation().angle())
}
