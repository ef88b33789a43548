//! The metrics of Schaefer (2020) §10.4: RMSE of the ray radii, the fraction `f` of
//! reflected rays explained, and (simulation) the area error `a` and the IoU against the
//! ground-truth polygon.

use std::f64::consts::TAU;

use nalgebra::Point2;
use raypath_geometry::Scan2;
use serde::Serialize;

use crate::rays::ScanRays;
use crate::{PolylineError, Polylines};

/// Ray metrics of one scan against a polyline map.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RayMetrics {
    /// RMSE in metres of `r − r̂` over the returned beams that hit the map (NaN if none).
    pub rmse_m: f64,
    /// `f`: returned beams that hit the map / returned beams (NaN for a scan without returns).
    pub f: f64,
    /// Returned beams that hit the map.
    pub explained: usize,
    /// Returned beams.
    pub returned: usize,
    /// Largest `|r − r̂|` in metres over the explained beams (NaN if none).
    pub max_abs_m: f64,
}

/// Distance along every beam to its first hit on the map (`None`: the beam misses it).
pub fn predicted_ranges(rays: &ScanRays, map: &Polylines) -> Vec<Option<f64>> {
    let mut best: Vec<Option<f64>> = vec![None; rays.len()];
    for (p, q) in map.segments() {
        rays.for_each_ray_in_segment_arc(&p, &q, |k| {
            if let Some(t) = rays.hit(k, &p, &q) {
                let slot = &mut best[k];
                if slot.is_none_or(|b| t < b) {
                    *slot = Some(t);
                }
            }
        });
    }
    best
}

/// RMSE, `f` and the largest residual of `map` on `scan` (map in the scan frame).
pub fn ray_metrics(scan: &Scan2, map: &Polylines) -> Result<RayMetrics, PolylineError> {
    let rays = ScanRays::new(scan)?;
    Ok(ray_metrics_of(&rays, map))
}

pub(crate) fn ray_metrics_of(rays: &ScanRays, map: &Polylines) -> RayMetrics {
    let predicted = predicted_ranges(rays, map);
    let (mut sum, mut explained, mut returned, mut max_abs) = (0.0, 0usize, 0usize, 0.0f64);
    for (k, hat) in predicted.iter().enumerate() {
        let Some(r) = rays.radius(k) else { continue };
        returned += 1;
        if let Some(t) = hat {
            let d = r - t;
            sum += d * d;
            explained += 1;
            max_abs = max_abs.max(d.abs());
        }
    }
    let nan_if_none = |v: f64| if explained == 0 { f64::NAN } else { v };
    RayMetrics {
        rmse_m: nan_if_none((sum / explained.max(1) as f64).sqrt()),
        f: if returned == 0 {
            f64::NAN
        } else {
            explained as f64 / returned as f64
        },
        explained,
        returned,
        max_abs_m: nan_if_none(max_abs),
    }
}

/// Area comparison of an estimate with the ground-truth polygon (simulated scans).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct AreaMetrics {
    /// Area of the ground-truth polygon, m².
    pub area_gt_m2: f64,
    /// Area of the estimated polygon, m².
    pub area_est_m2: f64,
    /// Area of the intersection, m².
    pub intersection_m2: f64,
    /// `a` as printed in the thesis: symmetric difference / estimated area.
    pub a_printed: f64,
    /// `a` as the reference implementation computes it: symmetric difference / GT area.
    pub a_gt: f64,
    /// Intersection over union.
    pub iou: f64,
}

/// The area metrics of §10.4: the map's vertices, sorted counter-clockwise by azimuth
/// around the sensor, form the estimated polygon; it is compared with `ground_truth`
/// (vertices in the scan frame). Both polygons must be star-shaped around the sensor (the
/// simulated polygons are; the estimate is by construction).
pub fn area_metrics(
    map: &Polylines,
    ground_truth: &[Point2<f64>],
) -> Result<AreaMetrics, PolylineError> {
    let gt = star_polygon(ground_truth.iter().copied()).ok_or_else(|| {
        PolylineError::InvalidGroundTruth {
            reason: format!(
                "need at least 3 finite vertices not at the sensor, got {}",
                ground_truth.len()
            ),
        }
    })?;
    let area_gt = star_area(&gt);
    let Some(est) = star_polygon(map.vertices()) else {
        return Ok(AreaMetrics {
            area_gt_m2: area_gt,
            area_est_m2: 0.0,
            intersection_m2: 0.0,
            a_printed: f64::INFINITY,
            a_gt: 1.0,
            iou: 0.0,
        });
    };
    let area_est = star_area(&est);
    let inter = star_intersection(&gt, &est);
    let union = area_gt + area_est - inter;
    let sym = union - inter;
    Ok(AreaMetrics {
        area_gt_m2: area_gt,
        area_est_m2: area_est,
        intersection_m2: inter,
        a_printed: sym / area_est,
        a_gt: sym / area_gt,
        iou: inter / union,
    })
}

