//! # raypath-geometry
//!
//! The geometric core every raypath crate stands on: poses in SE(2) and SE(3), rays with
//! hits and no-returns, axis-aligned boxes, uniform grids, **exact ray traversal** that reports
//! the length a ray travels inside every cell, point clouds, planar scans (with point-to-line
//! ICP between two of them) and organized range images.
//!
//! ## Concepts
//!
//! ```text
//!        y (left)
//!        ^
//!        |     ray: origin + t · direction, t ∈ [0, r]
//!        |    ╱
//!   ┌────┼───╱┬────┐   traversal yields (cell, t_enter, t_exit) for every cell the
//!   │    │  ╱ │    │   segment crosses; t_exit − t_enter is the in-cell path length
//!   ├────┼─╱──┼────┤   d_i that the decay-rate model of Schaefer (2020, ch. 7) sums
//!   │    │╱   │    │   into R_i = Σ_j d_i(j).
//!   └────o────┴────┘──> x (forward)
//! ```
//!
//! * Frames follow ROS REP-103 (x forward, y left, z up); metres and radians everywhere.
//! * A pose is named by the frames it maps between: `world_from_sensor * point_in_sensor`.
//! * Bulk point data ([`PointCloud`]) is `f32`, like the files it comes from; poses, rays and
//!   traversal are `f64`, because per-cell lengths must sum to the ray length to 1e-9.
//!
//! ## Usage
//!
//! ```
//! use nalgebra::{Point3, Vector3};
//! use raypath_geometry::{Grid3, Ray3, Range};
//!
//! // A 10 m cube of 0.5 m voxels and a ray from its centre that reflects after 3 m.
//! let grid = Grid3::new(Point3::new(-5.0, -5.0, -5.0), 0.5, [20, 20, 20])?;
//! let ray = Ray3::new(Point3::origin(), Vector3::new(1.0, 0.4, 0.2), Range::Hit(3.0)).unwrap();
//! let total: f64 = grid.traverse_ray(&ray, 80.0).map(|c| c.length()).sum();
//! assert!((total - 3.0).abs() < 1e-9);
//! # Ok::<(), raypath_geometry::GeometryError>(())
//! ```
//!
//! ## Optional features
//!
//! * `testing`: proptest strategies (module `testing`) for poses, rays and grids, for other crates'
//!   property tests.

mod aabb;
mod error;
mod grid;
mod lane_dot;
mod line_icp;
mod point_cloud;
mod pose;
mod range_image;
mod ray;
mod scan2;
mod traversal;

#[cfg(feature = "testing")]
pub mod testing;

pub use aabb::{Aabb2, Aabb3};
pub use error::GeometryError;
pub use grid::{Grid2, Grid3};
pub use lane_dot::lane_dot;
pub use line_icp::{LineAlignment, LineIcp, LineTarget, MIN_CORRESPONDENCES, line_normal};
pub use point_cloud::PointCloud;
pub use pose::{Pose2, Pose3, wrap_angle};
pub use range_image::{
    BeamDirections, MAX_PIXELS, RangeImage, RingAssignment, RingProjection, SphericalProjection,
    spherical_direction,
};
pub use ray::{Range, Ray2, Ray3};
pub use scan2::Scan2;
pub use traversal::{
    CellCrossing, CellCrossing2, CellCrossing3, SlabWalk, SlabWalkEnd, Traversal, Traversal2,
    Traversal3,
};
