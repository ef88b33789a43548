//! PLE: greedy maximum-likelihood vertex removal (Algorithm 1, lines 11–21; Eq. 10.3).
//!
//! The vertices live in an arena of doubly linked lists (one list per polyline), the removal
//! errors `e_j` in a binary heap with lazy deletion: each vertex carries a version counter, and
//! a heap entry whose version is stale is skipped. Removing a vertex recomputes the errors of
//! its two neighbours, and of the end vertices two steps away (their error depends on the
//! segment after their neighbour); each iteration costs O(log n) plus the intersections of
//! the beams in the affected sectors.
//!
//! Error of removing `v_j` (`e_j` of Eq. 10.3 in Schaefer 2020, §10.4.2, in the form of the
//! reference implementation's `rmverror`, in units of `d²/Σ`):
//!
//! * interior vertex (or any vertex of a polygon): `R` = returned beams hitting the two
//!   segments at `v_j` (local polyline only, no occlusion by the rest of the map);
//!   `e_j = Σ_R [(r − r̂_short)² − (r − r̂_orig)²]`, with `d_rm` for a beam the shortcut misses;
//! * end vertex: the beams of its segment lose their explanation (`d_rm²`) unless the next
//!   segment still explains them (the beam through the neighbouring vertex) — equal to the
//!   reference implementation's `− d_rm²·[n_v > 2]` term;
//! * a polyline of two vertices is removed as a whole (J drops by two).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use nalgebra::Point2;

use crate::initial::Chain;
use crate::rays::ScanRays;
use crate::{Polyline, Polylines};

const NONE: usize = usize::MAX;

#[derive(Clone, Debug)]
struct Node {
    point: Point2<f64>,
    ray: usize,
    prev: usize,
    next: usize,
    line: usize,
    alive: bool,
    version: u32,
}

#[derive(Clone, Debug)]
struct Line {
    head: usize,
    count: usize,
    closed: bool,
}

/// A heap entry; ordered so that the smallest error pops first (ties: lowest vertex id).
#[derive(Clone, Copy, Debug)]
struct Entry {
    error: f64,
    node: usize,
    version: u32,
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .error
            .total_cmp(&self.error)
            .then_with(|| other.node.cmp(&self.node))
    }
}

/// Parameters of the greedy removal.
#[derive(Clone, Copy, Debug)]
pub struct Greedy {
    /// `J_max`.
    pub max_vertices: usize,
    /// `d_rm` in metres.
    pub removed_residual_m: f64,
    /// `Σ` in m².
    pub variance_m2: f64,
    /// `e_max` (in units of `d²/Σ`).
    pub max_error_increase: f64,
}

/// The greedy extraction state.
struct State<'a> {
    rays: &'a ScanRays,
    nodes: Vec<Node>,
    lines: Vec<Line>,
    heap: BinaryHeap<Entry>,
    params: Greedy,
    /// Scratch: beam indices of the sector being evaluated.
    scratch: Vec<usize>,
}

/// Runs the greedy removal on the initial chains.
pub fn simplify(rays: &ScanRays, chains: &[Chain], params: Greedy) -> Polylines {
    let mut state = State::new(rays, chains, params);
    state.run();
    state.result()
}

impl<'a> State<'a> {
    fn new(rays: &'a ScanRays, chains: &[Chain], params: Greedy) -> Self {
        let mut nodes = Vec::with_capacity(chains.iter().map(|c| c.rays.len()).sum());
        let mut lines = Vec::with_capacity(chains.len());
        for (line, chain) in chains.iter().enumerate() {
            let first = nodes.len();
            let n = chain.rays.len();
            for (i, &k) in chain.rays.iter().enumerate() {
                let point = rays.endpoint(k).unwrap_or_else(Point2::origin);
                let prev = if i > 0 {
                    first + i - 1
                } else if chain.closed {
                    first + n - 1
                } else {
                    NONE
                };
                let next = if i + 1 < n {
                    first + i + 1
                } else if chain.closed {
                    first
                } else {
                    NONE
                };
                nodes.push(Node {
                    point,
                    ray: k,
                    prev,
                    next,
                    line,
                    alive: true,
                    version: 0,
                });
            }
            lines.push(Line {
                head: first,
                count: n,
                closed: chain.closed,
            });
        }
        let heap = BinaryHeap::with_capacity(nodes.len() * 2);
        Self {
            rays,
            nodes,
            lines,
            heap,
            params,
            scratch: Vec::with_capacity(64),
        }
    }

    fn vertex_count(&self) -> usize {
        self.lines.iter().map(|l| l.count).sum()
    }

    fn run(&mut self) {
        for id in 0..self.nodes.len() {
            self.push(id);
        }
        let mut count = self.vertex_count();
        while count > self.params.max_vertices {
            let Some(entry) = self.heap.pop() else {
                break;
            };
            let node = &self.nodes[entry.node];
            if !node.alive || node.version != entry.version {
                continue;
            }
            if entry.error > self.params.max_error_increase {
                break;
            }
            count -= self.remove(entry.node);
        }
    }

