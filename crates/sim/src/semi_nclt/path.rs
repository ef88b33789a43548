//! A polyline parameterized by arc length: positions and headings at any arc length, for
//! driving along a path given as positions only (the NCLT local-map positions).

use nalgebra::Point2;

use crate::error::{Result, SimError};

/// Half the baseline of the heading estimate (central difference over ±1 m), metres.
const HEADING_BASELINE_M: f64 = 1.0;

/// A polyline with cumulative arc lengths (consecutive duplicates dropped).
#[derive(Clone, Debug, PartialEq)]
pub struct ArcPath {
    points: Vec<Point2<f64>>,
    arc_m: Vec<f64>,
}

impl ArcPath {
    /// The path through `points`; at least two distinct, finite points.
    pub fn new(points: &[Point2<f64>]) -> Result<Self> {
        let mut kept: Vec<Point2<f64>> = Vec::with_capacity(points.len());
        let mut arc_m: Vec<f64> = Vec::with_capacity(points.len());
        for (i, p) in points.iter().enumerate() {
            if !(p.x.is_finite() && p.y.is_finite()) {
                return Err(SimError::InvalidParameter {
                    name: "path",
                    reason: format!("position {i} ({p}) is not finite"),
                });
            }
            match (kept.last(), arc_m.last()) {
                (Some(q), Some(&s)) => {
                    let d = (p - q).norm();
                    if d > 1e-9 {
                        kept.push(*p);
                        arc_m.push(s + d);
                    }
                }
                _ => {
                    kept.push(*p);
                    arc_m.push(0.0);
                }
            }
        }
        if kept.len() < 2 {
            return Err(SimError::InvalidParameter {
                name: "path",
                reason: "fewer than two distinct positions".into(),
            });
        }
        Ok(Self {
            points: kept,
            arc_m,
        })
    }

    /// Total length, metres.
    pub fn length_m(&self) -> f64 {
        self.arc_m.last().copied().unwrap_or(0.0)
    }

    /// The position at arc length `s` (clamped to the path), metres.
    pub fn at(&self, s: f64) -> Point2<f64> {
        let s = s.clamp(0.0, self.length_m());
        let k = self
            .arc_m
            .partition_point(|&a| a <= s)
            .clamp(1, self.arc_m.len() - 1);
        let (a, b) = (self.arc_m[k - 1], self.arc_m[k]);
        let t = if b > a { (s - a) / (b - a) } else { 0.0 };
        self.points[k - 1] + (self.points[k] - self.points[k - 1]) * t
    }

    /// The heading at arc length `s`: direction of the chord over ±1 m, radians.
    pub fn heading_rad(&self, s: f64) -> f64 {
        let d = self.at(s + HEADING_BASELINE_M) - self.at(s - HEADING_BASELINE_M);
        d.y.atan2(d.x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_and_headings_along_an_l() {
        let pts = [
            Point2::new(0.0, 0.0),
            Point2::new(10.0, 0.0),
            Point2::new(10.0, 0.0),
            Point2::new(10.0, 5.0),
        ];
        let path = ArcPath::new(&pts).unwrap();
        assert!((path.length_m() - 15.0).abs() < 1e-12);
        assert!((path.at(4.0) - Point2::new(4.0, 0.0)).norm() < 1e-12);
        assert!((path.at(12.0) - Point2::new(10.0, 2.0)).norm() < 1e-12);
        assert!((path.at(99.0) - Point2::new(10.0, 5.0)).norm() < 1e-12);
        assert!(path.heading_rad(4.0).abs() < 1e-12);
        assert!((path.heading_rad(13.0) - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!(ArcPath::new(&pts[..1]).is_err());
        assert!(ArcPath::new(&[Point2::new(f64::NAN, 0.0), pts[1]]).is_err());
    }
}
