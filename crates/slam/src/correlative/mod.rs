//! Correlative scan-to-submap matching with branch and bound, for loop-closure verification
//! (Olson, "Real-time correlative scan matching", ICRA 2009; Hess, Kohler, Rapp, Andor,
//! "Real-time loop closure in 2D LIDAR SLAM", ICRA 2016, §V).
//!
//! The search space is a regular lattice of poses around an initial guess: translations in
//! steps of the grid resolution `r` within `±W_x`, rotations in steps `δθ` within `±W_θ`,
//! with Hess's `δθ = arccos(1 − r² / (2 d_max²))` (the step that moves the farthest
//! point, at `d_max`, by at most one cell). A pose's score is the mean grid probability at
//! the scan's points (Hess §V, the score of a pose). [`match_scan_brute_force`] scores every lattice pose;
//! [`match_scan`] finds the same optimum by branch and bound over the translations of each
//! rotation (Hess §V): a node covers `2^h × 2^h` translations and is bounded by the
//! [`PrecomputedGrids`] level `h`, whose cells hold the maximum over the `2^h × 2^h` window
//! starting there; nodes are explored depth first, best child first, and pruned against the
//! best score so far, which starts at [`CorrelativeConfig::min_score`].
//!
//! Build [`PrecomputedGrids`] once per frozen submap and reuse it for every query. Subsample
//! the scan beforehand (for example a voxel filter): the cost is linear in the points.
//!
//! ```
//! use raypath_geometry::Pose2;
//! use raypath_slam::correlative::{
//!     CorrelativeConfig, PrecomputedGrids, ProbabilityGrid, SearchWindow, match_scan,
//! };
//! // A 4 m × 3 m room at 5 cm whose walls are the border cells.
//! let (w, h) = (80, 60);
//! let values: Vec<f32> = (0..w * h)
//!     .map(|k| {
//!         let (i, j) = (k % w, k / w);
//!         if i == 0 || j == 0 || i == w - 1 || j == h - 1 { 0.9 } else { 0.1 }
//!     })
//!     .collect();
//! let grid = ProbabilityGrid::new(0.05, [-2.0, -1.5], w, h, values)?;
//! let grids = PrecomputedGrids::new(&grid, 7);
//! // Points in the wall cells (sensor at the room's centre), and a guess 0.3 m off.
//! let points: Vec<[f64; 2]> = (0..80)
//!     .map(|k| {
//!         let t = k as f64 / 80.0;
//!         match k % 4 {
//!             0 => [-1.9 + 3.8 * t, 1.475],
//!             1 => [-1.9 + 3.8 * t, -1.475],
//!             2 => [1.975, -1.4 + 2.8 * t],
//!             _ => [-1.975, -1.4 + 2.8 * t],
//!         }
//!     })
//!     .collect();
//! let window = SearchWindow { linear_m: 0.5, angular_rad: 0.2 };
//! let found = match_scan(&grids, &points, Pose2::new(0.3, 0.0, 0.0), &window,
//!     &CorrelativeConfig::default()).expect("a match");
//! assert!(found.submap_from_sensor.translation().norm() < 0.051);
//! assert!(found.score > 0.85);
//! # Ok::<(), raypath_slam::SlamError>(())
//! ```

mod grid;
mod precompute;
mod search;
#[cfg(test)]
mod tests;

use raypath_geometry::Pose2;
use serde::{Deserialize, Serialize};

use crate::error::{Result, SlamError};

pub use grid::{ProbabilityGrid, UNKNOWN_PROBABILITY};
pub use precompute::{MAX_DEPTH, PrecomputedGrids};
pub use search::MAX_DISCRETE_POINTS;

/// The search window: `±linear_m` in x and y and `±angular_rad` around the initial pose.
///
/// Default: Cartographer's 2-D constraint builder (Hess et al. 2016): 7 m and 30°.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SearchWindow {
    /// Half-width of the translation window in x and y, metres (Hess's `W_x`, `W_y`).
    pub linear_m: f64,
    /// Half-width of the rotation window, radians (`W_θ`); at most π is searched.
    pub angular_rad: f64,
}

impl Default for SearchWindow {
    fn default() -> Self {
        Self {
            linear_m: 7.0,
            angular_rad: 30f64.to_radians(),
        }
    }
}

impl SearchWindow {
    /// Checks that both half-widths are finite and non-negative.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("linear_m", self.linear_m),
            ("angular_rad", self.angular_rad),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(SlamError::InvalidParameter {
                    name,
                    reason: format!("must be finite and non-negative, got {v}"),
                });
            }
        }
        Ok(())
    }
}

