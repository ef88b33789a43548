//! Proptest strategies for poses, rays and grids (feature `testing`), shared by the property
//! tests of every raypath crate.
//!
//! Values stay in ranges where `f64` arithmetic is comfortably exact to 1e-9: positions within
//! ±100 m, cell sizes from 1/32 m to 2 m. Directions mix uniformly random unit vectors with
//! the awkward ones (axis-parallel, face and space diagonals) so that degenerate cases are
//! drawn often; grids mix dyadic cell sizes and origins (on which lattice points are exact
//! binary fractions, so rays really do pass through corners) with arbitrary ones.
//!
//! ```
//! use proptest::prelude::*;
//! use raypath_geometry::testing::{pose3, ray3_in};
//! use raypath_geometry::Aabb3;
//! use nalgebra::Point3;
//!
//! proptest!(|(pose in pose3(), ray in ray3_in(Aabb3::new(Point3::origin(), Point3::new(1.0, 1.0, 1.0))))| {
//!     let back = pose.inverse() * (pose * ray.origin);
//!     prop_assert!((back - ray.origin).norm() < 1e-9);
//! });
//! ```

pub mod workloads;

use std::f64::consts::{PI, TAU};

use nalgebra::{Point2, Point3, Unit, UnitQuaternion, Vector2, Vector3};
use proptest::prelude::*;

use crate::{Aabb2, Aabb3, Grid2, Grid3, Pose2, Pose3, Range, Ray2, Ray3};

/// A planar pose with `x, y ∈ [−100, 100]` m and `θ ∈ (−π, π]`.
pub fn pose2() -> impl Strategy<Value = Pose2> {
    (-100.0..100.0f64, -100.0..100.0f64, -PI..PI).prop_map(|(x, y, theta)| Pose2::new(x, y, theta))
}

/// A rotation drawn uniformly by axis (on the sphere) and angle (in `[0, π]`).
pub fn rotation3() -> impl Strategy<Value = UnitQuaternion<f64>> {
    (uniform_unit_vector3(), 0.0..=PI)
        .prop_map(|(axis, angle)| UnitQuaternion::from_axis_angle(&axis, angle))
}

/// A 3-D pose with translation in `[−100, 100]³` m and a random rotation.
pub fn pose3() -> impl Strategy<Value = Pose3> {
    (
        -100.0..100.0f64,
        -100.0..100.0f64,
        -100.0..100.0f64,
        rotation3(),
    )
        .prop_map(|(x, y, z, rotation)| Pose3::from_parts(Vector3::new(x, y, z), rotation))
}

/// A unit vector uniformly distributed on the circle.
pub fn uniform_unit_vector2() -> impl Strategy<Value = Unit<Vector2<f64>>> {
    (0.0..TAU).prop_map(|a| Unit::new_normalize(Vector2::new(a.cos(), a.sin())))
}

/// A unit vector uniformly distributed on the sphere.
pub fn uniform_unit_vector3() -> impl Strategy<Value = Unit<Vector3<f64>>> {
    (-1.0..=1.0f64, 0.0..TAU).prop_map(|(z, phi)| {
        let r = (1.0 - z * z).max(0.0).sqrt();
        Unit::new_normalize(Vector3::new(r * phi.cos(), r * phi.sin(), z))
    })
}

/// A direction in the plane: mostly uniform, often axis-parallel or diagonal.
pub fn direction2() -> impl Strategy<Value = Unit<Vector2<f64>>> {
    let lattice = (-1i32..=1, -1i32..=1)
        .prop_filter("non-zero", |(x, y)| *x != 0 || *y != 0)
        .prop_map(|(x, y)| Unit::new_normalize(Vector2::new(f64::from(x), f64::from(y))));
    prop_oneof![3 => uniform_unit_vector2(), 1 => lattice]
}

