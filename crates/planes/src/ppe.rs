//! PPE: agglomerative maximum-likelihood plane extraction (Schaefer 2020, ch. 11,
//! Algorithm 2, with the efficiency measures of the reference implementation).
//!
//! Every returned ray starts as an atomic plane (error 0). Three actions grow planes:
//! **create** a regular plane from a valid tetromino of four atomic neighbours (cost
//! `e_crt`, Eq. 11.4), **extend** a plane by a 4-adjacent atomic ray (`e_ext`) and **merge**
//! two 4-adjacent planes (`e_mrg`). The action with the least error increment (Eq. 11.3) is
//! executed until the least increment exceeds `e` ([`PpeParams::max_increment_m2`]) or at
//! most `n` planes remain ([`PpeParams::max_planes`]). 4-neighbours farther apart than
//! `l_max` are never joined (the outlier filter `d`).
//!
//! The candidates live in one lazy priority queue keyed by the increment computed when
//! they were queued: a popped candidate is re-evaluated for the current planes and executed
//! if its increment is still no larger than the next key, else queued again; so only the
//! candidates at the front of the queue are ever recomputed. A final pass re-evaluates
//! every queued candidate before stopping (stale keys are not lower bounds).
//!
//! Merge candidates are queued once per pair of planes (again only with a smaller key),
//! which keeps the queue near the number of boundary rays.
//!
//! Optional post-processing ([`PpeParams::refine_rounds`], not in the thesis): each round
//! (1) moves every ray on a plane boundary to the adjacent plane with the least radial
//! residual, (2) merges 4-adjacent planes while the increment stays within `e`, and (3)
//! merges the pieces of one surface split by an occluder — plane `a` ends along a row or
//! column, only rays in front of the joint plane of `a` and `b` follow, then `b` begins —
//! while the increment stays within `e`. Each round costs O(K) plus the merges.
//!
//! Cost: seeding evaluates 17 tetrominoes per ray (parallel, rayon); every action costs
//! O(1) solves plus O(log Q) queue operations; a merge relabels the smaller plane
//! (O(K log K) relabelling in total). Final exact refits are O(K · iterations).
//! Each increment costs one 3 × 3 solve on the additive statistics of
//! [`crate::PlaneStats`]; the planes of the result are refitted on the exact radial
//! residuals ([`crate::fit::refine`]).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use nalgebra::Vector3;
use rayon::prelude::*;
use raypath_geometry::PointCloud;

use crate::error::PlaneError;
use crate::fit::{PlaneFit, refine};
use crate::params::PpeParams;
use crate::stats::PlaneStats;
use crate::tetromino::TETROMINOES;

const NONE: u32 = u32::MAX;

/// One extracted plane.
#[derive(Debug, Clone, PartialEq)]
pub struct Plane {
    /// Linear indices (`row * width + col`) of its rays.
    pub index: Vec<usize>,
    /// The exact radial fit of its rays.
    pub fit: PlaneFit,
}

/// The result of [`extract`].
#[derive(Debug, Clone, PartialEq)]
pub struct Segmentation {
    /// Grid width (second index).
    pub width: usize,
    /// Grid height (first index).
    pub height: usize,
    /// Plane id (index into `planes`) of every ray; `None` for no-returns and rays no
    /// plane with at least `min_points` rays explains.
    pub labels: Vec<Option<u32>>,
    /// The planes, largest first.
    pub planes: Vec<Plane>,
    /// Number of clustering actions executed.
    pub steps: usize,
}

impl Segmentation {
    /// Sum of squared radial residuals over all planes (m²).
    pub fn sse(&self) -> f64 {
        self.planes.iter().map(|p| p.fit.sse).sum()
    }

    /// Per-ray radial RMSE over all rays of all planes (m), the thesis' RMSE as its
    /// implementation computes it (Eq. (11.6) prints a division by the number of planes).
    pub fn rmse_m(&self) -> f64 {
        let n: usize = self.planes.iter().map(|p| p.fit.n).sum();
        if n == 0 {
            0.0
        } else {
            (self.sse() / n as f64).sqrt()
        }
    }
}

