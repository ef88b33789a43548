//! The multi-resolution occupancy + reflectivity map (Hector: Kohlbrecher et al. 2011 §IV-D;
//! Khan 2017 §3.4.1).
//!
//! Level 0 is the finest grid; level `l` has cells `2^l` times larger and covers the same
//! square of side [`MapConfig::size_m`] centred on the map origin. Every map update writes
//! all levels.

use raypath_geometry::Pose2;
use serde::{Deserialize, Serialize};

use crate::error::{ReflectivityError, Result, require_positive};
use crate::grid::{GridLevel, logit};
use crate::points::ScanPoints;

/// Map parameters. Defaults: Hector's update factors (free 0.4, occupied 0.9) and three
/// levels (hector_mapping; the thesis gives none); the finest cell is 5 cm, our working point
/// (Hector's node defaults to 2.5 cm).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MapConfig {
    /// Cell size of the finest level, metres.
    pub finest_resolution_m: f64,
    /// Number of levels (each coarser level doubles the cell size).
    pub levels: usize,
    /// Side of the square mapped area, metres, centred on the map-frame origin.
    pub size_m: f64,
    /// Occupancy probability added along a beam (Hector `update_factor_free` 0.4).
    pub update_factor_free: f64,
    /// Occupancy probability added at a beam's end point (Hector `update_factor_occupied` 0.9).
    pub update_factor_occupied: f64,
}

impl Default for MapConfig {
    fn default() -> Self {
        Self {
            finest_resolution_m: 0.05,
            levels: 3,
            size_m: 120.0,
            update_factor_free: 0.4,
            update_factor_occupied: 0.9,
        }
    }
}

impl MapConfig {
    /// Checks the parameters (positive sizes, 1–8 levels, factors in (0, 1), at most 2¹⁶
    /// cells per side).
    pub fn validate(&self) -> Result<()> {
        require_positive("finest_resolution_m", self.finest_resolution_m)?;
        require_positive("size_m", self.size_m)?;
        let bad = |name, reason: String| Err(ReflectivityError::InvalidParameter { name, reason });
        if !(1..=8).contains(&self.levels) {
            return bad("levels", format!("must be 1–8, got {}", self.levels));
        }
        let cells = self.size_m / self.finest_resolution_m;
        if !(4.0..=65536.0).contains(&cells) {
            return bad(
                "size_m",
                format!("gives {cells:.0} cells per side (4 … 65536)"),
            );
        }
        for (name, p) in [
            ("update_factor_free", self.update_factor_free),
            ("update_factor_occupied", self.update_factor_occupied),
        ] {
            if !(p > 0.0 && p < 1.0) {
                return bad(name, format!("must lie in (0, 1), got {p}"));
            }
        }
        Ok(())
    }
}

/// The multi-resolution map.
#[derive(Clone, Debug)]
pub struct MultiResMap {
    levels: Vec<GridLevel>,
    updates: u32,
    delta_free: f32,
    delta_occupied: f32,
}

impl MultiResMap {
    /// An unknown map.
    pub fn new(config: &MapConfig) -> Result<Self> {
        config.validate()?;
        let cells = (config.size_m / config.finest_resolution_m).ceil() as usize;
        let levels = (0..config.levels)
            .map(|l| {
                let res = config.finest_resolution_m * f64::from(1u32 << l);
                let n = cells.div_ceil(1 << l).max(2);
                let half = n as f64 * res / 2.0;
                GridLevel::new(res, [-half, -half], n, n)
            })
            .collect();
        Ok(Self {
            levels,
            updates: 0,
            delta_free: logit(config.update_factor_free),
            delta_occupied: logit(config.update_factor_occupied),
        })
    }

    /// The levels, finest first.
    pub fn levels(&self) -> &[GridLevel] {
        &self.levels
    }

    /// The levels cut to the observed part of the finest level plus `margin` finest cells
    /// ([`crate::export::observed_box`], [`GridLevel::crop`]): a compact frozen copy of a
    /// finished submap that [`crate::match_levels`] can still match against. `None` when
    /// nothing was observed.
    pub fn cropped_levels(&self, margin: usize) -> Option<Vec<GridLevel>> {
        let finest = self.levels.first()?;
        let b = crate::export::observed_box(finest, margin)?;
        let (res, o) = (finest.resolution_m(), finest.origin());
        let lo = [o[0] + b[0] as f64 * res, o[1] + b[1] as f64 * res];
        let hi = [o[0] + b[2] as f64 * res, o[1] + b[3] as f64 * res];
        Some(
            self.levels
                .iter()
                .map(|level| {
                    let (r, lo_l) = (level.resolution_m(), level.origin());
                    let cell = |v: f64, o: f64| ((v - o) / r).floor().max(0.0) as usize;
                    level.crop([
                        cell(lo[0], lo_l[0]),
                        cell(lo[1], lo_l[1]),
                        cell(hi[0], lo_l[0]) + 2,
                        cell(hi[1], lo_l[1]) + 2,
                    ])
                })
                .collect(),
        )
    }

    /// Number of map updates so far.
    pub fn updates(&self) -> u32 {
        self.updates
    }

    /// Integrates a scan taken at `world_from_sensor`: occupied end points (with their
    /// reflectivity, when finite) and free cells along each beam, on every level.
    pub fn update(&mut self, world_from_sensor: &Pose2, scan: &ScanPoints) {
        let base = GridLevel::stamp_base(self.updates);
        let (c, s) = (
            world_from_sensor.theta().cos(),
            world_from_sensor.theta().sin(),
        );
        let (tx, ty) = (world_from_sensor.x(), world_from_sensor.y());
        let world = |p: &[f64; 2]| (c * p[0] - s * p[1] + tx, s * p[0] + c * p[1] + ty);
        for level in &mut self.levels {
            for (p, &refl) in scan.points().iter().zip(scan.reflectivity()) {
                let (x, y) = world(p);
                if let Some(cell) = level.cell_of(x, y) {
                    level.mark_occupied(cell, self.delta_occupied, base);
                    if refl.is_finite() {
                        level.add_reflectivity(cell, refl);
                    }
                }
            }
            let Some(sensor) = level.cell_of(tx, ty) else {
                continue;
            };
            for p in scan.points() {
                let (x, y) = world(p);
                let end = level.cell_i64(x, y);
                level.mark_free_line(sensor, end, self.delta_free, base);
            }
        }
        self.updates = self.updates.wrapping_add(1);
    }
}
