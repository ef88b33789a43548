//! The extraction result: polylines and polygons in the scan frame.

use nalgebra::Point2;
use serde::Serialize;

/// One polyline (open) or polygon (closed) of the map, vertices in the scan frame (metres).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Polyline {
    /// The vertices in order (at least two; no repeated first vertex for a polygon).
    pub vertices: Vec<Point2<f64>>,
    /// For each vertex, the beam whose endpoint created it. After PLE+ the start and end
    /// vertices of an open polyline still lie on their beams; the others may have moved.
    pub rays: Vec<usize>,
    /// True for a closed polygon (the last vertex connects back to the first).
    pub closed: bool,
}

impl Polyline {
    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    /// True when the polyline has no vertices.
    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// The segments `(p, q)`, including the closing one of a polygon.
    pub fn segments(&self) -> impl Iterator<Item = (Point2<f64>, Point2<f64>)> + '_ {
        let n = self.vertices.len();
        let count = match (self.closed, n) {
            (_, 0 | 1) => 0,
            (true, 2) => 1,
            (true, _) => n,
            (false, _) => n - 1,
        };
        (0..count).map(move |i| (self.vertices[i], self.vertices[(i + 1) % n]))
    }
}

/// A polyline map `L`: polylines with pairwise distinct vertices.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Polylines {
    /// The polylines and polygons.
    pub lines: Vec<Polyline>,
}

impl Polylines {
    /// `J(L)`: the total number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.lines.iter().map(Polyline::len).sum()
    }

    /// All segments of all polylines.
    pub fn segments(&self) -> impl Iterator<Item = (Point2<f64>, Point2<f64>)> + '_ {
        self.lines.iter().flat_map(Polyline::segments)
    }

    /// All vertices of all polylines.
    pub fn vertices(&self) -> impl Iterator<Item = Point2<f64>> + '_ {
        self.lines.iter().flat_map(|l| l.vertices.iter().copied())
    }
}