/// Extracts planes from an organized cloud (sensor frame, metres; NaN coordinates or the
/// origin mark no-returns).
pub fn extract(cloud: &PointCloud, params: &PpeParams) -> Result<Segmentation, PlaneError> {
    if cloud.width == 0
        || cloud.height == 0
        || cloud.width.checked_mul(cloud.height) != Some(cloud.points.len())
    {
        return Err(PlaneError::NotOrganized {
            width: cloud.width,
            height: cloud.height,
            len: cloud.points.len(),
        });
    }
    let points: Vec<Vector3<f64>> = cloud
        .points
        .iter()
        .map(|p| p.coords.cast::<f64>())
        .collect();
    extract_grid(&points, cloud.width, cloud.height, params)
}

/// [`extract`] on a row-major grid of endpoints (`height` rows of `width`).
pub fn extract_grid(
    points: &[Vector3<f64>],
    width: usize,
    height: usize,
    params: &PpeParams,
) -> Result<Segmentation, PlaneError> {
    params.validate()?;
    PlaneError::check_organized(width, height, points.len())?;
    if points.len() >= NONE as usize {
        return Err(PlaneError::Parameter {
            name: "points",
            reason: "too many rays".into(),
        });
    }
    let mut state = State::new(points, width, height, params);
    state.run();
    state.polish();
    Ok(state.finish())
}

#[derive(Debug, Clone, Copy)]
enum Action {
    /// Best tetromino `mask` of atomic ray `point`.
    Create {
        point: u32,
        mask: u8,
    },
    Extend {
        plane: u32,
        point: u32,
    },
    Merge {
        a: u32,
        b: u32,
    },
}

#[derive(Debug, Clone, Copy)]
struct Entry {
    key: f64,
    action: Action,
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.key.total_cmp(&other.key) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    // Reversed: BinaryHeap is a max-heap, we pop the least increment.
    fn cmp(&self, other: &Self) -> Ordering {
        other.key.total_cmp(&self.key)
    }
}

struct Cluster {
    stats: PlaneStats,
    error: f64,
    members: Vec<u32>,
    parent: u32,
    /// Partners of the merge candidates queued for this plane, with the least queued key:
    /// a merge is queued again only with a smaller key (keeps the heap small).
    queued: Vec<(u32, f64)>,
}

struct State<'a> {
    points: &'a [Vector3<f64>],
    width: usize,
    height: usize,
    params: &'a PpeParams,
    valid: Vec<bool>,
    /// Statistics of every ray (zero for no-returns).
    point_stats: Vec<PlaneStats>,
    /// Edge (k, k + 1) usable.
    right: Vec<bool>,
    /// Edge (k, k + width) usable.
    down: Vec<bool>,
    label: Vec<u32>,
    /// Plane of the queued extension of each atomic ray (`NONE`: none queued).
    pending: Vec<u32>,
    clusters: Vec<Cluster>,
    heap: BinaryHeap<Entry>,
    /// The initial creation candidates, ascending by key, consumed from `next_create`
    /// (kept out of the heap: most are void by the time they come up).
    creates: Vec<Entry>,
    next_create: usize,
    plane_count: usize,
    steps: usize,
}

impl<'a> State<'a> {
    fn new(points: &'a [Vector3<f64>], width: usize, height: usize, params: &'a PpeParams) -> Self {
        let valid: Vec<bool> = points
            .iter()
            .map(|p| p.iter().all(|x| x.is_finite()) && p.norm_squared() > 0.0)
            .collect();
        let n = points.len();
        let mut right = vec![false; n];
        let mut down = vec![false; n];
        for k in 0..n {
            let col = k % width;
            if col + 1 < width && valid[k] && valid[k + 1] {
                right[k] = (points[k] - points[k + 1]).norm() <= params.l_max_m;
            }
            if k + width < n && valid[k] && valid[k + width] {
                down[k] = (points[k] - points[k + width]).norm() <= params.l_max_m;
            }
        }
        let plane_count = valid.iter().filter(|&&v| v).count();
        let point_stats = points
            .iter()
            .zip(&valid)
            .map(|(p, &ok)| {
                if ok {
                    PlaneStats::of_point(p)
                } else {
                    PlaneStats::default()
                }
            })
            .collect();
        let mut s = Self {
            points,
            width,
            height,
            params,
            valid,
            point_stats,
            right,
            down,
            label: vec![NONE; n],
            pending: vec![NONE; n],
            clusters: Vec::new(),
            heap: BinaryHeap::new(),
            creates: Vec::new(),
            next_create: 0,
            plane_count,
            steps: 0,
        };
        let chunk = n
            .div_ceil(rayon::current_num_threads().max(1) * 8)
            .max(1024);
        let mut entries: Vec<Entry> = (0..n)
            .into_par_iter()
            .with_min_len(chunk)
            .filter_map(|k| {
                s.best_create(k).map(|(key, mask)| Entry {
                    key,
                    action: Action::Create {
                        point: k as u32,
                        mask,
                    },
                })
            })
            .collect();
        entries.par_sort_unstable_by(|a, b| a.key.total_cmp(&b.key));
        s.creates = entries;
        s
    }

