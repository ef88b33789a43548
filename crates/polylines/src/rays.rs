//! The scan as a table of rays in the sensor frame, and ray–segment intersection.
//!
//! All rays start at the sensor origin (the scan frame, REP-103: x forward, y left, metres,
//! radians). Beam `k` points along `u_k = (cos θ_k, sin θ_k)` with `θ_k = θ_0 + k·Δθ`; a
//! returned beam has the measured radius `r_k` and the endpoint `b_k = r_k·u_k`.
//!
//! Because the angles are equally spaced, the beams that can hit a segment — those whose
//! azimuth lies inside the angle the segment subtends at the sensor — are found by
//! arithmetic, without a search: [`ScanRays::for_each_ray_in_segment_arc`].

use std::f64::consts::{PI, TAU};

use nalgebra::{Point2, Vector2};
use raypath_geometry::Scan2;

use crate::PolylineError;

/// Tolerance on the segment parameter `s ∈ [0, 1]` of a ray–segment hit, so that the beam
/// through a vertex hits both segments that share it despite rounding.
const SEGMENT_TOLERANCE: f64 = 1e-9;
/// Tolerance in beam-index units of the arc lookup.
const INDEX_TOLERANCE: f64 = 1e-7;

/// The beams of a scan in the sensor frame.
#[derive(Clone, Debug)]
pub struct ScanRays {
    theta0_rad: f64,
    increment_rad: f64,
    /// Unit direction of each beam.
    dirs: Vec<Vector2<f64>>,
    /// Measured radius of each returned beam (`None` for a no-return).
    radii: Vec<Option<f64>>,
    theta_lo_rad: f64,
    theta_hi_rad: f64,
    closed: bool,
}

impl ScanRays {
    /// The rays of `scan`. No-returns (non-finite, non-positive or at/above the maximum range)
    /// are kept as beams without a radius.
    pub fn new(scan: &Scan2) -> Result<Self, PolylineError> {
        if !scan.angle_min_rad.is_finite() || !scan.angle_increment_rad.is_finite() {
            return Err(PolylineError::InvalidScan {
                reason: "beam angles must be finite".into(),
            });
        }
        if scan.len() > 1 && scan.angle_increment_rad == 0.0 {
            return Err(PolylineError::InvalidScan {
                reason: "angle increment is zero".into(),
            });
        }
        let n = scan.len();
        let dirs = (0..n)
            .map(|k| {
                let a = scan.angle(k);
                Vector2::new(a.cos(), a.sin())
            })
            .collect();
        let radii = (0..n).map(|k| scan.range(k).hit()).collect();
        let last = scan.angle_max_rad();
        let (lo, hi) = if last >= scan.angle_min_rad {
            (scan.angle_min_rad, last)
        } else {
            (last, scan.angle_min_rad)
        };
        // The reference implementation's test: the scan is a closed revolution when the gap
        // between the last and the first beam (wrapped to [0, 2π)) is at most 4π/K.
        let closed = n >= 3 && {
            let gap = if scan.angle_increment_rad > 0.0 {
                (scan.angle_min_rad - last).rem_euclid(TAU)
            } else {
                (last - scan.angle_min_rad).rem_euclid(TAU)
            };
            gap <= 2.0 * TAU / n as f64 && (hi - lo) > PI
        };
        Ok(Self {
            theta0_rad: scan.angle_min_rad,
            increment_rad: scan.angle_increment_rad,
            dirs,
            radii,
            theta_lo_rad: lo,
            theta_hi_rad: hi,
            closed,
        })
    }

    /// Number of beams.
    pub fn len(&self) -> usize {
        self.dirs.len()
    }

    /// True when the scan has no beams.
    pub fn is_empty(&self) -> bool {
        self.dirs.is_empty()
    }

    /// True when the beams cover a full revolution (the endpoints form a closed polygon).
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// Unit direction of beam `k`.
    pub fn dir(&self, k: usize) -> Vector2<f64> {
        self.dirs.get(k).copied().unwrap_or_else(Vector2::zeros)
    }

    /// Azimuth of beam `k` in radians.
    pub fn angle(&self, k: usize) -> f64 {
        self.theta0_rad + k as f64 * self.increment_rad
    }

    /// Measured radius of beam `k` in metres, `None` for a no-return.
    pub fn radius(&self, k: usize) -> Option<f64> {
        self.radii.get(k).copied().flatten()
    }

    /// Endpoint `b_k` of a returned beam.
    pub fn endpoint(&self, k: usize) -> Option<Point2<f64>> {
        self.radius(k).map(|r| Point2::from(self.dir(k) * r))
    }

    /// Number of returned beams.
    pub fn returned(&self) -> usize {
        self.radii.iter().filter(|r| r.is_some()).count()
    }

