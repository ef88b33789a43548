//! # raypath-sim
//!
//! A lidar simulator and generated data sets that stand in for the benchmarks raypath cannot
//! download here (KITTI and NCLT scans, SegComp, the full SynPEB) and extend the real 2-D logs.
//! Every generator writes the **real formats** (CARMEN logs, KITTI and NCLT layouts, PCD), so
//! evaluations read simulated and real data through the same `raypath-io` readers.
//!
//! * **Exact ray casting** against scene geometry tagged with surfaces (ground-truth labels,
//!   reflectivity): parry2d-f64 in 2-D ([`scene2`]); in 3-D ([`scene3`]) an own SAH BVH over
//!   the triangles with f64 Möller–Trumbore tests, about 1.5× parry3d's `TriMesh` on the urban
//!   scene and cross-checked against it in the tests.
//! * **Deterministic by seed**: the same seed writes byte-identical files, whatever the number
//!   of threads ([`rng::stream`] gives every work item its own random stream).
//! * **Parallel** with rayon at the outer level (scans, rows of rays); no allocation per ray.
//!
//! ## What it simulates
//!
//! | module | scene | sensor | written as | thesis |
//! | --- | --- | --- | --- | --- |
//! | [`polygons`] | random polygons (n ∈ {3, 4, 5, 6, 12, 36, 180}) | 360 rays, σ 0.2° / 3 cm | CARMEN `ROBOTLASER1` + JSON truth | Schaefer ch. 10 |
//! | [`indoor`] | floor plans, doors, glass, clutter; a robot path | 2-D laser, odometry drift, intensities | corrected + raw CARMEN logs | Schaefer ch. 9–10, Khan ch. 3 |
//! | [`corridor`] | 1-D corridor of 100 voxels | Bernoulli / exponential beams | JSON + CSV | Schaefer ch. 8 |
//! | [`synpeb`] | rooms of polyhedral objects | organized 500 × 500, σ 1 mdeg, 0–4 cm | PCD, label in `intensity` | Schaefer ch. 11 |
//! | [`segcomp`] | blocks, wedges, prisms on a table (SegComp-like) | Perceptron 512 × 512, σ 1 mm / cos θ, mixed pixels, calibration kink | in memory (SegComp range image, labels, angles) | Schaefer ch. 11 |
//! | [`urban`] | streets, facades, poles, trees, cars; sessions with changes | HDL-64E / HDL-32E ([`lidar3`]) | KITTI / NCLT layouts + poles | Schaefer ch. 12 |
//! | [`semi_kitti`] | streets around a real KITTI drive and pole map | HDL-64E | KITTI layout + poles | Schaefer ch. 12 |
//! | [`semi_nclt`] | a campus around the real NCLT pole layout and path; sessions with changes | HDL-32E | in memory (scans on demand) | Schaefer ch. 12 |
//!
//! [`datasets`] names the embedded default sets (`cargo xtask datasets generate`); the
//! `raypath simulate` command runs any generator on user parameters.
//!
//! ## Usage
//!
//! ```
//! use nalgebra::{Point3, Vector3};
//! use raypath_geometry::Pose3;
//! use raypath_sim::lidar3::Lidar3;
//! use raypath_sim::scene3::{SceneBuilder3, Surface};
//!
//! // A 20 m × 20 m × 6 m hall, seen from inside by an HDL-32E 1.5 m above the floor.
//! let mut builder = SceneBuilder3::new();
//! let wall = builder.add_surface(Surface { label: 10, reflectivity: 0.5 });
//! builder.add_box(&Pose3::identity(), Vector3::new(10.0, 10.0, 3.0), [wall; 6]);
//! let scene = builder.build()?;
//! let lidar = Lidar3::hdl32e();
//! let world_from_sensor = Pose3::from_xyz_rpy(0.0, 0.0, -1.5, 0.0, 0.0, 0.0);
//! let scan = lidar.scan(&scene, &world_from_sensor, 42, 0)?;
//! assert_eq!(scan.cloud.height, 32);
//! // Every beam hits the closed hall; dropout and weak returns lose well under 1 %.
//! assert!(scan.cloud.num_valid() as f64 > 0.99 * scan.cloud.len() as f64);
//! # Ok::<(), raypath_sim::SimError>(())
//! ```

pub mod corridor;
mod dataset;
pub mod datasets;
mod error;
pub mod indoor;
pub mod lidar3;
mod out2d;
pub mod polygons;
pub mod rng;
pub mod scene2;
pub mod scene3;
pub mod segcomp;
pub mod semi_kitti;
pub mod semi_nclt;
pub mod synpeb;
pub mod urban;

pub use dataset::{GeneratedSet, Progress, SET_MANIFEST, in_generated_set, no_progress};
pub use error::{Result, SimError};
