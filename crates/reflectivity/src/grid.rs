//! One level of the occupancy + reflectivity grid (Khan 2017 §3.4.1).
//!
//! A square grid of `width × height` cells of `resolution_m`; cell `(i, j)` covers
//! `[x₀ + i·res, x₀ + (i+1)·res) × [y₀ + j·res, y₀ + (j+1)·res)` in the map frame (REP-103,
//! metres) and its value sits at the cell centre. Per cell:
//!
//! * occupancy as log-odds `L`, updated Hector-style: `L += logit(0.9)` at a beam's end point,
//!   `L += logit(0.4)` in the cells the beam crosses (Bresenham), each cell at most once per
//!   scan, clamped to ±[`LOG_ODDS_LIMIT`] (Hector's limit of 50);
//! * the incremental mean of relative reflectivity `R_m(g) ← R_m(g) + (ϱ̄ − R_m(g)) / n_g`
//!   over the end points that fall into the cell (§3.4.1), with its count `n_g`.
//!
//! Sampling ([`GridLevel::occupancy`], [`GridLevel::reflectivity`]) is the consistent
//! bilinear interpolation of the four surrounding cell centres with its analytic gradient
//! (per metre) — the corrected form of the thesis' formulas (§3.4.1: the printed value formula
//! permutes the four weights, and the `∂R/∂y` denominator reads `x_i − x_i` for `x_j − x_i`).

/// Hector's clamp of the log-odds (`GridMapLogOddsFunctions`: ±50).
pub const LOG_ODDS_LIMIT: f32 = 50.0;

/// A bilinear sample: value and gradient with respect to the map position (per metre).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// The interpolated value.
    pub value: f64,
    /// ∂value/∂x and ∂value/∂y, per metre.
    pub gradient: [f64; 2],
}

/// One resolution level of the map.
#[derive(Clone, Debug)]
pub struct GridLevel {
    resolution_m: f64,
    origin: [f64; 2],
    width: usize,
    height: usize,
    log_odds: Vec<f32>,
    stamp: Vec<u32>,
    refl_mean: Vec<f32>,
    refl_count: Vec<u32>,
}

/// Log-odds of a probability.
pub fn logit(p: f64) -> f32 {
    (p / (1.0 - p)).ln() as f32
}

/// Probability of a log-odds value.
#[inline]
pub fn probability(log_odds: f32) -> f64 {
    1.0 / (1.0 + (-f64::from(log_odds)).exp())
}

impl GridLevel {
    /// An unknown (log-odds 0) grid of `width × height` cells whose cell `(0, 0)` has its lower
    /// corner at `origin` (map frame, metres).
    pub fn new(resolution_m: f64, origin: [f64; 2], width: usize, height: usize) -> Self {
        let n = width * height;
        Self {
            resolution_m,
            origin,
            width,
            height,
            log_odds: vec![0.0; n],
            stamp: vec![0; n],
            refl_mean: Vec::new(),
            refl_count: Vec::new(),
        }
    }

    /// Cell size in metres.
    pub fn resolution_m(&self) -> f64 {
        self.resolution_m
    }

    /// Map-frame position of the lower corner of cell `(0, 0)`, metres.
    pub fn origin(&self) -> [f64; 2] {
        self.origin
    }

    /// Number of cells along x.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Number of cells along y.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Whether the reflectivity channel exists (after the first reflectivity update).
    pub fn has_reflectivity(&self) -> bool {
        !self.refl_count.is_empty()
    }

    /// The cell containing map-frame point `(x, y)`, if inside the grid.
    pub fn cell_of(&self, x: f64, y: f64) -> Option<(usize, usize)> {
        let cx = ((x - self.origin[0]) / self.resolution_m).floor();
        let cy = ((y - self.origin[1]) / self.resolution_m).floor();
        if cx >= 0.0 && cy >= 0.0 && cx < self.width as f64 && cy < self.height as f64 {
            Some((cx as usize, cy as usize))
        } else {
            None
        }
    }

