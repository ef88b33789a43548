//! # raypath-planes: maximum-likelihood finite planes from organized 3-D scans
//!
//! PPE (Schaefer, Vertens, Büscher and Burgard, ICRA 2019; Schaefer 2020, *Highly Accurate
//! Lidar-Based Mapping and Localization for Mobile Robots*, chapter 11) segments an
//! organized lidar scan into finite planes by **maximizing the likelihood of the measured
//! ray radii**: the error of a ray is measured **along the ray** to the plane it is
//! assigned to (Eq. 11.1), not perpendicular to the plane. Agglomerative clustering
//! starts from one atomic plane per ray, seeds regular planes from tetrominoes of four
//! neighbours and always executes the create/extend/merge action that raises the error
//! least, until the least increment exceeds `e` ([`PpeParams`]).
//!
//! * [`extract`] / [`extract_grid`]: PPE on an organized cloud; [`TETROMINOES`]: its seeds.
//! * [`fit_plane`]: the exact radial least-squares plane ([`refine`]: by Gauss–Newton from a
//!   start); [`PlaneStats`]: its additive sufficient statistics used for the clustering
//!   decisions.
//! * [`compare`]: the Hoover et al. protocol with `T = 0.8`, k-value and angle deviation
//!   ([`angle_deviation`], [`folded_angle_deg`]).
//! * [`msac`]: the iterative MSAC baseline.
//! * [`peac`]: the PEAC-style block-graph AHC baseline of Feng et al. (2014).
//! * [`PpeParams::synpeb`], [`PpeParams::segcomp`]: presets of the two benchmarks.
//!
//! Decisions beyond the thesis: the presets `synpeb-<σ>` enable a post-processing of the
//! clustering result ([`PpeParams::refine_rounds`]: boundary refinement by the least radial
//! residual, merges of adjacent planes and of the pieces of a surface split by an occluder,
//! each within `e`); what it gains on the training scans is in `docs/results/synpeb.md`.
//! `PpeParams::default()` keeps the thesis' algorithm (no post-processing). The RMSE is
//! the per-ray radial RMSE of the reference implementation: Eq. (11.6) prints `√(E / J(L))`,
//! which divides by the number of planes; the reported values (mm, below the 20 mm noise) fit
//! a per-ray RMSE.
//!
//! Frames and units: the sensor frame (REP-103: x forward, y left, z up) with every ray
//! starting at the origin; metres; errors in m². Rays with non-finite coordinates or at the
//! origin are no-returns and never join a plane. The organized grid has `height` rows
//! (first index) of `width` columns (second index); neighbours are 4-connected.
//!
//! ```
//! use nalgebra::Vector3;
//! use raypath_planes::{extract_grid, PpeParams};
//!
//! // A 20 × 20 grid of rays onto the wall x = 3 m and the floor z = −1 m.
//! let mut points = Vec::new();
//! for row in 0..20 {
//!     for col in 0..20 {
//!         let v = Vector3::new(1.0, (col as f64 - 9.5) * 0.03, -(row as f64) * 0.03).normalize();
//!         let t_wall = 3.0 / v.x;
//!         let t_floor = if v.z < 0.0 { -1.0 / v.z } else { f64::INFINITY };
//!         points.push(v * t_wall.min(t_floor));
//!     }
//! }
//! let params = PpeParams { max_increment_m2: 1e-8, ..PpeParams::default() };
//! let seg = extract_grid(&points, 20, 20, &params).unwrap();
//! // The two largest planes are the wall (normal +x) and the floor (normal −z); rays
//! // at the corner are explained exactly by a third, sloped plane as well.
//! assert!(seg.planes[0].index.len() + seg.planes[1].index.len() >= 360);
//! let normals = [seg.planes[0].fit.normal(), seg.planes[1].fit.normal()];
//! assert!(normals.iter().any(|n| n.x > 0.999999) && normals.iter().any(|n| n.z < -0.999999));
//! assert!(seg.rmse_m() < 1e-6);
//! ```

mod error;
mod fit;
mod hoover;
mod msac;
mod params;
mod peac;
mod ppe;
pub mod report;
mod stats;
#[cfg(test)]
mod test_scenes;
mod tetromino;

pub use error::PlaneError;
pub use fit::{PlaneFit, fit_plane, radial_sse, refine};
pub use hoover::{HooverParams, HooverResult, angle_deviation, compare, folded_angle_deg};
pub use msac::{MsacParams, msac};
pub use params::PpeParams;
pub use peac::{PeacParams, peac};
pub use ppe::{Plane, Segmentation, extract, extract_grid};
pub use stats::PlaneStats;
pub use tetromino::TETROMINOES;