    /// Calls `f(k)` for every beam whose azimuth lies in the angle segment `(p, q)` subtends
    /// at the sensor (the smaller arc between the azimuths of `p` and `q`, boundary beams
    /// included). Nothing for a segment through the sensor.
    pub fn for_each_ray_in_segment_arc(
        &self,
        p: &Point2<f64>,
        q: &Point2<f64>,
        mut f: impl FnMut(usize),
    ) {
        let n = self.len();
        if n == 0 {
            return;
        }
        let cross = p.x * q.y - p.y * q.x;
        let (a, b) = if cross >= 0.0 { (p, q) } else { (q, p) };
        let start = a.y.atan2(a.x);
        let span = (b.y.atan2(b.x) - start).rem_euclid(TAU);
        if !start.is_finite() || !span.is_finite() || span >= PI {
            return;
        }
        let end = start + span;
        // Shift the arc by whole turns so that it overlaps the fan [lo, hi].
        let m_lo = ((self.theta_lo_rad - end) / TAU).floor() as i64;
        let m_hi = ((self.theta_hi_rad - start) / TAU).ceil() as i64;
        let inc = if self.increment_rad == 0.0 {
            1.0
        } else {
            self.increment_rad
        };
        for m in m_lo..=m_hi {
            let shift = m as f64 * TAU;
            let x1 = (start + shift - self.theta0_rad) / inc;
            let x2 = (end + shift - self.theta0_rad) / inc;
            let lo = (x1.min(x2) - INDEX_TOLERANCE).ceil().max(0.0);
            let hi = (x1.max(x2) + INDEX_TOLERANCE).floor().min((n - 1) as f64);
            if lo > hi {
                continue;
            }
            for k in lo as usize..=hi as usize {
                f(k);
            }
        }
    }

    /// Distance from the sensor along beam `k` to segment `(p, q)`, if the beam hits it.
    #[inline]
    pub fn hit(&self, k: usize, p: &Point2<f64>, q: &Point2<f64>) -> Option<f64> {
        intersect(&self.dir(k), p, q)
    }
}

/// Distance `t > 0` along the unit direction `u` from the origin to segment `(p, q)`.
#[inline]
pub fn intersect(u: &Vector2<f64>, p: &Point2<f64>, q: &Point2<f64>) -> Option<f64> {
    let d = q - p;
    let denom = u.x * d.y - u.y * d.x;
    if denom.abs() < 1e-15 {
        return None;
    }
    let s = (p.x * u.y - p.y * u.x) / denom;
    if !(-SEGMENT_TOLERANCE..=1.0 + SEGMENT_TOLERANCE).contains(&s) {
        return None;
    }
    let t = (p.x * d.y - p.y * d.x) / denom;
    (t > 0.0 && t.is_finite()).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan(angle_min: f64, inc: f64, n: usize) -> Scan2 {
        Scan2 {
            angle_min_rad: angle_min,
            angle_increment_rad: inc,
            max_range_m: 50.0,
            ranges: vec![1.0; n],
            intensities: None,
        }
    }

    #[test]
    fn arc_lookup_finds_exactly_the_hitting_beams() {
        for s in [
            scan(-PI, TAU / 360.0, 360),
            scan(-PI / 2.0, PI / 179.0, 180),
            scan(PI / 2.0, -PI / 179.0, 180),
        ] {
            let rays = ScanRays::new(&s).expect("valid");
            let segments = [
                (Point2::new(2.0, -1.0), Point2::new(2.0, 1.0)),
                (Point2::new(-2.0, 0.5), Point2::new(-2.0, -0.5)),
                (Point2::new(-1.0, 3.0), Point2::new(1.0, 1.0)),
                (Point2::new(3.0, 0.1), Point2::new(-3.0, 0.2)),
            ];
            for (p, q) in segments {
                let mut found = Vec::new();
                rays.for_each_ray_in_segment_arc(&p, &q, |k| found.push(k));
                let brute: Vec<usize> = (0..rays.len())
                    .filter(|&k| rays.hit(k, &p, &q).is_some())
                    .collect();
                for k in &brute {
                    assert!(found.contains(k), "beam {k} hits but was not listed");
                }
            }
        }
    }

    #[test]
    fn closed_detection() {
        assert!(
            ScanRays::new(&scan(-PI, TAU / 360.0, 360))
                .expect("valid")
                .is_closed()
        );
        assert!(
            ScanRays::new(&scan(-PI, TAU / 359.0, 360))
                .expect("valid")
                .is_closed()
        );
        assert!(
            !ScanRays::new(&scan(-PI / 2.0, PI / 179.0, 180))
                .expect("valid")
                .is_closed()
        );
    }

    #[test]
    fn intersection_distance() {
        let u = Vector2::new(1.0, 0.0);
        let t = intersect(&u, &Point2::new(2.0, -1.0), &Point2::new(2.0, 1.0));
        assert!((t.expect("hit") - 2.0).abs() < 1e-12);
        assert!(intersect(&u, &Point2::new(-2.0, -1.0), &Point2::new(-2.0, 1.0)).is_none());
    }
}