    fn index(&self, i: usize, j: usize) -> usize {
        j * self.width + i
    }

    /// Log-odds of cell `(i, j)` (0 outside the grid).
    pub fn log_odds(&self, i: usize, j: usize) -> f32 {
        if i < self.width && j < self.height {
            self.log_odds.get(self.index(i, j)).copied().unwrap_or(0.0)
        } else {
            0.0
        }
    }

    /// Mean relative reflectivity and observation count of cell `(i, j)` (`None` if never
    /// observed).
    pub fn cell_reflectivity(&self, i: usize, j: usize) -> Option<(f32, u32)> {
        if i >= self.width || j >= self.height {
            return None;
        }
        let k = self.index(i, j);
        match self.refl_count.get(k) {
            Some(&n) if n > 0 => Some((self.refl_mean.get(k).copied().unwrap_or(0.0), n)),
            _ => None,
        }
    }

    /// The four cells around `(x, y)` and the fractions `(u, v)` for bilinear interpolation
    /// between cell centres; `None` near or beyond the border.
    #[inline]
    fn corners(&self, x: f64, y: f64) -> Option<([usize; 4], f64, f64)> {
        let cx = (x - self.origin[0]) / self.resolution_m - 0.5;
        let cy = (y - self.origin[1]) / self.resolution_m - 0.5;
        let (fx, fy) = (cx.floor(), cy.floor());
        if !(fx >= 0.0 && fy >= 0.0)
            || fx + 1.0 >= self.width as f64
            || fy + 1.0 >= self.height as f64
        {
            return None;
        }
        let (i, j) = (fx as usize, fy as usize);
        let k00 = j * self.width + i;
        Some((
            [k00, k00 + 1, k00 + self.width, k00 + self.width + 1],
            cx - fx,
            cy - fy,
        ))
    }

    #[inline]
    fn bilinear(&self, v: [f64; 4], u: f64, w: f64) -> Sample {
        let [p00, p10, p01, p11] = v;
        // Consistent bilinear weights (1−u)(1−v), u(1−v), (1−u)v, uv (the thesis permutes them).
        let value =
            (1.0 - u) * (1.0 - w) * p00 + u * (1.0 - w) * p10 + (1.0 - u) * w * p01 + u * w * p11;
        // Its derivatives (the thesis' gradient up to 1/cell size).
        let du = (1.0 - w) * (p10 - p00) + w * (p11 - p01);
        let dv = (1.0 - u) * (p01 - p00) + u * (p11 - p10);
        Sample {
            value,
            gradient: [du / self.resolution_m, dv / self.resolution_m],
        }
    }

    /// Occupancy probability M(P) at map-frame `(x, y)` with its gradient, interpolated
    /// bilinearly between cell centres (Hector's map access); `None` outside the grid.
    #[inline]
    pub fn occupancy(&self, x: f64, y: f64) -> Option<Sample> {
        let (k, u, w) = self.corners(x, y)?;
        let mut v = [0.0; 4];
        for (out, &ki) in v.iter_mut().zip(&k) {
            *out = probability(*self.log_odds.get(ki)?);
        }
        Some(self.bilinear(v, u, w))
    }

    /// Reflectivity R(P) at `(x, y)` with its gradient. Unobserved cells count as
    /// `unobserved` when it is `Some`; with `None` a sample touching an unobserved cell is
    /// `None` (the thesis leaves unobserved cells open).
    #[inline]
    pub fn reflectivity(&self, x: f64, y: f64, unobserved: Option<f64>) -> Option<Sample> {
        let (k, u, w) = self.corners(x, y)?;
        let mut v = [0.0; 4];
        for (out, &ki) in v.iter_mut().zip(&k) {
            *out = match self.refl_count.get(ki) {
                Some(&n) if n > 0 => f64::from(*self.refl_mean.get(ki)?),
                _ => unobserved?,
            };
        }
        Some(self.bilinear(v, u, w))
    }