/// A star-shaped polygon around the origin: `(azimuth, point)` sorted by azimuth.
type Star = Vec<(f64, Point2<f64>)>;

fn star_polygon(points: impl Iterator<Item = Point2<f64>>) -> Option<Star> {
    let mut star: Star = points
        .filter(|p| p.x.is_finite() && p.y.is_finite() && p.coords.norm() > 0.0)
        .map(|p| (p.y.atan2(p.x), p))
        .collect();
    star.sort_by(|a, b| a.0.total_cmp(&b.0));
    star.dedup_by(|a, b| a.0 == b.0);
    (star.len() >= 3).then_some(star)
}

fn star_area(star: &Star) -> f64 {
    let n = star.len();
    (0..n)
        .map(|i| {
            let (a, b) = (star[i].1, star[(i + 1) % n].1);
            0.5 * (a.x * b.y - a.y * b.x)
        })
        .sum()
}

/// Where the boundary of a star polygon crosses the ray at `angle`.
fn boundary_at(star: &Star, angle: f64) -> Point2<f64> {
    let n = star.len();
    let wrapped = (angle + std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI;
    // The edge whose azimuth interval (counter-clockwise, wrapping) contains `angle`.
    let idx = star.partition_point(|(a, _)| *a <= wrapped);
    let (i, j) = if idx == 0 || idx == n {
        (n - 1, 0)
    } else {
        (idx - 1, idx)
    };
    let u = nalgebra::Vector2::new(angle.cos(), angle.sin());
    let (p, q) = (star[i].1, star[j].1);
    let d = q - p;
    let denom = u.x * d.y - u.y * d.x;
    if denom.abs() < 1e-15 {
        return if p.coords.norm() < q.coords.norm() {
            p
        } else {
            q
        };
    }
    let t = (p.x * d.y - p.y * d.x) / denom;
    Point2::from(u * t)
}

/// Area of the intersection of two star polygons around the origin: the angle is split at
/// every vertex azimuth of both and where the boundaries cross; in each piece, the nearer
/// boundary is one straight edge, so the piece is a triangle with the origin.
fn star_intersection(a: &Star, b: &Star) -> f64 {
    let mut cuts: Vec<f64> = a.iter().chain(b).map(|(t, _)| *t).collect();
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    let n = cuts.len();
    let tri = |p: Point2<f64>, q: Point2<f64>| 0.5 * (p.x * q.y - p.y * q.x);
    let mut area = 0.0;
    for i in 0..n {
        let t0 = cuts[i];
        let t1 = if i + 1 < n {
            cuts[i + 1]
        } else {
            cuts[0] + TAU
        };
        if t1 <= t0 {
            continue;
        }
        let mid = 0.5 * (t0 + t1);
        // Each boundary is one edge on this piece: the edge the ray through its middle crosses.
        let (a0, a1) =
            edge_points(a, mid, t0, t1).unwrap_or_else(|| (boundary_at(a, t0), boundary_at(a, t1)));
        let (b0, b1) =
            edge_points(b, mid, t0, t1).unwrap_or_else(|| (boundary_at(b, t0), boundary_at(b, t1)));
        let da0 = a0.coords.norm() - b0.coords.norm();
        let da1 = a1.coords.norm() - b1.coords.norm();
        if da0 <= 0.0 && da1 <= 0.0 {
            area += tri(a0, a1);
        } else if da0 >= 0.0 && da1 >= 0.0 {
            area += tri(b0, b1);
        } else {
            // The edges cross inside the piece.
            let c = line_intersection(a0, a1, b0, b1).unwrap_or(a1);
            if da0 < 0.0 {
                area += tri(a0, c) + tri(c, b1);
            } else {
                area += tri(b0, c) + tri(c, a1);
            }
        }
    }
    area
}

/// The points at azimuths `t0`, `t1` of the edge of `star` that the ray at `mid` crosses.
fn edge_points(star: &Star, mid: f64, t0: f64, t1: f64) -> Option<(Point2<f64>, Point2<f64>)> {
    let wrap = |t: f64| (t + std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI;
    let n = star.len();
    let m = wrap(mid);
    let idx = star.partition_point(|(a, _)| *a <= m);
    let (i, j) = if idx == 0 || idx == n {
        (n - 1, 0)
    } else {
        (idx - 1, idx)
    };
    let (p, q) = (star[i].1, star[j].1);
    let at = |t: f64| {
        let u = nalgebra::Vector2::new(t.cos(), t.sin());
        let d = q - p;
        let denom = u.x * d.y - u.y * d.x;
        (denom.abs() > 1e-15).then(|| Point2::from(u * ((p.x * d.y - p.y * d.x) / denom)))
    };
    Some((at(t0)?, at(t1)?))
}

fn line_intersection(
    a0: Point2<f64>,
    a1: Point2<f64>,
    b0: Point2<f64>,
    b1: Point2<f64>,
) -> Option<Point2<f64>> {
    let r = a1 - a0;
    let s = b1 - b0;
    let denom = r.x * s.y - r.y * s.x;
    if denom.abs() < 1e-15 {
        return None;
    }
    let w = b0 - a0;
    let t = (w.x * s.y - w.y * s.x) / denom;
    Some(a0 + r * t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Polyline;

    fn square(h: f64, offset: (f64, f64)) -> Vec<Point2<f64>> {
        vec![
            Point2::new(-h + offset.0, -h + offset.1),
            Point2::new(h + offset.0, -h + offset.1),
            Point2::new(h + offset.0, h + offset.1),
            Point2::new(-h + offset.0, h + offset.1),
        ]
    }

    fn map_of(vertices: Vec<Point2<f64>>) -> Polylines {
        let rays = vec![0; vertices.len()];
        Polylines {
            lines: vec![Polyline {
                vertices,
                rays,
                closed: true,
            }],
        }
    }

    #[test]
    fn identical_squares() {
        let gt = square(2.0, (0.0, 0.0));
        let m = area_metrics(&map_of(gt.clone()), &gt).expect("valid");
        assert!((m.area_gt_m2 - 16.0).abs() < 1e-9);
        assert!((m.intersection_m2 - 16.0).abs() < 1e-9);
        assert!(m.a_gt.abs() < 1e-9 && m.a_printed.abs() < 1e-9);
        assert!((m.iou - 1.0).abs() < 1e-9);
    }

    #[test]
    fn shifted_squares() {
        // Two 4×4 squares shifted by 0.5 m in x: intersection 3.5 × 4 = 14.
        let gt = square(2.0, (0.0, 0.0));
        let est = square(2.0, (0.5, 0.0));
        let m = area_metrics(&map_of(est), &gt).expect("valid");
        assert!((m.intersection_m2 - 14.0).abs() < 1e-9, "{m:?}");
        assert!((m.a_gt - 4.0 / 16.0).abs() < 1e-9);
        assert!((m.iou - 14.0 / 18.0).abs() < 1e-9);
    }

    #[test]
    fn rotated_square_crossing_edges() {
        // A square and the same square rotated by 45°: intersection is a regular octagon.
        let gt = square(1.0, (0.0, 0.0));
        let r = std::f64::consts::SQRT_2;
        let est: Vec<_> = (0..4)
            .map(|i| {
                let a = i as f64 * std::f64::consts::FRAC_PI_2;
                Point2::new(r * a.cos(), r * a.sin())
            })
            .collect();
        let m = area_metrics(&map_of(est), &gt).expect("valid");
        // Octagon with inradius 1: area 8·tan(π/8).
        let octagon = 8.0 * (std::f64::consts::PI / 8.0).tan();
        assert!((m.intersection_m2 - octagon).abs() < 1e-9, "{m:?}");
    }
}