    fn cell(&self, k: usize, d: (i8, i8)) -> Option<usize> {
        let row = (k / self.width) as isize + d.0 as isize;
        let col = (k % self.width) as isize + d.1 as isize;
        (row >= 0 && col >= 0 && (row as usize) < self.height && (col as usize) < self.width)
            .then(|| row as usize * self.width + col as usize)
    }

    /// Whether 4-adjacent cells `a`, `b` may be joined.
    fn edge(&self, a: usize, b: usize) -> bool {
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        if hi == lo + 1 && hi % self.width != 0 {
            self.right[lo]
        } else if hi == lo + self.width {
            self.down[lo]
        } else {
            false
        }
    }

    /// The cells of tetromino `mask` around `k` if all are atomic, valid and connected.
    fn tetromino(&self, k: usize, mask: usize) -> Option<[usize; 4]> {
        let offsets = TETROMINOES.get(mask)?;
        let mut cells = [k; 4];
        for (slot, d) in cells.iter_mut().skip(1).zip(offsets) {
            *slot = self.cell(k, *d)?;
        }
        if cells
            .iter()
            .any(|&c| !self.valid[c] || self.label[c] != NONE)
        {
            return None;
        }
        for i in 0..4 {
            for j in i + 1..4 {
                let (a, b) = (cells[i], cells[j]);
                let adjacent = a.abs_diff(b) == self.width
                    || (a.abs_diff(b) == 1 && a / self.width == b / self.width);
                if adjacent && !self.edge(a, b) {
                    return None;
                }
            }
        }
        Some(cells)
    }

    fn tetromino_stats(&self, cells: &[usize; 4]) -> PlaneStats {
        let mut s = PlaneStats::default();
        for &c in cells {
            s.add(&self.point_stats[c]);
        }
        s
    }

    fn best_create(&self, k: usize) -> Option<(f64, u8)> {
        if !self.valid[k] || self.label[k] != NONE {
            return None;
        }
        let mut best: Option<(f64, u8)> = None;
        for mask in 0..TETROMINOES.len() {
            if let Some(cells) = self.tetromino(k, mask) {
                let e = self.tetromino_stats(&cells).error();
                if e.is_finite() && best.is_none_or(|(b, _)| e < b) {
                    best = Some((e, mask as u8));
                }
            }
        }
        best
    }

    fn root(&self, mut c: u32) -> u32 {
        while let Some(cl) = self.clusters.get(c as usize) {
            if cl.parent == c {
                break;
            }
            c = cl.parent;
        }
        c
    }

    fn ext_increment(&self, plane: u32, point: usize) -> f64 {
        let cl = &self.clusters[plane as usize];
        let e = cl
            .stats
            .union(&PlaneStats::of_point(&self.points[point]))
            .error();
        (e - cl.error).max(0.0)
    }

    fn mrg_increment(&self, a: u32, b: u32) -> f64 {
        let (ca, cb) = (&self.clusters[a as usize], &self.clusters[b as usize]);
        let e = ca.stats.union(&cb.stats).error();
        (e - ca.error - cb.error).max(0.0)
    }

