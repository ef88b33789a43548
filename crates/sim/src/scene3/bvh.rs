//! A bounding volume hierarchy over triangles for first-hit ray casting.
//!
//! Built top-down with the surface area heuristic over 16 centroid bins per axis (leaves of at
//! most 4 triangles, depth at most [`MAX_DEPTH`]); children are stored side by side. Rays
//! walk it front to back with a fixed-size stack (no allocation), test boxes with the slab
//! method and triangles with the Möller–Trumbore algorithm (boxes in `f32`, padded to cover
//! the rounding; triangles in `f64`). Triangles with an edge longer than 6 m are cut into
//! pieces first (longest-edge bisection), which keeps the boxes of road surfaces and facades
//! tight. This replaced parry3d's `TriMesh` ray cast, being faster on the urban HDL-64E
//! workload of `benches/rays.rs` (which times both); the results agree (`tests/scene3.rs`
//! cross-checks both).

use nalgebra::{Point3, Vector3};

/// Deepest level of the tree (the traversal stack holds `MAX_DEPTH + 2` entries).
const MAX_DEPTH: usize = 60;
/// Most triangles in a leaf.
const LEAF_SIZE: usize = 4;
/// Centroid bins per axis of the SAH split search.
const BINS: usize = 16;
/// Triangles with a longer edge are cut into pieces for the hierarchy, metres.
const SPLIT_EDGE_M: f64 = 6.0;
/// At most this many pieces per triangle on average (plus a million) are made.
const PIECE_BUDGET: usize = 8;
/// Nodes with more triangles are split even when the heuristic prefers a leaf.
const FORCED_SPLIT: usize = 16;

/// A triangle prepared for intersection tests.
#[derive(Clone, Copy, Debug)]
struct Triangle {
    v0: Vector3<f64>,
    e1: Vector3<f64>,
    e2: Vector3<f64>,
    /// Unit normal `e1 × e2 / |e1 × e2|`.
    normal: Vector3<f64>,
    /// `|e1 × e2|`: twice the area.
    area2: f64,
    /// Index of the triangle in the scene.
    id: u32,
}

impl Triangle {
    fn new(a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>, id: u32) -> Self {
        let (e1, e2) = (b - a, c - a);
        let cross = e1.cross(&e2);
        let area2 = cross.norm();
        Triangle {
            v0: a.coords,
            e1,
            e2,
            normal: if area2 > 0.0 {
                cross / area2
            } else {
                Vector3::z()
            },
            area2,
            id,
        }
    }
}

/// A node: a box, and either two children (`count == 0`, children at `first` and `first + 1`)
/// or `count` triangles from `first`.
#[derive(Clone, Copy, Debug)]
struct Node {
    min: [f32; 3],
    max: [f32; 3],
    first: u32,
    count: u32,
}

/// The hierarchy.
#[derive(Clone, Debug)]
pub(super) struct Bvh {
    nodes: Vec<Node>,
    triangles: Vec<Triangle>,
}

/// A ray hit: distance, unit normal (not oriented) and triangle index.
pub(super) struct BvhHit {
    pub t: f64,
    pub normal: Vector3<f64>,
    pub triangle: u32,
}

#[derive(Clone, Copy)]
struct Bounds {
    min: Vector3<f64>,
    max: Vector3<f64>,
}

impl Bounds {
    fn empty() -> Self {
        Self {
            min: Vector3::repeat(f64::INFINITY),
            max: Vector3::repeat(f64::NEG_INFINITY),
        }
    }

    fn grow(&mut self, p: &Vector3<f64>) {
        self.min = self.min.inf(p);
        self.max = self.max.sup(p);
    }

    fn merge(&mut self, other: &Bounds) {
        self.min = self.min.inf(&other.min);
        self.max = self.max.sup(&other.max);
    }

    fn area(&self) -> f64 {
        let d = self.max - self.min;
        if d.iter().any(|v| *v < 0.0) {
            0.0
        } else {
            d.x * d.y + d.y * d.z + d.z * d.x
        }
    }
}