/// A direction in space: mostly uniform, often axis-parallel, face- or space-diagonal.
pub fn direction3() -> impl Strategy<Value = Unit<Vector3<f64>>> {
    let lattice = (-1i32..=1, -1i32..=1, -1i32..=1)
        .prop_filter("non-zero", |(x, y, z)| *x != 0 || *y != 0 || *z != 0)
        .prop_map(|(x, y, z)| {
            Unit::new_normalize(Vector3::new(f64::from(x), f64::from(y), f64::from(z)))
        });
    prop_oneof![3 => uniform_unit_vector3(), 1 => lattice]
}

/// A point uniformly inside `aabb` (which must be non-empty).
pub fn point2_in(aabb: Aabb2) -> impl Strategy<Value = Point2<f64>> {
    (0.0..=1.0f64, 0.0..=1.0f64).prop_map(move |(a, b)| {
        let e = aabb.extents();
        Point2::new(aabb.min.x + a * e.x, aabb.min.y + b * e.y)
    })
}

/// A point uniformly inside `aabb` (which must be non-empty).
pub fn point3_in(aabb: Aabb3) -> impl Strategy<Value = Point3<f64>> {
    (0.0..=1.0f64, 0.0..=1.0f64, 0.0..=1.0f64).prop_map(move |(a, b, c)| {
        let e = aabb.extents();
        Point3::new(
            aabb.min.x + a * e.x,
            aabb.min.y + b * e.y,
            aabb.min.z + c * e.z,
        )
    })
}

/// A sensor reading: a hit in `[0, max_range_m]` (three times in four) or a no-return.
pub fn range(max_range_m: f64) -> impl Strategy<Value = Range> {
    prop_oneof![3 => (0.0..=max_range_m).prop_map(Range::Hit), 1 => Just(Range::NoReturn)]
}

/// A ray starting inside `aabb` with a [`direction2`] and a hit up to twice the box diagonal
/// (so it often leaves the box) or a no-return.
pub fn ray2_in(aabb: Aabb2) -> impl Strategy<Value = Ray2> {
    let reach = 2.0 * aabb.extents().norm() + 1e-3;
    (point2_in(aabb), direction2(), range(reach)).prop_map(|(origin, direction, range)| Ray2 {
        origin,
        direction,
        range,
    })
}

/// A ray starting inside `aabb` with a [`direction3`] and a hit up to twice the box diagonal
/// (so it often leaves the box) or a no-return.
pub fn ray3_in(aabb: Aabb3) -> impl Strategy<Value = Ray3> {
    let reach = 2.0 * aabb.extents().norm() + 1e-3;
    (point3_in(aabb), direction3(), range(reach)).prop_map(|(origin, direction, range)| Ray3 {
        origin,
        direction,
        range,
    })
}

/// A cell size in metres: dyadic (1/32 to 2, exact in binary) or arbitrary in `[0.03, 2]`.
pub fn cell_size() -> impl Strategy<Value = f64> {
    prop_oneof![(-5i32..=1).prop_map(|e| 2f64.powi(e)), 0.03..2.0f64,]
}

/// A grid origin coordinate: a dyadic value (multiple of 1/8 in `[−10, 10]`) or arbitrary.
fn origin_coordinate() -> impl Strategy<Value = f64> {
    prop_oneof![
        (-80i32..=80).prop_map(|k| f64::from(k) / 8.0),
        -10.0..10.0f64,
    ]
}

/// A 2-D grid of 1 to 40 cells per axis.
pub fn grid2() -> impl Strategy<Value = Grid2> {
    (
        origin_coordinate(),
        origin_coordinate(),
        cell_size(),
        1usize..=40,
        1usize..=40,
    )
        .prop_filter_map("valid grid", |(x, y, cell, nx, ny)| {
            Grid2::new(Point2::new(x, y), cell, [nx, ny]).ok()
        })
}

/// A 3-D grid of 1 to 12 cells per axis.
pub fn grid3() -> impl Strategy<Value = Grid3> {
    (
        (
            origin_coordinate(),
            origin_coordinate(),
            origin_coordinate(),
        ),
        cell_size(),
        (1usize..=12, 1usize..=12, 1usize..=12),
    )
        .prop_filter_map("valid grid", |((x, y, z), cell, (nx, ny, nz))| {
            Grid3::new(Point3::new(x, y, z), cell, [nx, ny, nz]).ok()
        })
}
