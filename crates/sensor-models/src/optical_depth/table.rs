//! The cumulative optical-depth table: line integrals of a 2-D cell field in O(1).

use std::f64::consts::PI;

use nalgebra::{Point2, Unit, Vector2};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use raypath_geometry::Grid2;

use crate::SensorModelError;

/// Configuration of an [`OpticalDepthTable`].
///
/// Defaults: 360 directions over `[0, π)` (0.5° apart), samples one cell apart along and
/// across the lines, and blending of the two nearest directions (twice the look-ups, much
/// smaller error for long rays; see the crate docs for measured errors and speeds).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OpticalDepthConfig {
    /// Number of directions `D` over `[0, π)`; a ray in direction `θ + π` uses the table of
    /// `θ` backwards.
    pub directions: usize,
    /// Sample spacing along and across the lines, in cells.
    pub spacing_cells: f64,
    /// Interpolate linearly between the two nearest directions instead of taking the
    /// nearest one.
    pub blend_directions: bool,
}

impl Default for OpticalDepthConfig {
    fn default() -> Self {
        Self {
            directions: 360,
            spacing_cells: 1.0,
            blend_directions: true,
        }
    }
}

/// One direction: the map sampled on lines `v = v0 + j·s` (across) at `u = u0 + k·s`
/// (along), with `u = p·(cos θ, sin θ)` and `v = p·(−sin θ, cos θ)` for a point `p`
/// relative to the grid origin.
#[derive(Clone, Debug)]
struct Direction {
    cos: f64,
    sin: f64,
    u0: f64,
    v0: f64,
    n_u: usize,
    n_v: usize,
    /// Offset of this direction's samples in the shared value array.
    offset: usize,
}

impl Direction {
    /// The sample lattice of direction `theta` covering `grid`, one sample spacing beyond
    /// the box on every side (`offset` 0).
    fn layout(grid: &Grid2, theta: f64, spacing_m: f64) -> Self {
        let (sin, cos) = theta.sin_cos();
        let extent = grid.bounds().extents();
        // Projections of the box corners (relative to the origin) onto u and v.
        let corners = [
            (0.0, 0.0),
            (extent.x, 0.0),
            (0.0, extent.y),
            (extent.x, extent.y),
        ];
        let (mut u_lo, mut u_hi, mut v_lo, mut v_hi) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for (x, y) in corners {
            let u = x * cos + y * sin;
            let v = -x * sin + y * cos;
            u_lo = u_lo.min(u);
            u_hi = u_hi.max(u);
            v_lo = v_lo.min(v);
            v_hi = v_hi.max(v);
        }
        let u0 = u_lo - spacing_m;
        let v0 = v_lo - spacing_m;
        Self {
            cos,
            sin,
            u0,
            v0,
            n_u: ((u_hi - u0) / spacing_m).ceil() as usize + 2,
            n_v: ((v_hi - v0) / spacing_m).ceil() as usize + 2,
            offset: 0,
        }
    }

    /// The direction angle θ ∈ [0, π).
    fn angle(&self) -> f64 {
        self.sin.atan2(self.cos)
    }
}

/// One finite, non-negative value per cell of `grid`.
fn check_field(grid: &Grid2, field: &[f64]) -> Result<(), SensorModelError> {
    if field.len() != grid.num_cells() {
        return Err(SensorModelError::GridMismatch {
            reason: format!(
                "{} field values for {} cells",
                field.len(),
                grid.num_cells()
            ),
        });
    }
    if field.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
        return Err(SensorModelError::InvalidParameter {
            name: "field",
            reason: "values must be finite and non-negative".into(),
        });
    }
    Ok(())
}

/// 1 to 65 536 directions and a sample spacing of 0.05 to 16 cells.
fn check_config(config: &OpticalDepthConfig) -> Result<(), SensorModelError> {
    if config.directions == 0 || config.directions > 1 << 16 {
        return Err(SensorModelError::InvalidParameter {
            name: "directions",
            reason: format!("need 1 to 65536, got {}", config.directions),
        });
    }
    if !(config.spacing_cells.is_finite()
        && config.spacing_cells >= 0.05
        && config.spacing_cells <= 16.0)
    {
        return Err(SensorModelError::InvalidParameter {
            name: "spacing_cells",
            reason: format!("need 0.05 to 16, got {}", config.spacing_cells),
        });
    }
    Ok(())
}

