//! IEF and SAM: top-down splitting of the endpoint sequence.
//!
//! Both drop the no-returns first (they cannot represent them) and treat the remaining
//! endpoints, in beam order, as one sequence from the first to the last endpoint.
//!
//! * **IEF** (iterative end-point fit, Duda & Hart; Douglas–Peucker style): start with the
//!   segment from the first to the last endpoint; repeatedly split the segment with the
//!   endpoint farthest from it at that endpoint, until `J_max` vertices or no endpoint is
//!   farther than `split_threshold_m` (reference implementation: 0.01 m). Vertices are
//!   endpoints, so the result is one connected polyline.
//! * **SAM** (split-and-merge, Pavlidis & Horowitz 1974), as Schaefer (2020, §10.5) runs it:
//!   every piece of the endpoint sequence carries its own least-squares segment (the
//!   total-least-squares line through its endpoints, cut at the projections of its first and
//!   last endpoint). Split the piece whose endpoint lies farthest from its segment at that
//!   endpoint and refit both halves, while some endpoint is farther than
//!   `split_threshold_m` or the segments have fewer than `J_max` vertices; then merge the
//!   two neighbouring pieces whose shared endpoint lies closest to the joined segment, and
//!   refit, until at most `J_max` vertices remain. Fitted neighbours do not share their
//!   end vertices, so the result is a set of separate segments (each two vertices): a depth
//!   jump between two pieces stays open, and the rays there hit nothing — the thesis' "SAM
//!   misses many rays". (An earlier version of this module joined neighbouring fitted lines
//!   at their intersections into one polyline; the corners of lines fitted to distant pieces
//!   then lay far in free space and the RMSE of rays hitting those bridges was metres.)

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

    fn project(&self, p: &Point2<f64>) -> Point2<f64> {
        self.centroid + self.dir * (p - self.centroid).dot(&self.dir)
    }
}

/// Runs SAM (see the module docs).
pub fn sam(rays: &ScanRays, config: &PolylineConfig) -> Polylines {
    let (pts, beams) = returned_points(rays);
    if pts.len() < 2 {
        return Polylines::default();
    }
    let mut pieces = vec![Piece::fit(&pts, 0, pts.len() - 1)];
    // Split: the endpoint farthest from its piece's segment, while any is beyond the
    // threshold or vertices are missing.
    loop {
        let worst = pieces
            .iter()
            .enumerate()
            .filter_map(|(k, piece)| {
                farthest(piece.first, piece.last, |m| piece.distance(&pts[m]))
                    .map(|(m, d)| (k, m, d))
            })
            .max_by(|a, b| a.2.total_cmp(&b.2));
        let Some((k, m, d)) = worst else { break };
        if d < config.split_threshold_m && vertex_count(&pieces) >= config.max_vertices {
            break;
        }
        let (first, last) = (pieces[k].first, pieces[k].last);
        pieces[k] = Piece::fit(&pts, first, m);
        pieces.insert(k + 1, Piece::fit(&pts, m, last));
    }
    // Merge: the shared endpoint closest to the segment joining its two pieces.
    while vertex_count(&pieces) > config.max_vertices && pieces.len() > 1 {
        let Some((k, _)) = pieces
            .windows(2)
            .enumerate()
            .map(|(k, w)| {
                let shared = &pts[w[0].last];
                (k, point_segment_distance(shared, &w[0].start, &w[1].end))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
        else {
            break;
        };
        let (first, last) = (pieces[k].first, pieces[k + 1].last);
        pieces[k] = Piece::fit(&pts, first, last);
        pieces.remove(k + 1);
    }
    polylines_of(&pieces, &beams)
}

/// A run `first..=last` of returned endpoints and its fitted segment `start → end`.
#[derive(Clone, Copy, Debug)]
struct Piece {
    first: usize,
    last: usize,
    start: Point2<f64>,
    end: Point2<f64>,
}

impl Piece {
    /// The total-least-squares segment of `pts[first..=last]`, cut at the projections of the
    /// first and last endpoint; two endpoints are their own segment.
    fn fit(pts: &[Point2<f64>], first: usize, last: usize) -> Piece {
        let (start, end) = if last - first < 2 {
            (pts[first], pts[last])
        } else {
            let line = Line::fit(&pts[first..=last]);
            (line.project(&pts[first]), line.project(&pts[last]))
        };
        Piece {
            first,
            last,
            start,
            end,
        }
    }

    fn distance(&self, p: &Point2<f64>) -> f64 {
        point_segment_distance(p, &self.start, &self.end)
    }
}

/// Vertices of the pieces joined where a segment ends exactly where the next starts (only
/// unfitted two-point pieces do), as the reference implementation counts them.
fn vertex_count(pieces: &[Piece]) -> usize {
    let joined = pieces
        .windows(2)
        .filter(|w| (w[0].end - w[1].start).norm() <= 1e-10)
        .count();
    2 * pieces.len() - joined
}

/// The pieces as polylines: neighbours that share an end vertex form one polyline.
fn polylines_of(pieces: &[Piece], beams: &[usize]) -> Polylines {
    let mut lines: Vec<Polyline> = Vec::new();
    let mut previous: Option<&Piece> = None;
    for piece in pieces {
        let joins = previous.is_some_and(|p| (p.end - piece.start).norm() <= 1e-10);
        match lines.last_mut() {
            Some(line) if joins => {
                line.vertices.push(piece.end);
                line.rays.push(beams[piece.last]);
            }
            _ => lines.push(Polyline {
                vertices: vec![piece.start, piece.end],
                rays: vec![beams[piece.first], beams[piece.last]],
                closed: false,
            }),
        }
        previous = Some(piece);
    }
    Polylines { lines }
}