    /// Queues the extensions and mergers made possible by ray `k` joining `plane`.
    fn push_neighbours(&mut self, plane: u32, k: usize) {
        let neighbours = [(-1i8, 0i8), (1, 0), (0, -1), (0, 1)];
        for d in neighbours {
            let Some(o) = self.cell(k, d) else { continue };
            if !self.edge(k, o) {
                continue;
            }
            let lo = self.label[o];
            if lo == NONE {
                if self.pending[o] != NONE && self.root(self.pending[o]) == plane {
                    continue; // already queued; re-evaluated when popped
                }
                let key = self.ext_increment(plane, o);
                if key.is_finite() {
                    self.pending[o] = plane;
                    let action = Action::Extend {
                        plane,
                        point: o as u32,
                    };
                    self.heap.push(Entry { key, action });
                }
            } else if lo != plane {
                let queued = self.clusters[plane as usize]
                    .queued
                    .iter()
                    .find(|q| q.0 == lo)
                    .map(|q| q.1);
                let key = self.mrg_increment(plane, lo);
                if key.is_finite() && queued.is_none_or(|q| key < q) {
                    self.queue_merge(plane, lo, key);
                }
            }
        }
    }

    /// Queues the merge of planes `a` and `b` with `key` and records it on both.
    fn queue_merge(&mut self, a: u32, b: u32, key: f64) {
        for (x, y) in [(a, b), (b, a)] {
            let list = &mut self.clusters[x as usize].queued;
            match list.iter_mut().find(|q| q.0 == y) {
                Some(q) => q.1 = q.1.min(key),
                None => list.push((y, key)),
            }
        }
        self.heap.push(Entry {
            key,
            action: Action::Merge { a, b },
        });
    }

    /// Forgets the queued merge of `a` and `b` (popped from the heap).
    fn unqueue_merge(&mut self, a: u32, b: u32) {
        for (x, y) in [(a, b), (b, a)] {
            if let Some(cl) = self.clusters.get_mut(x as usize) {
                cl.queued.retain(|q| q.0 != y);
            }
        }
    }

    /// The least key queued in the heap or the sorted creates.
    fn peek_key(&self) -> Option<f64> {
        let h = self.heap.peek().map(|e| e.key);
        let c = self.creates.get(self.next_create).map(|e| e.key);
        match (h, c) {
            (Some(h), Some(c)) => Some(h.min(c)),
            (h, c) => h.or(c),
        }
    }

    /// Pops the least entry of the heap and the sorted creates.
    fn pop(&mut self) -> Option<Entry> {
        let c = self.creates.get(self.next_create).copied();
        match (self.heap.peek(), c) {
            (Some(h), Some(c)) if c.key < h.key => {
                self.next_create += 1;
                Some(c)
            }
            (None, Some(c)) => {
                self.next_create += 1;
                Some(c)
            }
            _ => self.heap.pop(),
        }
    }

    fn stop(&self, key: f64) -> bool {
        key > self.params.max_increment_m2 || self.plane_limit_reached()
    }

    fn plane_limit_reached(&self) -> bool {
        self.params
            .max_planes
            .is_some_and(|n| self.plane_count <= n)
    }

    /// Runs the clustering; when the least increment exceeds `e`, re-evaluates every
    /// queued candidate once and resumes if any is now admissible; candidates still above
    /// `e` are dropped.
    fn run(&mut self) {
        loop {
            self.run_until_stop();
            if self.plane_limit_reached() {
                return;
            }
            let mut old = std::mem::take(&mut self.heap).into_vec();
            old.extend(self.creates.drain(self.next_create..));
            self.next_create = 0;
            let mut fresh = Vec::new();
            for entry in old {
                if let Some(e) = self.reevaluate(entry)
                    && e.key <= self.params.max_increment_m2
                {
                    fresh.push(e);
                }
            }
            if fresh.is_empty() {
                return;
            }
            for cl in &mut self.clusters {
                cl.queued.clear();
            }
            for e in &fresh {
                if let Action::Merge { a, b } = e.action {
                    for (x, y) in [(a, b), (b, a)] {
                        self.clusters[x as usize].queued.push((y, e.key));
                    }
                }
            }
            self.heap = BinaryHeap::from(fresh);
        }
    }

