//! # raypath-polylines: maximum-likelihood polylines from 2-D laser scans
//!
//! A 2-D scan of a building is a few hundred endpoints along walls. A handful of polylines
//! describes it to millimetres at a fraction of the memory. This crate extracts them the
//! way Schaefer (2020, *Highly Accurate Lidar-Based Mapping and Localization for Mobile
//! Robots*, chapter 10; Schaefer, Büscher, Luft and Burgard, IROS 2018) does: **maximize the
//! likelihood of the measured ray radii** under a Gaussian radial noise model, with the
//! errors measured **along each ray** to its first hit on the polylines (not perpendicular
//! to the lines, as classical line fitters do).
//!
//! * **PLE** ([`Method::Ple`]): Algorithm 1. Connect neighbouring endpoints (skip no-returns,
//!   break at gaps over `l_max`), then greedily remove the vertex whose removal lowers the
//!   likelihood least (Eq. 10.3), recomputing only the neighbours' errors (a priority queue),
//!   until `J_max` vertices remain. Removing an end vertex charges the placeholder residual
//!   `d_rm` to every ray its segment explained.
//! * **PLE+** ([`Method::PlePlus`]): PLE, then move the vertices to maximize the likelihood
//!   (Eq. 10.4) with the topology fixed: interior vertices move freely, the ends of an open
//!   polyline slide along their rays (`2(J − I)` parameters). The thesis uses Nelder–Mead;
//!   the default here is Levenberg–Marquardt with the analytic Jacobian of the ray–segment
//!   distance, which reaches a lower RMSE in a fraction of the time (see
//!   `docs/results/polylines.md`); [`Optimizer::NELDER_MEAD`] reproduces the thesis.
//! * Baselines with the same interface: Visvalingam simplification ([`Method::Vvl`]),
//!   iterative end-point fit ([`Method::Ief`]) and split-and-merge ([`Method::Sam`]).
//! * Metrics ([`metrics`]): RMSE of the ray radii, the fraction `f` of reflected rays the
//!   map explains, and for simulated scans the area error `a` (both denominators) and IoU.
//!
//! Frames and units: everything is in the scan (sensor) frame — REP-103, x forward, y left,
//! the sensor at the origin — in metres and radians. Beams whose range is not finite, not
//! positive or at/above the scan's maximum range are no-returns; they never become
//! vertices and are not scored.
//!
//! ```
//! use raypath_geometry::Scan2;
//! use raypath_polylines::{extract, metrics, Method, PolylineConfig};
//!
//! // A 4 m × 4 m room seen from its centre by 360 beams.
//! let ranges = (0..360)
//!     .map(|i| {
//!         let a = -std::f64::consts::PI + (i as f64).to_radians();
//!         2.0 / a.cos().abs().max(a.sin().abs())
//!     })
//!     .collect();
//! let scan = Scan2 {
//!     angle_min_rad: -std::f64::consts::PI,
//!     angle_increment_rad: 1f64.to_radians(),
//!     max_range_m: 30.0,
//!     ranges,
//!     intensities: None,
//! };
//! let config = PolylineConfig::new(Method::Ple, 4);
//! let map = extract(&scan, &config)?;
//! assert_eq!(map.vertex_count(), 4);
//! let m = metrics::ray_metrics(&scan, &map)?;
//! assert!(m.f == 1.0 && m.rmse_m < 0.05);
//! # Ok::<(), raypath_polylines::PolylineError>(())
//! ```
//!
//! ## Crate map
//!
//! | module | content |
//! |---|---|
//! | `rays` | the scan as unit rays from the sensor; which beams a segment can hit (O(1) by angle) |
//! | `initial` | Algorithm 1 lines 1–10: polylines through neighbouring endpoints |
//! | `ple` | Algorithm 1 lines 11–21: greedy removal with a lazily updated heap |
//! | `optimize` | PLE+: Levenberg–Marquardt (default) and Nelder–Mead |
//! | `baselines` | VVL, IEF, SAM |
//! | [`metrics`] | RMSE, f, area error a (both denominators), IoU |
//! | `svg` (feature `svg`) | a picture of scan and polylines, with axes |
//!
//! ## Defaults and their sources
//!
//! `J_max` = 10 (reference implementation default; the thesis evaluates 10…50), `l_max` =
//! 1 m and `d_rm` = 0.5 m (thesis experiments), Σ = 1 m² (irrelevant when constant),
//! `e_max` = ∞, IEF/SAM split threshold 0.01 m (reference implementation), Nelder–Mead
//! `TolX` = `TolFun` = 1e-2 and 200·dim iterations (MATLAB `fminsearch` as called by the
//! reference implementation).
//!
//! ## Measured performance
//!
//! `cargo bench -p raypath-polylines` times PLE and PLE+ (Levenberg–Marquardt and
//! Nelder–Mead) per scan on 20 Intel scans; `cargo xtask eval polylines` compares every
//! method's RMSE and speed on real and simulated scans, beside the thesis' figures:
//! `docs/results/polylines.md` has the figures, including why Levenberg–Marquardt is the
//! default optimizer.
//!
//! ## Decisions on the thesis' open points
//!
//! * Eq. (10.2) says `J = J_max`; Algorithm 1 stops at `J ≤ J_max` — a removed two-vertex
//!   polyline can undershoot by one. We follow Algorithm 1.
//! * The end-vertex error follows the reference implementation (`rmverror`): the beam
//!   through the neighbouring vertex stays explained. A beam that the shortcut segment
//!   misses (non-star-shaped corner) is charged `d_rm`.
//! * PLE+ optimizes each polyline separately over the beams that hit it before
//!   optimization, like the reference implementation; a beam that would lose its hit is
//!   charged `d_rm` instead of being dropped, so the optimizer cannot gain by uncovering
//!   rays, and `f` of PLE and PLE+ agree.
//! * The area error `a` is reported with both denominators: the estimated area (as
//!   printed) and the ground-truth area (as implemented); IoU besides.
//! * `l_max`: 1 m by default (thesis text); the evaluation uses ∞ on simulated polygons
//!   like the reference implementation (the polygons are closed anyway).
//! * A scan is a closed revolution when the gap between its last and first beam is at most
//!   4π/K (reference implementation); its endpoints then form one polygon.
//! * Baselines: IEF and SAM drop the no-returns and run on one sequence of all remaining
//!   endpoints (thesis); IEF splits at the endpoint farthest from its segment, SAM at the
//!   endpoint farthest from the piece's total-least-squares line, then merges pieces whose
//!   joint fit stays within 0.01 m; SAM's vertices are intersections of neighbouring lines
//!   (the mean of the break point's projections when the lines are nearly parallel or meet
//!   more than 1 m away). VVL removes Visvalingam's smallest effective triangle area;
//!   a lone two-vertex polyline vanishes at cost 0 (thesis: "solitary segments are removed
//!   at zero cost").