impl Bvh {
    /// Builds the hierarchy over `triangles` (corner points; the index is the triangle id).
    pub fn build(triangles: &[[Point3<f64>; 3]]) -> Self {
        // Long triangles (road surfaces, facades) are cut into pieces of at most
        // `SPLIT_EDGE_M` per edge, so that boxes stay tight; every piece keeps the id of its
        // triangle, and a ray hits a piece exactly where it hits the triangle.
        let budget = triangles.len().saturating_mul(PIECE_BUDGET) + 1_000_000;
        let mut tris: Vec<Triangle> = Vec::with_capacity(triangles.len());
        let mut work: Vec<[Point3<f64>; 3]> = Vec::new();
        for (id, corners) in triangles.iter().enumerate() {
            work.push(*corners);
            while let Some([a, b, c]) = work.pop() {
                let edges = [(b - a).norm(), (c - b).norm(), (a - c).norm()];
                let longest = (0..3).fold(0, |k, i| if edges[i] > edges[k] { i } else { k });
                if edges[longest] > SPLIT_EDGE_M && tris.len() + work.len() < budget {
                    // Bisect the longest edge.
                    let (p, q, r) = match longest {
                        0 => (a, b, c),
                        1 => (b, c, a),
                        _ => (c, a, b),
                    };
                    let m = Point3::from((p.coords + q.coords) / 2.0);
                    work.push([p, m, r]);
                    work.push([m, q, r]);
                    continue;
                }
                tris.push(Triangle::new(&a, &b, &c, id as u32));
            }
        }
        let mut nodes = Vec::with_capacity(2 * tris.len().max(1));
        nodes.push(Node {
            min: [0.0; 3],
            max: [0.0; 3],
            first: 0,
            count: 0,
        });
        let n = tris.len();
        build_node(&mut nodes, &mut tris, 0, 0, n, 0);
        Self {
            nodes,
            triangles: tris,
        }
    }

    /// The first hit of `origin + t · direction` with `0 ≤ t ≤ max_t`.
    pub fn cast(
        &self,
        origin: &Point3<f64>,
        direction: &Vector3<f64>,
        max_t: f64,
    ) -> Option<BvhHit> {
        let o = origin.coords;
        let o32: [f32; 3] = std::array::from_fn(|i| o[i] as f32);
        let inv32: [f32; 3] = std::array::from_fn(|i| 1.0 / direction[i] as f32);
        let mut closest = max_t;
        let mut best: Option<(f64, usize)> = None;
        let mut stack = [(0u32, 0.0f32); MAX_DEPTH + 2];
        let root = self.nodes.first()?;
        let mut depth = match slab(root, &o32, &inv32, closest as f32) {
            Some(t) => {
                stack[0] = (0, t);
                1
            }
            None => 0,
        };
        while depth > 0 {
            depth -= 1;
            let (index, t_enter) = stack[depth];
            if f64::from(t_enter) > closest {
                continue;
            }
            let Some(node) = self.nodes.get(index as usize) else {
                continue;
            };
            if node.count > 0 {
                let first = node.first as usize;
                let leaf = self
                    .triangles
                    .get(first..first + node.count as usize)
                    .unwrap_or(&[]);
                for (k, tri) in leaf.iter().enumerate() {
                    if let Some(t) = intersect(tri, &o, direction, closest) {
                        closest = t;
                        best = Some((t, first + k));
                    }
                }
                continue;
            }
            let (left, right) = (node.first, node.first + 1);
            let hit = |i: u32| {
                self.nodes
                    .get(i as usize)
                    .and_then(|n| slab(n, &o32, &inv32, closest as f32))
                    .map(|t| (i, t))
            };
            match (hit(left), hit(right)) {
                (Some(a), Some(b)) => {
                    let (near, far) = if a.1 <= b.1 { (a, b) } else { (b, a) };
                    if depth + 2 <= stack.len() {
                        stack[depth] = far;
                        stack[depth + 1] = near;
                        depth += 2;
                    }
                }
                (Some(a), None) | (None, Some(a)) => {
                    if depth < stack.len() {
                        stack[depth] = a;
                        depth += 1;
                    }
                }
                (None, None) => {}
            }
        }
        let (t, k) = best?;
        let tri = self.triangles.get(k)?;
        Some(BvhHit {
            t,
            normal: tri.normal,
            triangle: tri.id,
        })
    }
}

/// Entry distance of the ray into the node's box if it meets it within `[0, max_t]`
/// (`f32`: the boxes are padded to cover the rounding).
#[inline]
fn slab(node: &Node, o: &[f32; 3], inv: &[f32; 3], max_t: f32) -> Option<f32> {
    let mut t0 = 0.0_f32;
    let mut t1 = max_t;
    for axis in 0..3 {
        let a = (node.min[axis] - o[axis]) * inv[axis];
        let b = (node.max[axis] - o[axis]) * inv[axis];
        // NaN (0 · ∞: a parallel ray in the plane of a face) does not constrain: the box
        // is closed.
        let (lo, hi) = if a <= b {
            (a, b)
        } else if b < a {
            (b, a)
        } else {
            continue;
        };
        t0 = if lo > t0 { lo } else { t0 };
        t1 = if hi < t1 { hi } else { t1 };
    }
    (t0 <= t1).then_some(t0)
}

/// The `f32` box covering `bounds` with a margin for the `f32` rounding of ray origins far
/// from zero (1e-6 relative plus 0.1 mm).
fn padded(bounds: &Bounds) -> ([f32; 3], [f32; 3]) {
    let pad = |v: f64| v.abs() * 1e-6 + 1e-4;
    (
        std::array::from_fn(|i| (bounds.min[i] - pad(bounds.min[i])) as f32),
        std::array::from_fn(|i| (bounds.max[i] + pad(bounds.max[i])) as f32),
    )
}