    /// The entry re-keyed for the current planes (`None` when it is void).
    fn reevaluate(&self, entry: Entry) -> Option<Entry> {
        match entry.action {
            Action::Create { point, .. } => {
                let (key, mask) = self.best_create(point as usize)?;
                Some(Entry {
                    key,
                    action: Action::Create { point, mask },
                })
            }
            Action::Extend { plane, point } => {
                if self.label[point as usize] != NONE {
                    return None;
                }
                let r = self.root(plane);
                let key = self.ext_increment(r, point as usize);
                key.is_finite().then_some(Entry {
                    key,
                    action: Action::Extend { plane: r, point },
                })
            }
            Action::Merge { a, b } => {
                let (ra, rb) = (self.root(a), self.root(b));
                if ra == rb {
                    return None;
                }
                let key = self.mrg_increment(ra, rb);
                key.is_finite().then_some(Entry {
                    key,
                    action: Action::Merge { a: ra, b: rb },
                })
            }
        }
    }

    /// Lazy greedy loop: a popped candidate is re-evaluated for the current planes; it is
    /// executed when its current increment is still no larger than the next queued key,
    /// otherwise queued again with the new key.
    fn run_until_stop(&mut self) {
        while let Some(entry) = self.pop() {
            if self.plane_limit_reached() {
                break;
            }
            match entry.action {
                Action::Extend { point, .. } => self.pending[point as usize] = NONE,
                Action::Merge { a, b } => self.unqueue_merge(a, b),
                Action::Create { .. } => {}
            }
            let Some(current) = self.reevaluate(entry) else {
                continue;
            };
            if let Action::Extend { plane, point } = current.action {
                self.pending[point as usize] = plane;
            }
            let still_least =
                current.key <= entry.key || self.peek_key().is_none_or(|next| current.key <= next);
            let stop = still_least && self.stop(current.key);
            if !still_least || stop {
                match current.action {
                    Action::Merge { a, b } => self.queue_merge(a, b, current.key),
                    _ => self.heap.push(current),
                }
                if stop {
                    break;
                }
                continue;
            }
            match current.action {
                Action::Create { point, mask } => {
                    if let Some(cells) = self.tetromino(point as usize, mask as usize) {
                        self.create(cells);
                    }
                }
                Action::Extend { plane, point } => self.extend(plane, point as usize),
                Action::Merge { a, b } => self.merge(a, b),
            }
        }
    }

    fn create(&mut self, cells: [usize; 4]) {
        let id = self.clusters.len() as u32;
        let stats = self.tetromino_stats(&cells);
        self.clusters.push(Cluster {
            stats,
            error: stats.error(),
            members: cells.iter().map(|&c| c as u32).collect(),
            parent: id,
            queued: Vec::new(),
        });
        for &c in &cells {
            self.label[c] = id;
        }
        self.plane_count -= 3;
        self.steps += 1;
        for &c in &cells {
            self.push_neighbours(id, c);
        }
    }

    fn extend(&mut self, plane: u32, k: usize) {
        let add = self.point_stats[k];
        let cl = &mut self.clusters[plane as usize];
        cl.stats.add(&add);
        cl.error = cl.stats.error();
        cl.members.push(k as u32);
        self.label[k] = plane;
        self.plane_count -= 1;
        self.steps += 1;
        self.push_neighbours(plane, k);
    }

    fn merge(&mut self, a: u32, b: u32) {
        let (big, small) =
            if self.clusters[a as usize].members.len() >= self.clusters[b as usize].members.len() {
                (a, b)
            } else {
                (b, a)
            };
        let moved = std::mem::take(&mut self.clusters[small as usize].members);
        let small_stats = self.clusters[small as usize].stats;
        for &m in &moved {
            self.label[m as usize] = big;
        }
        self.clusters[small as usize].parent = big;
        let cl = &mut self.clusters[big as usize];
        cl.stats.add(&small_stats);
        cl.error = cl.stats.error();
        cl.members.extend(moved);
        self.plane_count -= 1;
        self.steps += 1;
    }

    /// The post-processing rounds of [`PpeParams::refine_rounds`].
    fn polish(&mut self) {
        for _ in 0..self.params.refine_rounds {
            let moved = self.refine_boundary();
            let mut merged = self.merge_adjacent();
            merged += self.merge_occluded();
            if moved == 0 && merged == 0 {
                break;
            }
        }
    }

    /// Absolute radial residual of ray `k` on plane `w` (`∞` when the ray misses it).
    fn residual(&self, w: &Vector3<f64>, k: usize) -> f64 {
        let p = &self.points[k];
        let r = p.norm();
        let d = w.dot(p) / r;
        if d > 0.0 {
            (r - 1.0 / d).abs()
        } else {
            f64::INFINITY
        }
    }

