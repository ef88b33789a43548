//! Planar scans rasterised to 8-bit images, so that image-feature methods (IBuILD, the
//! DBoW2-style baseline) run on 2-D laser logs.
//!
//! Khan (2017, §4.4, §4.6.1) evaluates IBuILD on camera images; for 2-D laser logs the
//! evaluation uses **rasterised scans**: a top view of the scan's end points in the sensor
//! frame, drawn so that the structure FAST and the binary tests see is the structure of the
//! place (this route is ours, not in the thesis):
//!
//! * The sensor sits at the centre pixel of a square image of side `2 ⌈R / s⌉ + 1` pixels
//!   (`R` = [`RasterConfig::max_range_m`], `s` = [`RasterConfig::pixel_m`]). REP-103 top view:
//!   x forward points **up** (towards row 0) and y left points **left**, so the picture is a
//!   proper rotation of the map view (no mirror) and a turn of the robot turns the image.
//! * Consecutive end points closer than [`RasterConfig::gap_m`] are joined by a line
//!   (walls become lines, corners become corners); every end point is also drawn as a dot.
//!   Lines and dots are anti-aliased discs of radius [`RasterConfig::line_radius_px`] stamped
//!   every half pixel, combined by maximum (white 255 on black 0).
//! * For a full-circle scan the last and first beams are neighbours too.
//! * No-returns (the scan's own rule: not finite, not positive or at/above its maximum range),
//!   end points beyond `max_range_m` and non-finite coordinates are skipped. An empty scan
//!   gives a blank image.

use image::GrayImage;
use raypath_geometry::Scan2;

use crate::error::require_positive;
use crate::{PlaceError, Result};

/// Largest image side we allocate, in pixels (a guard against tiny pixel sizes).
const MAX_SIDE: usize = 8192;

/// How a planar scan becomes an image.
#[derive(Clone, Debug, PartialEq)]
pub struct RasterConfig {
    /// Pixel size in metres (default 0.05 m; ours, the usual 2-D grid-map resolution).
    pub pixel_m: f64,
    /// Range drawn around the sensor in metres: the image spans `±max_range_m` (default 15 m;
    /// ours, indoor laser logs rarely see further). Default image: 601 × 601 pixels.
    pub max_range_m: f64,
    /// Consecutive end points closer than this are joined by a line, in metres (default
    /// 0.5 m; ours: 1°-spaced beams at 20 m are 0.35 m apart, a doorway is wider).
    pub gap_m: f64,
    /// Radius of the drawn dots and half the line width, in pixels (default 1.0; ours).
    pub line_radius_px: f64,
}

impl Default for RasterConfig {
    fn default() -> Self {
        Self {
            pixel_m: 0.05,
            max_range_m: 15.0,
            gap_m: 0.5,
            line_radius_px: 1.0,
        }
    }
}

impl RasterConfig {
    /// Checks the parameters and returns the image side in pixels.
    pub fn side(&self) -> Result<usize> {
        require_positive("pixel_m", self.pixel_m)?;
        require_positive("max_range_m", self.max_range_m)?;
        require_positive("line_radius_px", self.line_radius_px)?;
        if !(self.gap_m.is_finite() && self.gap_m >= 0.0) {
            return Err(PlaceError::InvalidParameter {
                name: "gap_m",
                reason: format!("must be finite and non-negative, got {}", self.gap_m),
            });
        }
        let half = (self.max_range_m / self.pixel_m).ceil();
        if half > ((MAX_SIDE - 1) / 2) as f64 {
            return Err(PlaceError::InvalidParameter {
                name: "pixel_m",
                reason: format!(
                    "{} m pixels over ±{} m exceed {MAX_SIDE} pixels per side",
                    self.pixel_m, self.max_range_m
                ),
            });
        }
        Ok(2 * half as usize + 1)
    }
}

/// Rasterises a planar scan (sensor frame) into an image (see the module docs).
pub fn rasterize_scan(scan: &Scan2, config: &RasterConfig) -> Result<GrayImage> {
    let side = config.side()?;
    let mut canvas = Canvas::new(side, config.line_radius_px);
    let centre = (side / 2) as f64;
    // Sensor (x, y) in metres → pixel (column, row): x up, y left.
    let to_pixel = |x: f64, y: f64| (centre - y / config.pixel_m, centre - x / config.pixel_m);
    let end_point = |i: usize| {
        let r = scan.range(i).hit()?;
        let (s, c) = scan.angle(i).sin_cos();
        let (x, y) = (r * c, r * s);
        (x.is_finite() && y.is_finite() && r <= config.max_range_m).then_some((x, y))
    };
    let n = scan.len();
    let full_circle =
        n > 2 && (n as f64 * scan.angle_increment_rad.abs()) >= std::f64::consts::TAU - 1e-9;
    let mut previous = if full_circle { end_point(n - 1) } else { None };
    for i in 0..n {
        let current = end_point(i);
        if let Some((x, y)) = current {
            let (u, v) = to_pixel(x, y);
            canvas.stamp(u, v);
            if let Some((px, py)) = previous
                && (x - px).hypot(y - py) < config.gap_m
            {
                let (pu, pv) = to_pixel(px, py);
                canvas.line(pu, pv, u, v);
            }
        }
        previous = current;
    }
    Ok(canvas.into_image())
}