/// Möller–Trumbore: the distance to `tri` if the ray meets it within `[0, max_t)`.
#[inline]
fn intersect(tri: &Triangle, o: &Vector3<f64>, d: &Vector3<f64>, max_t: f64) -> Option<f64> {
    let p = d.cross(&tri.e2);
    let det = tri.e1.dot(&p);
    if det.abs() <= 1e-12 * tri.area2 {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = o - tri.v0;
    let u = s.dot(&p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(&tri.e1);
    let v = d.dot(&q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = tri.e2.dot(&q) * inv_det;
    (t >= 0.0 && t < max_t).then_some(t)
}

fn triangle_bounds(tri: &Triangle) -> Bounds {
    let mut b = Bounds::empty();
    b.grow(&tri.v0);
    b.grow(&(tri.v0 + tri.e1));
    b.grow(&(tri.v0 + tri.e2));
    b
}

fn centroid(tri: &Triangle) -> Vector3<f64> {
    tri.v0 + (tri.e1 + tri.e2) / 3.0
}

/// Fills node `index` with the triangles `tris[start..end]`, splitting recursively.
fn build_node(
    nodes: &mut Vec<Node>,
    tris: &mut [Triangle],
    index: usize,
    start: usize,
    end: usize,
    depth: usize,
) {
    let mut bounds = Bounds::empty();
    let mut centroids = Bounds::empty();
    for tri in &tris[start..end] {
        bounds.merge(&triangle_bounds(tri));
        centroids.grow(&centroid(tri));
    }
    let count = end - start;
    let (min, max) = padded(&bounds);
    let leaf = Node {
        min,
        max,
        first: start as u32,
        count: count as u32,
    };
    if count <= LEAF_SIZE || depth >= MAX_DEPTH {
        nodes[index] = leaf;
        return;
    }
    // Split where the surface area heuristic says so; larger sets are split even when it
    // does not (long overlapping triangles), by the best bin boundary or else in halves.
    let leaf_cost = bounds.area() * count as f64;
    let mid = match best_split(&tris[start..end], &centroids) {
        Some((cost, axis, split)) if cost < leaf_cost || count > FORCED_SPLIT => {
            let (lo, extent) = (
                centroids.min[axis],
                centroids.max[axis] - centroids.min[axis],
            );
            let mut mid = start;
            for i in start..end {
                if bin_index(centroid(&tris[i])[axis], lo, extent) < split {
                    tris.swap(i, mid);
                    mid += 1;
                }
            }
            mid
        }
        None if count > FORCED_SPLIT => start + count / 2,
        _ => start,
    };
    if mid == start || mid == end {
        nodes[index] = leaf;
        return;
    }
    let left = nodes.len();
    let placeholder = Node { count: 0, ..leaf };
    nodes.push(placeholder);
    nodes.push(placeholder);
    nodes[index] = Node {
        min,
        max,
        first: left as u32,
        count: 0,
    };
    build_node(nodes, tris, left, start, mid, depth + 1);
    build_node(nodes, tris, left + 1, mid, end, depth + 1);
}

/// The bin of a centroid coordinate `c` in `[lo, lo + extent]`.
#[inline]
fn bin_index(c: f64, lo: f64, extent: f64) -> usize {
    (((c - lo) / extent * BINS as f64) as usize).min(BINS - 1)
}

/// The SAH cost, axis and bin index (triangles in lower bins go left) of the best split;
/// `None` when all centroids coincide.
fn best_split(tris: &[Triangle], centroids: &Bounds) -> Option<(f64, usize, usize)> {
    let mut best: Option<(f64, usize, usize)> = None;
    for axis in 0..3 {
        let (lo, extent) = (
            centroids.min[axis],
            centroids.max[axis] - centroids.min[axis],
        );
        if extent <= 0.0 {
            continue;
        }
        let mut bins = [(Bounds::empty(), 0usize); BINS];
        for tri in tris {
            let b = bin_index(centroid(tri)[axis], lo, extent);
            bins[b].0.merge(&triangle_bounds(tri));
            bins[b].1 += 1;
        }
        // Sweep: areas and counts left of each boundary, then right.
        let mut left_area = [0.0; BINS];
        let mut left_count = [0usize; BINS];
        let (mut acc, mut n) = (Bounds::empty(), 0);
        for i in 0..BINS - 1 {
            acc.merge(&bins[i].0);
            n += bins[i].1;
            left_area[i + 1] = acc.area();
            left_count[i + 1] = n;
        }
        let (mut acc, mut n) = (Bounds::empty(), 0);
        for split in (1..BINS).rev() {
            acc.merge(&bins[split].0);
            n += bins[split].1;
            if left_count[split] == 0 || n == 0 {
                continue;
            }
            let cost = left_area[split] * left_count[split] as f64 + acc.area() * n as f64;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, split));
            }
        }
    }
    best
}