    /// One sweep of boundary refinement; returns the number of rays moved.
    fn refine_boundary(&mut self) -> usize {
        let min_points = self.params.min_points.max(4);
        let big: Vec<Option<Vector3<f64>>> = self
            .clusters
            .iter()
            .enumerate()
            .map(|(id, cl)| {
                (cl.parent as usize == id && cl.members.len() >= min_points)
                    .then(|| cl.stats.solve().map(|(w, _)| w))
                    .flatten()
            })
            .collect();
        let plane_of = |l: u32| big.get(l as usize).copied().flatten();
        let limit = self.params.max_increment_m2.sqrt();
        let neighbours = [(-1i8, 0i8), (1, 0), (0, -1), (0, 1)];
        let mut moves = Vec::new();
        for k in 0..self.points.len() {
            let own = self.label[k];
            if own == NONE {
                continue;
            }
            let mut best: Option<(f64, u32)> = plane_of(own).map(|w| (self.residual(&w, k), own));
            let own_big = best.is_some();
            let mut boundary = false;
            for d in neighbours {
                let Some(o) = self.cell(k, d) else { continue };
                let lo = self.label[o];
                if lo == NONE || lo == own || !self.edge(k, o) {
                    continue;
                }
                boundary = true;
                if let Some(w) = plane_of(lo) {
                    let e = self.residual(&w, k);
                    if best.is_none_or(|(b, _)| e < b) {
                        best = Some((e, lo));
                    }
                }
            }
            if !boundary {
                continue;
            }
            if let Some((e, to)) = best
                && to != own
                && (own_big || e <= limit)
            {
                moves.push((k, to));
            }
        }
        for &(k, to) in &moves {
            let from = self.label[k];
            let ps = self.point_stats[k];
            self.clusters[from as usize].stats.remove(&ps);
            self.clusters[to as usize].stats.add(&ps);
            self.label[k] = to;
        }
        if !moves.is_empty() {
            for cl in &mut self.clusters {
                cl.members.clear();
            }
            for (k, &l) in self.label.iter().enumerate() {
                if l != NONE {
                    self.clusters[l as usize].members.push(k as u32);
                }
            }
            for cl in &mut self.clusters {
                cl.error = if cl.members.len() >= 4 {
                    cl.stats.error()
                } else {
                    0.0
                };
            }
        }
        moves.len()
    }

