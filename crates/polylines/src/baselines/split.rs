//! IEF and SAM: top-down splitting of the endpoint sequence.
//!
//! Both drop the no-returns first (they cannot represent them) and treat the remaining
//! endpoints, in beam order, as one sequence from the first to the last endpoint.
//!
//! * **IEF** (iterative end-point fit, Duda & Hart; Douglas–Peucker style): start with the
//!   segment from the first to the last endpoint; repeatedly split the segment with the
//!   endpoint farthest from it at that endpoint, until `J_max` vertices or no endpoint is
//!   farther than `split_threshold_m` (reference implementation: 0.01 m). Vertices are
//!   endpoints.
//! * **SAM** (split-and-merge, Pavlidis & Horowitz 1974): the same splitting, but every
//!   iteration first fits a total-least-squares line to the endpoints of each piece and
//!   splits the piece with the largest endpoint-to-line distance; afterwards neighbouring
//!   pieces whose joint fit stays within the threshold are merged. Vertices are the
//!   intersections of neighbouring fitted lines (the ends: the first and last endpoint
//!   projected onto their lines).

use nalgebra::{Point2, Vector2};

use crate::rays::ScanRays;
use crate::{Polyline, PolylineConfig, Polylines};

fn returned_points(rays: &ScanRays) -> (Vec<Point2<f64>>, Vec<usize>) {
    (0..rays.len())
        .filter_map(|k| rays.endpoint(k).map(|p| (p, k)))
        .unzip()
}

fn point_segment_distance(p: &Point2<f64>, a: &Point2<f64>, b: &Point2<f64>) -> f64 {
    let d = b - a;
    let len2 = d.norm_squared();
    if len2 == 0.0 {
        return (p - a).norm();
    }
    let s = ((p - a).dot(&d) / len2).clamp(0.0, 1.0);
    (p - (a + d * s)).norm()
}

/// The interior index of `pts[i..=j]` farthest from `dist`, and that distance.
fn farthest(i: usize, j: usize, dist: impl Fn(usize) -> f64) -> Option<(usize, f64)> {
    (i + 1..j)
        .map(|m| (m, dist(m)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

/// Runs IEF.
pub fn ief(rays: &ScanRays, config: &PolylineConfig) -> Polylines {
    let (pts, beams) = returned_points(rays);
    if pts.len() < 2 {
        return Polylines::default();
    }
    let mut breaks = vec![0, pts.len() - 1];
    while breaks.len() < config.max_vertices {
        let best = breaks
            .windows(2)
            .filter_map(|w| {
                let (i, j) = (w[0], w[1]);
                farthest(i, j, |m| point_segment_distance(&pts[m], &pts[i], &pts[j]))
            })
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((m, d)) = best else { break };
        if d < config.split_threshold_m {
            break;
        }
        let at = breaks.partition_point(|&b| b < m);
        breaks.insert(at, m);
    }
    Polylines {
        lines: vec![Polyline {
            vertices: breaks.iter().map(|&i| pts[i]).collect(),
            rays: breaks.iter().map(|&i| beams[i]).collect(),
            closed: false,
        }],
    }
}

/// A total-least-squares line: a point on it and its unit direction.
#[derive(Clone, Copy, Debug)]
struct Line {
    centroid: Point2<f64>,
    dir: Vector2<f64>,
}

impl Line {
    fn fit(pts: &[Point2<f64>]) -> Line {
        let n = pts.len().max(1) as f64;
        let c = pts.iter().fold(Vector2::zeros(), |s, p| s + p.coords) / n;
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        for p in pts {
            let d = p.coords - c;
            sxx += d.x * d.x;
            sxy += d.x * d.y;
            syy += d.y * d.y;
        }
        let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        Line {
            centroid: Point2::from(c),
            dir: Vector2::new(angle.cos(), angle.sin()),
        }
    }

    fn distance(&self, p: &Point2<f64>) -> f64 {
        (p - self.centroid).perp(&self.dir).abs()
    }

    fn project(&self, p: &Point2<f64>) -> Point2<f64> {
        self.centroid + self.dir * (p - self.centroid).dot(&self.dir)
    }

    fn max_distance(pts: &[Point2<f64>]) -> f64 {
        let line = Line::fit(pts);
        pts.iter().map(|p| line.distance(p)).fold(0.0, f64::max)
    }
}

/// Runs SAM.
pub fn sam(rays: &ScanRays, config: &PolylineConfig) -> Polylines {
    let (pts, beams) = returned_points(rays);
    if pts.len() < 2 {
        return Polylines::default();
    }
    // Pieces are index ranges [breaks[i], breaks[i + 1]] sharing their break points.
    let mut breaks = vec![0, pts.len() - 1];
    while breaks.len() < config.max_vertices {
        let best = breaks
            .windows(2)
            .filter_map(|w| {
                let (i, j) = (w[0], w[1]);
                let line = Line::fit(&pts[i..=j]);
                farthest(i, j, |m| line.distance(&pts[m]))
            })
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((m, d)) = best else { break };
        if d < config.split_threshold_m {
            break;
        }
        let at = breaks.partition_point(|&b| b < m);
        breaks.insert(at, m);
    }
    // Merge neighbouring pieces whose joint fit is within the threshold.
    let mut i = 1;
    while i + 1 < breaks.len() {
        let (a, b) = (breaks[i - 1], breaks[i + 1]);
        if Line::max_distance(&pts[a..=b]) < config.split_threshold_m {
            breaks.remove(i);
        } else {
            i += 1;
        }
    }
    let lines: Vec<Line> = breaks
        .windows(2)
        .map(|w| Line::fit(&pts[w[0]..=w[1]]))
        .collect();
    let mut vertices = Vec::with_capacity(breaks.len());
    let mut rays_of = Vec::with_capacity(breaks.len());
    for (v, &b) in breaks.iter().enumerate() {
        let point = if v == 0 {
            lines[0].project(&pts[b])
        } else if v + 1 == breaks.len() {
            lines[v - 1].project(&pts[b])
        } else {
            corner(&lines[v - 1], &lines[v], &pts[b])
        };
        vertices.push(point);
        rays_of.push(beams[b]);
    }
    Polylines {
        lines: vec![Polyline {
            vertices,
            rays: rays_of,
            closed: false,
        }],
    }
}

/// The vertex between two fitted lines: their intersection, or (nearly parallel lines, or
/// an intersection more than 1 m from the break point) the mean of the break point's
/// projections onto both.
fn corner(a: &Line, b: &Line, at: &Point2<f64>) -> Point2<f64> {
    let fallback = Point2::from((a.project(at).coords + b.project(at).coords) * 0.5);
    let denom = a.dir.perp(&b.dir);
    if denom.abs() < 1e-6 {
        return fallback;
    }
    let t = (b.centroid - a.centroid).perp(&b.dir) / denom;
    let x = a.centroid + a.dir * t;
    if (x - at).norm() > 1.0 { fallback } else { x }
}