    fn push(&mut self, id: usize) {
        let error = self.removal_error(id);
        let node = &mut self.nodes[id];
        node.version = node.version.wrapping_add(1);
        let version = node.version;
        self.heap.push(Entry {
            error,
            node: id,
            version,
        });
    }

    /// Removes vertex `id` and returns how many vertices disappeared (1, or 2 when a
    /// two-vertex polyline goes).
    fn remove(&mut self, id: usize) -> usize {
        let Node {
            prev, next, line, ..
        } = self.nodes[id].clone();
        let count = self.lines[line].count;
        if count <= 2 {
            for v in [id, prev, next] {
                if v != NONE {
                    self.nodes[v].alive = false;
                }
            }
            self.lines[line].count = 0;
            return count;
        }
        self.nodes[id].alive = false;
        if prev != NONE {
            self.nodes[prev].next = next;
        }
        if next != NONE {
            self.nodes[next].prev = prev;
        }
        let l = &mut self.lines[line];
        l.count -= 1;
        if l.head == id {
            l.head = next;
        }
        if l.closed && l.count == 2 {
            // A triangle lost a vertex: what remains is the open segment next → prev.
            l.closed = false;
            l.head = next;
            self.nodes[next].prev = NONE;
            self.nodes[prev].next = NONE;
        }
        // Recompute the neighbours, and end vertices whose next-but-one segment changed.
        let mut touched = [prev, next, NONE, NONE];
        if prev != NONE {
            let pp = self.nodes[prev].prev;
            if pp != NONE && self.is_end(pp) {
                touched[2] = pp;
            }
        }
        if next != NONE {
            let nn = self.nodes[next].next;
            if nn != NONE && self.is_end(nn) {
                touched[3] = nn;
            }
        }
        for v in touched {
            if v != NONE && self.nodes[v].alive {
                self.push(v);
            }
        }
        1
    }

    fn is_end(&self, id: usize) -> bool {
        let n = &self.nodes[id];
        n.prev == NONE || n.next == NONE
    }

    /// `e_j` of Eq. (10.3) for vertex `id`.
    fn removal_error(&mut self, id: usize) -> f64 {
        let node = &self.nodes[id];
        let (prev, next) = (node.prev, node.next);
        let v = node.point;
        let d_rm2 = self.params.removed_residual_m * self.params.removed_residual_m;
        let rays = self.rays;
        let mut sum = 0.0;
        match (prev != NONE, next != NONE) {
            (true, true) => {
                let p = self.nodes[prev].point;
                let q = self.nodes[next].point;
                self.collect(&[(p, v), (v, q)]);
                for &k in &self.scratch {
                    let Some(r) = rays.radius(k) else { continue };
                    let before = min_hit(rays, k, &[(p, v), (v, q)]);
                    let Some(before) = before else { continue };
                    let after = rays.hit(k, &p, &q).map_or(d_rm2, |t| (r - t) * (r - t));
                    sum += after - (r - before) * (r - before);
                }
            }
            (true, false) | (false, true) => {
                let (n1, outer) = if prev != NONE {
                    (prev, self.nodes[prev].prev)
                } else {
                    (next, self.nodes[next].next)
                };
                let p = self.nodes[n1].point;
                let beyond = (outer != NONE).then(|| self.nodes[outer].point);
                self.collect(&[(v, p)]);
                for &k in &self.scratch {
                    let Some(r) = rays.radius(k) else { continue };
                    let Some(before) = rays.hit(k, &v, &p) else {
                        continue;
                    };
                    let after = beyond
                        .and_then(|b| rays.hit(k, &p, &b))
                        .map_or(d_rm2, |t| (r - t) * (r - t));
                    sum += after - (r - before) * (r - before);
                }
            }
            (false, false) => {}
        }
        sum / self.params.variance_m2
    }

    /// Fills `scratch` with the beams in the sectors of `segments` (sorted, no repeats).
    fn collect(&mut self, segments: &[(Point2<f64>, Point2<f64>)]) {
        self.scratch.clear();
        for (p, q) in segments {
            let scratch = &mut self.scratch;
            self.rays
                .for_each_ray_in_segment_arc(p, q, |k| scratch.push(k));
        }
        self.scratch.sort_unstable();
        self.scratch.dedup();
    }

    fn result(&self) -> Polylines {
        let mut lines = Vec::new();
        for line in &self.lines {
            if line.count < 2 || line.head == NONE {
                continue;
            }
            let mut vertices = Vec::with_capacity(line.count);
            let mut beams = Vec::with_capacity(line.count);
            let mut id = line.head;
            for _ in 0..line.count {
                if id == NONE {
                    break;
                }
                vertices.push(self.nodes[id].point);
                beams.push(self.nodes[id].ray);
                id = self.nodes[id].next;
            }
            lines.push(Polyline {
                vertices,
                rays: beams,
                closed: line.closed,
            });
        }
        Polylines { lines }
    }
}

/// The first hit of beam `k` on any of `segments`.
pub(crate) fn min_hit(
    rays: &ScanRays,
    k: usize,
    segments: &[(Point2<f64>, Point2<f64>)],
) -> Option<f64> {
    segments
        .iter()
        .filter_map(|(p, q)| rays.hit(k, p, q))
        .min_by(f64::total_cmp)
}