    /// Merges 4-adjacent planes, least increment first, while the increment is at most
    /// `e`; returns the number of merges.
    fn merge_adjacent(&mut self) -> usize {
        let mut pairs = Vec::new();
        for k in 0..self.points.len() {
            let a = self.label[k];
            if a == NONE {
                continue;
            }
            for o in [k + 1, k + self.width] {
                if o < self.points.len() && self.edge(k, o) {
                    let b = self.label[o];
                    if b != NONE && b != a {
                        pairs.push((a.min(b), a.max(b)));
                    }
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        pairs.retain(|&(a, b)| {
            self.clusters[a as usize].members.len() >= 4
                && self.clusters[b as usize].members.len() >= 4
        });
        self.merge_pairs(pairs)
    }

    /// Merges planes that are pieces of one surface seen on both sides of an occluder:
    /// along a row or column, plane `a` ends, only rays **in front of** the joint plane of
    /// `a` and `b` follow (by more than three RMS residuals of the joint fit), then plane `b`
    /// begins; the merge is executed when its increment is at most `e`. Returns the number
    /// of merges.
    fn merge_occluded(&mut self) -> usize {
        let min_points = self.params.min_points.max(4);
        let is_big = |s: &Self, l: u32| {
            l != NONE
                && s.clusters
                    .get(l as usize)
                    .is_some_and(|c| c.members.len() >= min_points)
        };
        // Candidate gaps: (a, b, first gap ray, last gap ray, stride).
        let mut gaps: Vec<(u32, u32, usize, usize, usize)> = Vec::new();
        let lines = (0..self.height)
            .map(|row| (row * self.width, 1, self.width))
            .chain((0..self.width).map(|col| (col, self.width, self.height)));
        for (start, stride, len) in lines {
            // The last ray of the most recent distinct planes along the line.
            let mut recent: [(u32, usize); 4] = [(NONE, 0); 4];
            for i in 0..len {
                let k = start + i * stride;
                let l = self.label[k];
                if !is_big(self, l) {
                    continue;
                }
                if recent[0].0 != l {
                    for &(a, ka) in &recent {
                        if a != NONE && a != l && k - ka > stride {
                            gaps.push((a.min(l), a.max(l), ka + stride, k - stride, stride));
                        }
                    }
                    if let Some(pos) = recent.iter().position(|r| r.0 == l) {
                        recent[..=pos].rotate_right(1);
                    } else {
                        recent.rotate_right(1);
                    }
                }
                recent[0] = (l, k);
            }
        }
        // Joint plane and occlusion margin of each pair.
        type Joint = Option<(Vector3<f64>, f64)>;
        let mut cache: std::collections::HashMap<(u32, u32), Joint> =
            std::collections::HashMap::new();
        let mut pairs = Vec::new();
        for (a, b, first, last, stride) in gaps {
            let joint = *cache.entry((a, b)).or_insert_with(|| {
                let st = self.clusters[a as usize]
                    .stats
                    .union(&self.clusters[b as usize].stats);
                st.solve()
                    .map(|(w, sse)| (w, 3.0 * (sse / st.n.max(1) as f64).sqrt()))
            });
            let Some((w, margin)) = joint else { continue };
            let occluded = (first..=last).step_by(stride).all(|k| {
                let p = &self.points[k];
                if !self.valid[k] {
                    return false;
                }
                let r = p.norm();
                let d = w.dot(p) / r;
                d > 0.0 && r < 1.0 / d - margin
            });
            if occluded {
                pairs.push((a, b));
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        self.merge_pairs(pairs)
    }

    /// Merges the given plane pairs (and what they become), least increment first, while the
    /// increment stays at most `e`; a pair whose increment grew since it was queued goes back
    /// into the queue. Returns the number of merges.
    fn merge_pairs(&mut self, pairs: Vec<(u32, u32)>) -> usize {
        let e_max = self.params.max_increment_m2;
        let mut heap: BinaryHeap<Entry> = pairs
            .into_iter()
            .map(|(a, b)| Entry {
                key: self.mrg_increment(a, b),
                action: Action::Merge { a, b },
            })
            .filter(|e| e.key <= e_max)
            .collect();
        let mut merged = 0;
        while let Some(entry) = heap.pop() {
            let Action::Merge { a, b } = entry.action else {
                continue;
            };
            let (ra, rb) = (self.root(a), self.root(b));
            if ra == rb {
                continue;
            }
            let key = self.mrg_increment(ra, rb);
            if key > e_max {
                continue;
            }
            if key > entry.key && heap.peek().is_some_and(|n| key > n.key) {
                heap.push(Entry {
                    key,
                    action: Action::Merge { a: ra, b: rb },
                });
                continue;
            }
            self.merge(ra, rb);
            merged += 1;
        }
        merged
    }

    fn finish(self) -> Segmentation {
        let min_points = self.params.min_points.max(4);
        let alive: Vec<&Cluster> = self
            .clusters
            .iter()
            .enumerate()
            .filter(|(id, cl)| cl.parent as usize == *id && cl.members.len() >= min_points)
            .map(|(_, cl)| cl)
            .collect();
        let points = self.points;
        let mut planes: Vec<Plane> = alive
            .into_par_iter()
            .filter_map(|cl| {
                let (w0, _) = cl.stats.solve()?;
                let buf: Vec<Vector3<f64>> =
                    cl.members.iter().map(|&m| points[m as usize]).collect();
                let fit = refine(w0, &buf, 1e-6, 20)?;
                let mut index: Vec<usize> = cl.members.iter().map(|&m| m as usize).collect();
                index.sort_unstable();
                Some(Plane { index, fit })
            })
            .collect();
        planes.sort_by(|a, b| {
            b.index
                .len()
                .cmp(&a.index.len())
                .then(a.index.cmp(&b.index))
        });
        let mut labels = vec![None; self.points.len()];
        for (id, p) in planes.iter().enumerate() {
            for &i in &p.index {
                labels[i] = Some(id as u32);
            }
        }
        Segmentation {
            width: self.width,
            height: self.height,
            labels,
            planes,
            steps: self.steps,
        }
    }
}