mod baselines;
mod config;
mod error;
mod initial;
pub mod metrics;
mod optimize;
mod ple;
mod polyline;
mod rays;
pub mod report;
#[cfg(feature = "svg")]
pub mod svg;

pub use config::{Method, Optimizer, PolylineConfig};
pub use error::PolylineError;
pub use polyline::{Polyline, Polylines};

use raypath_geometry::Scan2;

use crate::rays::ScanRays;

/// Extracts polylines from `scan` with `config.method`, at most `config.max_vertices`
/// vertices, in the scan frame.
///
/// An empty scan, a scan without returns or one beam gives an empty map (not an error).
pub fn extract(scan: &Scan2, config: &PolylineConfig) -> Result<Polylines, PolylineError> {
    config.validate()?;
    let rays = ScanRays::new(scan)?;
    Ok(match config.method {
        Method::Ple => ple_on(&rays, config),
        Method::PlePlus => {
            let mut map = ple_on(&rays, config);
            optimize::optimize(&rays, &mut map, config);
            map
        }
        Method::Vvl => baselines::vvl(&rays, config),
        Method::Ief => baselines::ief(&rays, config),
        Method::Sam => baselines::sam(&rays, config),
    })
}

/// PLE+ on an existing map: moves the vertices of `map` (extracted from `scan`, e.g. by
/// PLE) to lower the squared ray-radius error, topology fixed.
pub fn optimize(
    scan: &Scan2,
    map: &mut Polylines,
    config: &PolylineConfig,
) -> Result<(), PolylineError> {
    config.validate()?;
    let rays = ScanRays::new(scan)?;
    optimize::optimize(&rays, map, config);
    Ok(())
}

fn ple_on(rays: &ScanRays, config: &PolylineConfig) -> Polylines {
    let chains = initial::initial_chains(rays, config.max_edge_m);
    ple::simplify(
        rays,
        &chains,
        ple::Greedy {
            max_vertices: config.max_vertices,
            removed_residual_m: config.removed_residual_m,
            variance_m2: config.radial_variance_m2,
            max_error_increase: config.max_error_increase,
        },
    )
}
