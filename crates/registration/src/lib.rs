//! # raypath-registration
//!
//! Where did the lidar move between two scans? **3-D scan registration** by point-to-plane
//! ICP, and **lidar odometry** that registers each scan to a local map of the previous ones.
//!
//! ## The idea
//!
//! ICP alternates data association (each source point's nearest target point) and a
//! least-squares pose update. Point-to-plane ICP (Chen & Medioni 1992) measures the residual
//! along the target's surface normal, `e = nᵀ (T p − q)`, so points may slide along surfaces
//! instead of being pulled to the sampled points; linearising the rotation (Low 2004) makes
//! each step a 6 × 6 linear system. Normals come from local PCA of the target's down-sampled
//! points (the eigenvector of the smallest eigenvalue of the neighbours' covariance); points
//! whose neighbourhood is not a surface (a blob, or one ring of a far scan) are left out.
//!
//! The surrounding pipeline follows KISS-ICP (Vizzo et al. 2023), which showed that a few
//! well-chosen parts make plain ICP a strong odometry:
//!
//! * **voxel down-sampling** at two scales of one voxel size `v` (`v / 2` for the map, `1.5 v`
//!   for the registration source), `v = max_range / 100`;
//! * a **robust kernel** (Geman–McClure) on the residuals, solved by iteratively reweighted
//!   least squares; ours: once converged, the kernel scale is halved and the estimate refined
//!   down to [`RegistrationConfig::final_kernel_scale_m`] (graduated robustness: the wide
//!   kernel's basin of convergence, the narrow kernel's precision);
//! * an **adaptive correspondence threshold** σ — the RMS error of the motion prediction —
//!   gating correspondences at 3σ with kernel scale σ / 3 ([`AdaptiveThreshold`]);
//! * a **constant-velocity initial guess** and a **local voxel map** of the last scans around
//!   the sensor ([`Odometry`]).
//!
//! Our departures from KISS-ICP: point-to-plane instead of point-to-point residuals (with the
//! normals stored in the map, computed when a scan joins it), the point nearest each voxel's
//! centroid instead of the first point per voxel (the workspace's voxel thinning), a k-d tree
//! ([`kiddo`]) instead of voxel-neighbourhood search, and no deskewing (scans are rigid).
//!
//! ## Frames
//!
//! Clouds are in their sensor frame (REP-103, metres, sensor at the origin: the range crop
//! is about the origin). [`Registration::target_from_source`] maps source points into the
//! target frame; [`OdometryStep::world_from_sensor`] maps a scan into the frame of the first.
//!
//! ## Example
//!
//! ```
//! use nalgebra::Point3;
//! use raypath_geometry::{PointCloud, Pose3};
//! use raypath_registration::{RegistrationConfig, register};
//!
//! // A street: the ground, two house fronts and a wall ahead, sampled every 0.25 m.
//! let mut points = Vec::new();
//! for i in 0..120 {
//!     for j in 0..48 {
//!         let (a, b) = (i as f32 * 0.25 - 10.0, j as f32 * 0.25);
//!         points.push(Point3::new(a, b - 6.0, -1.7)); // ground
//!         points.push(Point3::new(a, 6.0, b - 1.7)); // left front
//!         points.push(Point3::new(a, -6.0, b - 1.7)); // right front
//!         points.push(Point3::new(20.0, b - 6.0, a / 2.0 + 3.3)); // wall ahead
//!     }
//! }
//! let target = PointCloud::from_points(points);
//! // The sensor drove 0.8 m forward and turned by 3°: the same scene seen from there.
//! let truth = Pose3::from_xyz_rpy(0.8, 0.1, 0.0, 0.0, 0.0, 3f64.to_radians());
//! let source = PointCloud::from_points(
//!     target
//!         .points
//!         .iter()
//!         .map(|p| truth.inverse().transform_point(&p.cast()).cast())
//!         .collect(),
//! );
//! let found = register(&source, &target, &Pose3::identity(), &RegistrationConfig::default())?;
//! let error = truth.inverse() * found.target_from_source;
//! assert!(found.converged);
//! assert!(error.translation().norm() < 0.01 && error.rotation().angle() < 1e-3);
//! # Ok::<(), raypath_registration::RegistrationError>(())
//! ```
//!
//! `cargo xtask eval registration` runs frame-to-frame registration and the odometry on the
//! real KITTI frames against their poses (`docs/results/registration.md`); `raypath register`
//! registers two scans or a KITTI sequence of your own.
//!
//! ## References
//!
//! * Y. Chen, G. Medioni, "Object modelling by registration of multiple range images",
//!   Image and Vision Computing 10(3), 1992.
//! * K.-L. Low, "Linear Least-Squares Optimization for Point-to-Plane ICP Surface
//!   Registration", UNC Chapel Hill TR04-004, 2004.
//! * I. Vizzo, T. Guadagnino, B. Mersch, L. Wiesmann, J. Behley, C. Stachniss, "KISS-ICP: In
//!   Defense of Point-to-Point ICP – Simple, Accurate, and Robust Registration If Done the
//!   Right Way", IEEE Robotics and Automation Letters 8(2), 2023.
//! * H. Hoppe et al., "Surface reconstruction from unorganized points", SIGGRAPH 1992 (PCA
//!   normals); M. Pauly, M. Gross, L. Kobbelt, "Efficient simplification of point-sampled
//!   surfaces", IEEE Visualization 2002 (surface variation).

mod adaptive;
mod config;
mod error;
mod icp;
mod local_map;
mod normals;
mod odometry;
mod preprocess;
pub mod report;
mod target;

pub use adaptive::AdaptiveThreshold;
pub use config::{Kernel, OdometryConfig, RegistrationConfig};
pub use error::{RegistrationError, Result};
pub use icp::{Gate, Registration, align, register, source_points};
pub use normals::surface_normals;
pub use odometry::{Odometry, OdometryStep};
pub use target::Target;