    /// The part `[i0, i1) × [j0, j1)` of this level as a level of its own (same resolution,
    /// the same map-frame positions; stamps reset), e.g. a finished submap cut to its observed
    /// box ([`crate::export::observed_box`]). The bounds are clamped to the grid and keep at
    /// least 2 × 2 cells where the grid has them.
    pub fn crop(&self, bounds: [usize; 4]) -> GridLevel {
        let i1 = bounds[2].min(self.width);
        let j1 = bounds[3].min(self.height);
        let i0 = bounds[0].min(i1.saturating_sub(2));
        let j0 = bounds[1].min(j1.saturating_sub(2));
        let (w, h) = (i1 - i0, j1 - j0);
        let origin = [
            self.origin[0] + i0 as f64 * self.resolution_m,
            self.origin[1] + j0 as f64 * self.resolution_m,
        ];
        let mut out = GridLevel::new(self.resolution_m, origin, w, h);
        let rows = |v: &[f32]| -> Vec<f32> {
            (j0..j1)
                .flat_map(|j| v[j * self.width + i0..j * self.width + i1].iter().copied())
                .collect()
        };
        out.log_odds = rows(&self.log_odds);
        if self.has_reflectivity() {
            out.refl_mean = rows(&self.refl_mean);
            out.refl_count = (j0..j1)
                .flat_map(|j| {
                    self.refl_count[j * self.width + i0..j * self.width + i1]
                        .iter()
                        .copied()
                })
                .collect();
        }
        out
    }

    /// Starts a scan update: returns the stamp base for [`Self::mark_occupied`] and
    /// [`Self::mark_free`] (`scan_number` counts map updates from 0).
    pub(crate) fn stamp_base(scan_number: u32) -> u32 {
        scan_number.wrapping_mul(2).wrapping_add(2)
    }

    /// Adds `delta` to cell `(i, j)` unless it was updated in this scan already.
    #[inline]
    fn mark(&mut self, i: usize, j: usize, delta: f32, base: u32, mark: u32) {
        let k = j * self.width + i;
        if let (Some(stamp), Some(l)) = (self.stamp.get_mut(k), self.log_odds.get_mut(k)) {
            if *stamp < base {
                *l = (*l + delta).clamp(-LOG_ODDS_LIMIT, LOG_ODDS_LIMIT);
                *stamp = mark;
            }
        }
    }

    /// Marks the end-point cell of a hit as occupied (once per scan).
    pub(crate) fn mark_occupied(&mut self, cell: (usize, usize), delta: f32, base: u32) {
        self.mark(cell.0, cell.1, delta, base, base + 1);
    }

    /// Adds a reflectivity observation to a cell (incremental mean, §3.4.1).
    pub(crate) fn add_reflectivity(&mut self, cell: (usize, usize), reflectivity: f64) {
        if self.refl_count.is_empty() {
            self.refl_mean = vec![0.0; self.width * self.height];
            self.refl_count = vec![0; self.width * self.height];
        }
        let k = self.index(cell.0, cell.1);
        if let (Some(n), Some(m)) = (self.refl_count.get_mut(k), self.refl_mean.get_mut(k)) {
            *n = n.saturating_add(1);
            // R_m ← R_m + (ϱ̄ − R_m) / n_g  (§3.4.1)
            *m += (reflectivity as f32 - *m) / *n as f32;
        }
    }