/// For `D` directions `θ_d = d·π/D`, the grid field `ρ(x)` (piecewise constant on cells)
/// integrated along parallel lines of direction `θ_d` from the grid border:
/// `C_d(u, v) = ∫_{−∞}^{u} ρ(u', v) du'` sampled on a rotated lattice (exact traversal of
/// each line, so samples are exact). The integral along a segment from `a` to `b` is then
/// `|C_d(u_b, v) − C_d(u_a, v)|`: two bilinear look-ups (on the line through the segment's
/// midpoint, in the nearest direction(s)) instead of a traversal.
///
/// Memory: about `D · n_u · n_v` `f32` values, `n_u, n_v ≤ √2 ·` the grid's larger side in
/// samples (a 400 × 400 grid with 360 directions: ≈ 460 MB).
#[derive(Clone, Debug)]
pub struct OpticalDepthTable {
    grid: Grid2,
    spacing_m: f64,
    blend: bool,
    directions: Vec<Direction>,
    values: Vec<f32>,
}

impl OpticalDepthTable {
    /// Tabulates `field` (one value per cell of `grid`, by linear index; per metre) times
    /// `scale(θ_d)` for every direction (the reflection model's cell counting uses
    /// `(|cos θ| + |sin θ|) / c`, others `1`). Parallel over directions.
    pub fn new(
        grid: &Grid2,
        field: &[f64],
        scale: impl Fn(f64) -> f64 + Sync,
        config: OpticalDepthConfig,
    ) -> Result<Self, SensorModelError> {
        check_field(grid, field)?;
        Self::build(grid, config, |direction, spacing_m| {
            let theta_scale = scale(direction.angle());
            Ok(tabulate(grid, field, direction, spacing_m, theta_scale))
        })
    }

    /// Tabulates a direction-dependent field: `field(θ_d)` returns, for the direction
    /// `θ_d ∈ [0, π)`, one value per cell of `grid` (by linear index; per metre, finite and
    /// non-negative). For integrands that are not a fixed field times a factor of θ, such as
    /// the Gamma posterior's miss exponent per metre of a mean chord (see [`Tabulated`]'s
    /// decay-rate posterior). Called once per direction, in parallel.
    ///
    /// [`Tabulated`]: crate::Tabulated
    pub fn directional(
        grid: &Grid2,
        field: impl Fn(f64) -> Vec<f64> + Sync,
        config: OpticalDepthConfig,
    ) -> Result<Self, SensorModelError> {
        Self::build(grid, config, |direction, spacing_m| {
            let values = field(direction.angle());
            check_field(grid, &values)?;
            Ok(tabulate(grid, &values, direction, spacing_m, 1.0))
        })
    }

    /// Lays out the directions of `config` over `grid` and fills each with `tabulate_one`.
    fn build(
        grid: &Grid2,
        config: OpticalDepthConfig,
        tabulate_one: impl Fn(&Direction, f64) -> Result<Vec<f32>, SensorModelError> + Sync,
    ) -> Result<Self, SensorModelError> {
        check_config(&config)?;
        let spacing_m = config.spacing_cells * grid.cell_size();
        let mut directions: Vec<Direction> = (0..config.directions)
            .map(|d| Direction::layout(grid, d as f64 * PI / config.directions as f64, spacing_m))
            .collect();
        let mut total = 0usize;
        for direction in &mut directions {
            direction.offset = total;
            total = total.saturating_add(direction.n_u.saturating_mul(direction.n_v));
        }
        if total > 1 << 33 {
            return Err(SensorModelError::InvalidParameter {
                name: "optical-depth table",
                reason: format!("{total} samples (more than 2^33); use fewer directions"),
            });
        }
        let tables = directions
            .par_iter()
            .map(|direction| tabulate_one(direction, spacing_m))
            .collect::<Result<Vec<Vec<f32>>, _>>()?;
        let mut values = Vec::with_capacity(total);
        for table in tables {
            values.extend_from_slice(&table);
        }
        Ok(Self {
            grid: *grid,
            spacing_m,
            blend: config.blend_directions,
            directions,
            values,
        })
    }

    /// The grid.
    pub fn grid(&self) -> &Grid2 {
        &self.grid
    }

    /// Number of directions.
    pub fn num_directions(&self) -> usize {
        self.directions.len()
    }

    /// Heap memory of the samples in bytes.
    pub fn memory_bytes(&self) -> usize {
        self.values.len() * size_of::<f32>()
    }

