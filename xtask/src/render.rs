//! Pictures for evaluation reports: top-down hit maps with overlays, false-colour images.

use std::path::Path;

use anyhow::{Context, Result};
use image::{Rgb, RgbImage};

/// A top-down picture of the ground plane (north up): hit counts in grey, with coloured
/// overlays (trajectories, poles, polygons) drawn on top.
pub struct TopDown {
    min_x: f64,
    max_y: f64,
    cell_m: f64,
    width: u32,
    height: u32,
    counts: Vec<u32>,
    overlay: Vec<(u32, u32, [u8; 3])>,
}

impl TopDown {
    /// A picture of the region spanned by `points` (the `quantile`–(1 − `quantile`) range of
    /// each axis, so a few stray points do not shrink it), with cells of at least `min_cell_m`
    /// and at most `max_side_px` pixels on the longer side. `None` for no points.
    pub fn fit(
        points: &[(f64, f64)],
        quantile: f64,
        min_cell_m: f64,
        max_side_px: f64,
    ) -> Option<Self> {
        if points.is_empty() {
            return None;
        }
        let (min_x, max_x) = robust_bounds(points.iter().map(|p| p.0).collect(), quantile);
        let (min_y, max_y) = robust_bounds(points.iter().map(|p| p.1).collect(), quantile);
        let cell_m = ((max_x - min_x).max(max_y - min_y) / max_side_px).max(min_cell_m);
        let width = ((max_x - min_x) / cell_m).floor() as u32 + 1;
        let height = ((max_y - min_y) / cell_m).floor() as u32 + 1;
        Some(Self {
            min_x,
            max_y,
            cell_m,
            width,
            height,
            counts: vec![0; width as usize * height as usize],
            overlay: Vec::new(),
        })
    }

    fn pixel(&self, x: f64, y: f64) -> Option<(u32, u32)> {
        let col = (x - self.min_x) / self.cell_m;
        let row = (self.max_y - y) / self.cell_m;
        (col >= 0.0 && row >= 0.0 && col < f64::from(self.width) && row < f64::from(self.height))
            .then_some((col as u32, row as u32))
    }

    /// Counts one hit at `(x, y)` metres.
    pub fn hit(&mut self, x: f64, y: f64) {
        if let Some((col, row)) = self.pixel(x, y) {
            self.counts[(row * self.width + col) as usize] += 1;
        }
    }

    /// A filled dot of `radius_px` pixels.
    pub fn dot(&mut self, x: f64, y: f64, radius_px: i32, color: [u8; 3]) {
        let Some((col, row)) = self.pixel(x, y) else {
            return;
        };
        for dr in -radius_px..=radius_px {
            for dc in -radius_px..=radius_px {
                if dr * dr + dc * dc <= radius_px * radius_px {
                    let (c, r) = (col as i64 + i64::from(dc), row as i64 + i64::from(dr));
                    if c >= 0 && r >= 0 && c < i64::from(self.width) && r < i64::from(self.height) {
                        self.overlay.push((c as u32, r as u32, color));
                    }
                }
            }
        }
    }

    /// A line from `a` to `b` (metres).
    pub fn line(&mut self, a: (f64, f64), b: (f64, f64), color: [u8; 3]) {
        let steps = ((b.0 - a.0).hypot(b.1 - a.1) / (0.5 * self.cell_m))
            .ceil()
            .max(1.0) as usize;
        for i in 0..=steps {
            let t = i as f64 / steps as f64;
            if let Some((col, row)) = self.pixel(a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)) {
                self.overlay.push((col, row, color));
            }
        }
    }

    /// Writes the PNG: white background, 1 hit light grey, 8 or more black; overlays on top.
    pub fn save(&self, path: &Path) -> Result<()> {
        let mut image = RgbImage::from_fn(self.width, self.height, |col, row| {
            let c = self.counts[(row * self.width + col) as usize];
            let shade = if c == 0 {
                255
            } else {
                (200.0 * (1.0 - (f64::from(c).log2() / 3.0).min(1.0))) as u8
            };
            Rgb([shade, shade, shade])
        });
        for &(col, row, color) in &self.overlay {
            image.put_pixel(col, row, Rgb(color));
        }
        image
            .save(path)
            .with_context(|| format!("writing {}", path.display()))
    }
}

/// The `q`–(1 − `q`) quantile range of the finite values, padded by 2 % on each side
/// (`(0, 1)` when there are none).
pub fn robust_bounds(mut values: Vec<f64>, q: f64) -> (f64, f64) {
    values.retain(|v| v.is_finite());
    if values.is_empty() {
        return (0.0, 1.0);
    }
    values.sort_by(f64::total_cmp);
    let at = |f: f64| values[((values.len() - 1) as f64 * f) as usize];
    let (lo, hi) = (at(q), at(1.0 - q));
    if hi <= lo {
        return (lo - 0.5, lo + 0.5);
    }
    let pad = 0.02 * (hi - lo);
    (lo - pad, hi + pad)
}

/// A perceptually ordered colour for `t ∈ [0, 1]` (dark blue → green → yellow; a compact
/// approximation of viridis).
pub fn colormap(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    } * (STOPS.len() - 1) as f64;
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - i as f64;
    let mix = |k: usize| (STOPS[i][k] * (1.0 - f) + STOPS[i + 1][k] * f) as u8;
    [mix(0), mix(1), mix(2)]
}

/// A distinct colour per label (black for 0, grey for labels below 10).
pub fn label_color(label: u32) -> [u8; 3] {
    match label {
        0 => [0, 0, 0],
        1..=9 => [150, 150, 150],
        _ => {
            let h = label.wrapping_mul(2_654_435_761);
            [
                64 + (h & 0xbf) as u8,
                64 + ((h >> 8) & 0xbf) as u8,
                64 + ((h >> 16) & 0xbf) as u8,
            ]
        }
    }
}