    /// Marks the cells from `from` up to (excluding) `to` as free (Bresenham), each at most
    /// once per scan; stops at the border.
    pub(crate) fn mark_free_line(
        &mut self,
        from: (usize, usize),
        to: (i64, i64),
        delta: f32,
        base: u32,
    ) {
        let (mut x, mut y) = (from.0 as i64, from.1 as i64);
        let dx = (to.0 - x).abs();
        let dy = -(to.1 - y).abs();
        let sx = if x < to.0 { 1 } else { -1 };
        let sy = if y < to.1 { 1 } else { -1 };
        let mut err = dx + dy;
        let (w, h) = (self.width as i64, self.height as i64);
        while (x, y) != to {
            if x < 0 || y < 0 || x >= w || y >= h {
                return;
            }
            self.mark(x as usize, y as usize, delta, base, base);
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                x += sx;
            }
            if e2 <= dx {
                err += dx;
                y += sy;
            }
        }
    }

    /// The cell coordinates of `(x, y)` as integers (may lie outside the grid).
    pub(crate) fn cell_i64(&self, x: f64, y: f64) -> (i64, i64) {
        (
            ((x - self.origin[0]) / self.resolution_m).floor() as i64,
            ((y - self.origin[1]) / self.resolution_m).floor() as i64,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn textured() -> GridLevel {
        let mut g = GridLevel::new(0.1, [-1.0, -1.0], 20, 20);
        for j in 0..20 {
            for i in 0..20 {
                let k = g.index(i, j);
                g.log_odds[k] = ((i as f32) * 0.37).sin() * 3.0 + (j as f32 * 0.21).cos() * 2.0;
                g.add_reflectivity((i, j), 0.5 + 0.3 * ((i * 7 + j * 3) % 11) as f64 / 11.0);
            }
        }
        g
    }

    #[test]
    fn bilinear_matches_cell_values_at_centres() {
        let g = textured();
        let (x, y) = (-1.0 + 0.1 * 5.5, -1.0 + 0.1 * 7.5);
        let s = g.occupancy(x, y).unwrap();
        assert!((s.value - probability(g.log_odds(5, 7))).abs() < 1e-12);
        let r = g.reflectivity(x, y, None).unwrap();
        assert!((r.value - f64::from(g.cell_reflectivity(5, 7).unwrap().0)).abs() < 1e-6);
    }

    #[test]
    fn gradient_agrees_with_finite_differences() {
        let g = textured();
        let h = 1e-6;
        for k in 0..200 {
            let x = -0.8 + 1.6 * ((k * 37 % 200) as f64 / 200.0) + 0.0013;
            let y = -0.8 + 1.6 * ((k * 91 % 200) as f64 / 200.0) + 0.0007;
            for f in [&|x, y| g.occupancy(x, y) as Option<Sample>, &|x, y| {
                g.reflectivity(x, y, Some(0.0))
            }] as [&dyn Fn(f64, f64) -> Option<Sample>; 2]
            {
                let s = f(x, y).unwrap();
                let gx = (f(x + h, y).unwrap().value - f(x - h, y).unwrap().value) / (2.0 * h);
                let gy = (f(x, y + h).unwrap().value - f(x, y - h).unwrap().value) / (2.0 * h);
                assert!(
                    (gx - s.gradient[0]).abs() < 1e-4,
                    "{gx} vs {:?}",
                    s.gradient
                );
                assert!(
                    (gy - s.gradient[1]).abs() < 1e-4,
                    "{gy} vs {:?}",
                    s.gradient
                );
            }
        }
    }

    #[test]
    fn incremental_mean_and_once_per_scan() {
        let mut g = GridLevel::new(0.1, [0.0, 0.0], 10, 10);
        for r in [0.2, 0.4, 0.9] {
            g.add_reflectivity((3, 3), r);
        }
        let (m, n) = g.cell_reflectivity(3, 3).unwrap();
        assert_eq!(n, 3);
        assert!((f64::from(m) - 0.5).abs() < 1e-6);
        let base = GridLevel::stamp_base(0);
        g.mark_occupied((5, 5), 2.0, base);
        g.mark_occupied((5, 5), 2.0, base);
        g.mark_free_line((0, 5), (5, 5), -0.4, base);
        assert_eq!(g.log_odds(5, 5), 2.0);
        assert_eq!(g.log_odds(0, 5), -0.4);
        assert_eq!(g.log_odds(4, 5), -0.4);
        let next = GridLevel::stamp_base(1);
        g.mark_occupied((5, 5), 2.0, next);
        assert_eq!(g.log_odds(5, 5), 4.0);
        assert!(g.occupancy(100.0, 0.0).is_none());
    }
}