/// Parameters of the branch-and-bound matcher.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CorrelativeConfig {
    /// Number of precomputed levels (`h = 0 … depth − 1`) to build, and at most to search with
    /// (a search uses `min(depth, grids.depth())` levels). Default 7 (Hess et al. 2016,
    /// Cartographer's `branch_and_bound_depth`).
    pub depth: usize,
    /// The smallest score accepted as a match, in `[0, 1]`. Default 0.55 (Cartographer's
    /// `min_score` for loop-closure constraints).
    pub min_score: f64,
    /// The rotation step; `None` uses Hess's step for the scan's farthest point (see
    /// [`hess_angular_step`]).
    pub angular_step_rad: Option<f64>,
}

impl Default for CorrelativeConfig {
    fn default() -> Self {
        Self {
            depth: 7,
            min_score: 0.55,
            angular_step_rad: None,
        }
    }
}

impl CorrelativeConfig {
    /// Checks `depth` in `1 ..= MAX_DEPTH`, `min_score` in `[0, 1]` and a positive finite
    /// step when one is given.
    pub fn validate(&self) -> Result<()> {
        let bad = |name, reason: String| Err(SlamError::InvalidParameter { name, reason });
        if !(1..=MAX_DEPTH).contains(&self.depth) {
            return bad(
                "depth",
                format!("must be 1–{MAX_DEPTH}, got {}", self.depth),
            );
        }
        if !(0.0..=1.0).contains(&self.min_score) {
            return bad(
                "min_score",
                format!("must lie in [0, 1], got {}", self.min_score),
            );
        }
        if let Some(step) = self.angular_step_rad {
            crate::error::require_positive("angular_step_rad", step)?;
        }
        Ok(())
    }

    /// The rotation step used for `points` on a grid of `resolution_m`: the configured one,
    /// or Hess's step ([`hess_angular_step`]).
    pub fn angular_step(&self, points: &[[f64; 2]], resolution_m: f64) -> f64 {
        self.angular_step_rad.unwrap_or_else(|| {
            let d_max = points
                .iter()
                .map(|p| p[0].hypot(p[1]))
                .filter(|d| d.is_finite())
                .fold(0.0, f64::max);
            hess_angular_step(resolution_m, d_max)
        })
    }
}

/// Hess et al. 2016 §V: `δθ = arccos(1 − r² / (2 d_max²))`, the rotation that moves a
/// point at `d_max` by one cell `r`; π when `d_max < r / 2` (a single rotation suffices).
pub fn hess_angular_step(resolution_m: f64, max_range_m: f64) -> f64 {
    let ratio = resolution_m * resolution_m / (2.0 * max_range_m * max_range_m);
    (1.0 - ratio).clamp(-1.0, 1.0).acos() // Hess et al. 2016 §V, δθ
}

/// The result of a correlative search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CorrelativeMatch {
    /// The best lattice pose of the scan in the submap frame.
    pub submap_from_sensor: Pose2,
    /// Mean probability of the points at that pose (Hess §V), in `[0, 1]`.
    pub score: f64,
    /// Number of candidates scored (all levels for branch and bound).
    pub candidates_scored: usize,
}

/// The best pose of `points` (sensor frame, metres) in the submap frame within `window`
/// around `initial`, or `None` when no pose reaches `config.min_score`.
///
/// Exhaustive-equivalent: the same optimum (pose and score, ties broken towards the initial
/// guess) as [`match_scan_brute_force`] over the same lattice, with the step of
/// [`CorrelativeConfig::angular_step`]. A pose must put at least one point on the grid.
/// Non-finite points count as misses. Also `None` for an invalid query: no points, a
/// non-finite `initial`, a window or config that fails `validate`, an empty grid, or more
/// than [`MAX_DISCRETE_POINTS`] (rotation, point) pairs.
pub fn match_scan(
    grids: &PrecomputedGrids,
    points: &[[f64; 2]],
    initial: Pose2,
    window: &SearchWindow,
    config: &CorrelativeConfig,
) -> Option<CorrelativeMatch> {
    config.validate().ok()?;
    let grid = grids.grid();
    let step = config.angular_step(points, grid.resolution_m());
    let scans = search::DiscreteScans::new(grid, points, initial, window, step)?;
    search::branch_and_bound(grids, &scans, config.min_score, config.depth)
}

/// Brute force over the same lattice as [`match_scan`] (the reference for tests and
/// ablations): every rotation `θ₀ + k·angular_step_rad`, every translation offset, scored on
/// `grid`. `None` as for [`match_scan`].
pub fn match_scan_brute_force(
    grid: &ProbabilityGrid,
    points: &[[f64; 2]],
    initial: Pose2,
    window: &SearchWindow,
    min_score: f64,
    angular_step_rad: f64,
) -> Option<CorrelativeMatch> {
    let scans = search::DiscreteScans::new(grid, points, initial, window, angular_step_rad)?;
    search::brute_force(grid, &scans, min_score)
}