    /// `∫ ρ` along the ray from `t0_m` to `t1_m` (both inside the grid box or on its border;
    /// `t0 ≤ t1`), approximated by the table (see the type docs).
    #[inline]
    pub fn integral(
        &self,
        origin: &Point2<f64>,
        direction: &Unit<Vector2<f64>>,
        t0_m: f64,
        t1_m: f64,
    ) -> f64 {
        let n = self.directions.len();
        let (dx, dy) = (direction.x, direction.y);
        // Direction angle folded into [0, π).
        let mut theta = dy.atan2(dx);
        if theta < 0.0 {
            theta += PI;
        }
        if theta >= PI {
            theta -= PI;
        }
        let position = theta * n as f64 / PI;
        // Points relative to the grid origin.
        let grid_origin = self.grid.origin();
        let ax = origin.x + dx * t0_m - grid_origin.x;
        let ay = origin.y + dy * t0_m - grid_origin.y;
        let bx = origin.x + dx * t1_m - grid_origin.x;
        let by = origin.y + dy * t1_m - grid_origin.y;
        if self.blend {
            let d0 = position.floor();
            let w = position - d0;
            let d0 = (d0 as usize) % n;
            let d1 = (d0 + 1) % n;
            (1.0 - w) * self.segment(d0, ax, ay, bx, by) + w * self.segment(d1, ax, ay, bx, by)
        } else {
            let d = (position.round() as usize) % n;
            self.segment(d, ax, ay, bx, by)
        }
    }

    /// `|C(u_b, v_m) − C(u_a, v_m)|` in direction `d`, `v_m` of the midpoint.
    #[inline(always)]
    fn segment(&self, d: usize, ax: f64, ay: f64, bx: f64, by: f64) -> f64 {
        let Some(direction) = self.directions.get(d) else {
            return 0.0;
        };
        let (c, s) = (direction.cos, direction.sin);
        let ua = ax * c + ay * s;
        let ub = bx * c + by * s;
        let vm = 0.5 * ((-ax * s + ay * c) + (-bx * s + by * c));
        (self.lookup(direction, ub, vm) - self.lookup(direction, ua, vm)).abs()
    }

    /// Bilinear look-up of `C` at `(u, v)`.
    #[inline(always)]
    fn lookup(&self, direction: &Direction, u: f64, v: f64) -> f64 {
        let fu = ((u - direction.u0) / self.spacing_m).clamp(0.0, (direction.n_u - 1) as f64);
        let fv = ((v - direction.v0) / self.spacing_m).clamp(0.0, (direction.n_v - 1) as f64);
        let k = (fu as usize).min(direction.n_u - 2);
        let j = (fv as usize).min(direction.n_v - 2);
        let wu = fu - k as f64;
        let wv = fv - j as f64;
        let row0 = direction.offset + j * direction.n_u + k;
        let row1 = row0 + direction.n_u;
        let value = |i: usize| f64::from(self.values.get(i).copied().unwrap_or(0.0));
        let c0 = value(row0) + wu * (value(row0 + 1) - value(row0));
        let c1 = value(row1) + wu * (value(row1 + 1) - value(row1));
        c0 + wv * (c1 - c0)
    }
}

/// The samples of one direction: every line traversed exactly through the grid.
fn tabulate(
    grid: &Grid2,
    field: &[f64],
    direction: &Direction,
    spacing_m: f64,
    scale: f64,
) -> Vec<f32> {
    let mut values = vec![0.0f32; direction.n_u * direction.n_v];
    let unit = Unit::new_unchecked(Vector2::new(direction.cos, direction.sin));
    let length = (direction.n_u - 1) as f64 * spacing_m;
    let origin = grid.origin();
    for (j, row) in values.chunks_mut(direction.n_u).enumerate() {
        let v = direction.v0 + j as f64 * spacing_m;
        // Line start: u = u0 on line v, back in map coordinates.
        let start = Point2::new(
            origin.x + direction.u0 * direction.cos - v * direction.sin,
            origin.y + direction.u0 * direction.sin + v * direction.cos,
        );
        let mut k = 0usize;
        let mut cumulative = 0.0f64;
        for crossing in grid.traverse(&start, &unit, length) {
            let rate = field.get(crossing.index).copied().unwrap_or(0.0) * scale;
            // Samples inside this crossing.
            while k < row.len() {
                let t = k as f64 * spacing_m;
                if t > crossing.t_exit {
                    break;
                }
                let inside = (t - crossing.t_enter).max(0.0);
                row[k] = (cumulative + rate * inside) as f32;
                k += 1;
            }
            cumulative += rate * crossing.length();
        }
        for value in row.iter_mut().skip(k) {
            *value = cumulative as f32;
        }
    }
    values
}