/// A square float canvas with anti-aliased disc stamps combined by maximum.
struct Canvas {
    side: usize,
    radius: f64,
    values: Vec<f32>,
}

impl Canvas {
    fn new(side: usize, radius: f64) -> Self {
        Self {
            side,
            radius,
            values: vec![0.0; side * side],
        }
    }

    /// Stamps a disc centred at pixel coordinates `(u, v)` (pixel centres at integers); the
    /// coverage falls linearly from 1 to 0 over the half pixel either side of the rim.
    fn stamp(&mut self, u: f64, v: f64) {
        let reach = self.radius + 0.5;
        let max = (self.side - 1) as f64;
        if u < -reach || v < -reach || u > max + reach || v > max + reach {
            return;
        }
        let (u0, u1) = ((u - reach).floor().max(0.0), (u + reach).ceil().min(max));
        let (v0, v1) = ((v - reach).floor().max(0.0), (v + reach).ceil().min(max));
        for row in v0 as usize..=v1 as usize {
            for col in u0 as usize..=u1 as usize {
                let d = (col as f64 - u).hypot(row as f64 - v);
                let a = (reach - d).clamp(0.0, 1.0) as f32;
                let cell = &mut self.values[row * self.side + col];
                *cell = cell.max(a);
            }
        }
    }

    /// Stamps discs every half pixel along the segment from `(u0, v0)` to `(u1, v1)`.
    fn line(&mut self, u0: f64, v0: f64, u1: f64, v1: f64) {
        let steps = ((u1 - u0).hypot(v1 - v0) * 2.0).ceil().max(1.0) as usize;
        for k in 1..steps {
            let t = k as f64 / steps as f64;
            self.stamp(u0 + t * (u1 - u0), v0 + t * (v1 - v0));
        }
    }

    fn into_image(self) -> GrayImage {
        let pixels = self
            .values
            .iter()
            .map(|&a| (a * 255.0).round() as u8)
            .collect();
        GrayImage::from_raw(self.side as u32, self.side as u32, pixels)
            .unwrap_or_else(|| GrayImage::new(0, 0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    fn scan(angle_min_rad: f64, ranges: Vec<f64>) -> Scan2 {
        let n = ranges.len() as f64;
        Scan2 {
            angle_min_rad,
            angle_increment_rad: TAU / n,
            max_range_m: 30.0,
            ranges,
            intensities: None,
        }
    }

    #[test]
    fn forward_is_up_and_left_is_left() {
        let config = RasterConfig {
            pixel_m: 0.1,
            max_range_m: 5.0,
            ..RasterConfig::default()
        };
        // Four beams: forward 2 m, left 3 m, back: no-return, right: NaN.
        let s = scan(0.0, vec![2.0, 3.0, 30.0, f64::NAN]);
        let img = rasterize_scan(&s, &config).unwrap();
        assert_eq!(img.dimensions(), (101, 101));
        assert_eq!(img.get_pixel(50, 30).0[0], 255, "forward 2 m = 20 px up");
        assert_eq!(img.get_pixel(20, 50).0[0], 255, "left 3 m = 30 px left");
        let lit = img.pixels().filter(|p| p.0[0] > 0).count();
        assert!(lit < 30, "only two dots, {lit} pixels lit");
    }

    #[test]
    fn walls_become_lines_and_gaps_stay_open() {
        // A 360-beam scan of a 4 m × 4 m square room, sensor in the middle.
        let ranges: Vec<f64> = (0..360)
            .map(|i| {
                let a = (i as f64 + 0.5).to_radians();
                2.0 / a.cos().abs().max(a.sin().abs())
            })
            .collect();
        let config = RasterConfig::default();
        let img = rasterize_scan(&scan(0.0, ranges), &config).unwrap();
        // The front wall (x = 2 m, 40 px up) is continuous from y = −1.9 m to 1.9 m.
        let c = 300;
        for col in c - 38..=c + 38 {
            assert!(
                img.get_pixel(col, c - 40).0[0] >= 128,
                "gap at column {col}"
            );
        }
        // Nothing inside the room.
        assert_eq!(img.get_pixel(c, c).0[0], 0);
        // Neighbouring beams 3 m apart in range are not joined (midpoint 4.5 m ahead).
        let mut ranges = vec![30.0; 360];
        ranges[0] = 3.0;
        ranges[1] = 6.0;
        let img = rasterize_scan(&scan(0.0, ranges), &config).unwrap();
        assert_eq!(img.get_pixel(c - 1, c - 90).0[0], 0);
        assert_eq!(img.get_pixel(c, c - 60).0[0], 255);
    }

    #[test]
    fn empty_scans_are_blank_and_bad_configs_fail() {
        let config = RasterConfig::default();
        let img = rasterize_scan(&scan(0.0, vec![]), &config).unwrap();
        assert_eq!(img.dimensions(), (601, 601));
        assert!(img.pixels().all(|p| p.0[0] == 0));
        for bad in [
            RasterConfig {
                pixel_m: 0.0,
                ..config.clone()
            },
            RasterConfig {
                max_range_m: f64::NAN,
                ..config.clone()
            },
            RasterConfig {
                pixel_m: 1e-4,
                ..config.clone()
            },
        ] {
            assert!(matches!(
                rasterize_scan(&scan(0.0, vec![1.0]), &bad),
                Err(PlaceError::InvalidParameter { .. })
            ));
        }
    }
}
