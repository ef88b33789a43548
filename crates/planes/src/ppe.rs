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
//! every queued candidate before stopping (stale keys are not lower bounds). Equal
//! increments are frequent (the radial error of four rays often vanishes to machine
//! precision and clamps at 0), so their order is fixed: merges before extensions before
//! creations; creations by ray index; extensions and merges by their plane and ray ids
//! under a fixed bijection that scatters neighbouring ids (in plain index order, their
//! ties favoured one side of the image and raised the plane RMSE on real KITTI frames).
//! The order of the pops is then a
//! function of the queued set, independent of the queue's layout (`ppe/queue.rs`).
//!
//! Merge candidates are queued once per pair of planes (again only with a smaller key),
//! which keeps the queue near the number of boundary rays. A creation candidate stays valid
//! while the cells of its tetromino are atomic: rays only ever join planes, so the set of
//! tetrominoes of a ray only shrinks and its best one stays the best.
//!
//! Optional post-processing ([`PpeParams::refine_rounds`], not in the thesis): each round
//! (1) moves every ray on a plane boundary to the adjacent plane with the least radial
//! residual, (2) merges 4-adjacent planes while the increment stays within `e`, and (3)
//! merges the pieces of one surface split by an occluder — plane `a` ends along a row or
//! column, only rays in front of the joint plane of `a` and `b` follow, then `b` begins —
//! while the increment stays within `e`. Each round costs O(K) plus the merges.
//!
//! Cost: seeding evaluates 17 tetrominoes per ray (parallel over rows, rayon), each a
//! bit test on the ray's 3 × 3 neighbourhood and, when valid, one 3 × 3 solve; every action
//! costs O(1) solves plus O(log Q) queue operations on 16-byte entries (bucketed by the
//! key's exponent, so a pop touches a small heap); a merge relabels the smaller plane and
//! splices its member list (O(K log K) relabelling in total). Final exact refits are
//! O(K · iterations), parallel over planes. Each increment costs one 3 × 3 solve on the
//! additive statistics of [`crate::PlaneStats`] (computed from the endpoints when needed);
//! the planes of the result are refitted on the exact radial residuals
//! ([`crate::fit::refine`]).
//!
//! Storage is contiguous: per ray its link bits, neighbourhood links, label, queued
//! extension, the next member of its plane (planes are intrusive lists) and one bit
//! "atomic"; per plane its statistics, error, list ends and parent (union by size).

use nalgebra::Vector3;
use rayon::prelude::*;
use raypath_geometry::PointCloud;

use crate::error::PlaneError;
use crate::fit::PlaneFit;
use crate::params::PpeParams;
use crate::stats::Moments;
use crate::tetromino::TETROMINOES;

mod grid;
mod polish;
mod queue;

const NONE: u32 = u32::MAX;
/// Rays and planes are packed into 31 bits in the queue.
const MAX_RAYS: usize = 1 << 31;
const ID_MASK: u64 = (1 << 31) - 1;

/// One bit per ray, set where `bits` is true.
fn bitset(bits: &[bool]) -> Vec<u64> {
    let mut out = vec![0u64; bits.len().div_ceil(64)];
    for (k, _) in bits.iter().enumerate().filter(|(_, b)| **b) {
        out[k / 64] |= 1 << (k % 64);
    }
    out
}

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
    /// The segmentation of `rays` rays on a `width × height` grid into `planes` after
    /// `steps` actions: the planes sorted largest first (ties by their ray indices), every
    /// ray labelled with the plane that holds it. Each extractor ([`extract`],
    /// [`crate::msac`], [`crate::peac`]) ends here.
    pub(crate) fn from_planes(
        width: usize,
        height: usize,
        rays: usize,
        mut planes: Vec<Plane>,
        steps: usize,
    ) -> Self {
        planes.sort_by(|a, b| {
            b.index
                .len()
                .cmp(&a.index.len())
                .then(a.index.cmp(&b.index))
        });
        let mut labels = vec![None; rays];
        for (id, p) in planes.iter().enumerate() {
            for &i in &p.index {
                labels[i] = Some(id as u32);
            }
        }
        Self {
            width,
            height,
            labels,
            planes,
            steps,
        }
    }

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
    if points.len() >= MAX_RAYS {
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

/// A bijection of 31-bit ids that scatters neighbouring ids ([`unscramble`] inverts it).
fn scramble(x: u32) -> u32 {
    let mut x = u64::from(x);
    x = (x * 0x5bd1_e995) & ID_MASK;
    x ^= x >> 16;
    x = (x * 0x2c1b_3c6d) & ID_MASK;
    x ^= x >> 15;
    x as u32
}

/// The inverse of [`scramble`].
fn unscramble(x: u32) -> u32 {
    let mut x = u64::from(x);
    x ^= (x >> 15) ^ (x >> 30);
    x = (x * inverse(0x2c1b_3c6d)) & ID_MASK;
    x ^= x >> 16;
    x = (x * inverse(0x5bd1_e995)) & ID_MASK;
    x as u32
}

/// The inverse of odd `a` modulo 2^31 (Newton's iteration).
const fn inverse(a: u64) -> u64 {
    let mut x = a;
    let mut i = 0;
    while i < 5 {
        x = x.wrapping_mul(2u64.wrapping_sub(a.wrapping_mul(x)));
        i += 1;
    }
    x & ID_MASK
}

impl Action {
    /// Two bits of kind and two 31-bit ids, ordered as ties are broken (module docs).
    fn pack(self) -> u64 {
        let (kind, hi, lo) = match self {
            Action::Create { point, mask } => (2, point, u32::from(mask)),
            Action::Extend { plane, point } => (1, scramble(plane), scramble(point)),
            Action::Merge { a, b } => (0, scramble(a), scramble(b)),
        };
        (kind << 62) | (u64::from(hi) << 31) | u64::from(lo)
    }

    fn unpack(bits: u64) -> Self {
        let hi = ((bits >> 31) & ID_MASK) as u32;
        let lo = (bits & ID_MASK) as u32;
        match bits >> 62 {
            2 => Action::Create {
                point: hi,
                mask: lo as u8,
            },
            1 => Action::Extend {
                plane: unscramble(hi),
                point: unscramble(lo),
            },
            _ => Action::Merge {
                a: unscramble(hi),
                b: unscramble(lo),
            },
        }
    }
}

/// A candidate: its increment and its packed [`Action`]. Candidates are ordered by
/// increment, ties by the packed action (see the module docs).
#[derive(Debug, Clone, Copy)]
struct Entry {
    key: f64,
    action: u64,
}

impl Entry {
    fn new(key: f64, action: Action) -> Self {
        Self {
            key,
            action: action.pack(),
        }
    }

    fn action(&self) -> Action {
        Action::unpack(self.action)
    }

    /// The queue's 16-byte form, ordered as the candidates.
    fn item(&self) -> queue::Item {
        queue::item(self.key, self.action)
    }

    fn from_item(item: queue::Item) -> Self {
        let (key, action) = queue::split(item);
        Self { key, action }
    }
}

/// A plane: its additive statistics, their error (Eq. 11.2) and its member list.
struct Cluster {
    stats: Moments,
    error: f64,
    /// First and last member ray (`NONE` when empty) and the number of members; the
    /// members are chained by `State::next`.
    head: u32,
    tail: u32,
    len: u32,
}

struct State<'a> {
    points: &'a [Vector3<f64>],
    width: usize,
    height: usize,
    params: &'a PpeParams,
    valid: Vec<bool>,
    /// Link bits of every ray ([`grid::UP`] … [`grid::RIGHT`]): neighbours it may join.
    links: Vec<u8>,
    /// The links inside the 3 × 3 neighbourhood of every ray ([`grid::edges`]).
    edges: Vec<u16>,
    label: Vec<u32>,
    /// One bit per ray: a valid ray that is still atomic (cache-resident, unlike `label`).
    free: Vec<u64>,
    /// The next member of the ray's plane (`NONE`: last).
    next: Vec<u32>,
    /// Plane of the queued extension of each atomic ray (`NONE`: none queued).
    pending: Vec<u32>,
    clusters: Vec<Cluster>,
    /// The plane each plane was merged into (itself while it is a root).
    parent: Vec<u32>,
    queued: queue::Queued,
    heap: queue::Queue,
    /// The initial creation candidates in ascending order, consumed from `next_create`
    /// (kept out of the heap: most are void by the time they come up).
    creates: Vec<queue::Item>,
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
        let links = grid::links(&valid, points, width, params.l_max_m);
        let plane_count = valid.iter().filter(|&&v| v).count();
        let free = bitset(&valid);
        let size = (width, height);
        let edges = (0..n)
            .into_par_iter()
            .map(|k| grid::edges(k, size, &links))
            .collect();
        let mut s = Self {
            points,
            width,
            height,
            params,
            valid,
            links,
            edges,
            label: vec![NONE; n],
            free,
            next: vec![NONE; n],
            pending: vec![NONE; n],
            clusters: Vec::new(),
            parent: Vec::new(),
            queued: queue::Queued::default(),
            heap: queue::Queue::default(),
            creates: Vec::new(),
            next_create: 0,
            plane_count,
            steps: 0,
        };
        s.creates = s.seed();
        s
    }

    /// The best tetromino of every ray, ascending by `e_crt` (Eq. 11.4); rows in parallel.
    fn seed(&self) -> Vec<queue::Item> {
        let mut entries: Vec<queue::Item> = (0..self.height)
            .into_par_iter()
            .flat_map_iter(|row| {
                (row * self.width..(row + 1) * self.width).filter_map(move |k| {
                    let (key, mask) = self.best_create(k)?;
                    let point = k as u32;
                    Some(Entry::new(key, Action::Create { point, mask }).item())
                })
            })
            .collect();
        entries.par_sort_unstable();
        entries
    }

    /// The cells of tetromino `mask` around `k` if all are atomic, valid and connected.
    fn tetromino(&self, k: usize, mask: usize) -> Option<[usize; 4]> {
        let &(need_cells, need_edges) = grid::SHAPES.get(mask)?;
        let (cells, edges) = (self.cells(k), self.edges[k]);
        if cells & need_cells != need_cells || edges & need_edges != need_edges {
            return None;
        }
        Some(self.tetromino_cells(k, mask))
    }

    /// The cells of tetromino `mask` around `k`, `k` first (all must exist).
    fn tetromino_cells(&self, k: usize, mask: usize) -> [usize; 4] {
        let o = TETROMINOES[mask];
        let w = self.width;
        [
            k,
            grid::offset(k, w, o[0]),
            grid::offset(k, w, o[1]),
            grid::offset(k, w, o[2]),
        ]
    }

    /// The atomic valid cells of the 3 × 3 neighbourhood of `k` ([`grid::cells`]).
    fn cells(&self, k: usize) -> u16 {
        grid::cells(k, (self.width, self.height), |c| self.is_free(c))
    }

    /// The statistics of ray `k` (computed when needed: 24 bytes of endpoint are cheaper to
    /// load than 88 bytes of statistics).
    fn ray_stats(&self, k: usize) -> Moments {
        Moments::of_point(&self.points[k])
    }

    fn tetromino_stats(&self, cells: &[usize; 4]) -> Moments {
        let mut s = Moments::default();
        for &c in cells {
            s.add(&self.ray_stats(c));
        }
        s
    }

    /// The tetromino of atomic ray `k` with the least error `e_crt` (Eq. 11.4).
    fn best_create(&self, k: usize) -> Option<(f64, u8)> {
        if !self.is_free(k) {
            return None;
        }
        self.best_create_in(k, self.cells(k))
    }

    /// [`State::best_create`] for the atomic valid cells `cells` around `k`.
    fn best_create_in(&self, k: usize, cells: u16) -> Option<(f64, u8)> {
        let edges = self.edges[k];
        // Statistics of the 3 × 3 neighbourhood, row-major.
        let mut around = [Moments::default(); 9];
        for (i, m) in around.iter_mut().enumerate() {
            if cells & (1 << i) != 0 {
                let d = (i as i8 / 3 - 1, i as i8 % 3 - 1);
                *m = self.ray_stats(grid::offset(k, self.width, d));
            }
        }
        let mut best: Option<(f64, u8)> = None;
        for (mask, &(need_cells, need_edges)) in grid::SHAPES.iter().enumerate() {
            if cells & need_cells != need_cells || edges & need_edges != need_edges {
                continue;
            }
            // e_crt (Eq. 11.4), summed in the order k, then the offsets of the tetromino.
            let mut stats = Moments::default();
            stats.add(&around[4]);
            for d in TETROMINOES[mask] {
                stats.add(&around[((d.0 + 1) * 3 + d.1 + 1) as usize]);
            }
            let e = stats.error();
            if e.is_finite() && best.is_none_or(|(b, _)| e < b) {
                best = Some((e, mask as u8));
            }
        }
        best
    }

    /// Whether ray `k` is valid and still atomic.
    fn is_free(&self, k: usize) -> bool {
        self.free[k / 64] & (1 << (k % 64)) != 0
    }

    /// Marks ray `k` as joined to a plane.
    fn take(&mut self, k: usize) {
        self.free[k / 64] &= !(1 << (k % 64));
    }

    fn root(&self, mut c: u32) -> u32 {
        while let Some(&p) = self.parent.get(c as usize) {
            if p == c {
                break;
            }
            c = p;
        }
        c
    }

    /// `e_ext` of adding ray `point` to `plane` (Eq. 11.3).
    fn ext_increment(&self, plane: u32, point: usize) -> f64 {
        let cl = &self.clusters[plane as usize];
        let e = cl.stats.union(&self.ray_stats(point)).error();
        (e - cl.error).max(0.0)
    }

    /// `e_mrg` of joining planes `a` and `b` (Eq. 11.3).
    fn mrg_increment(&self, a: u32, b: u32) -> f64 {
        let (ca, cb) = (&self.clusters[a as usize], &self.clusters[b as usize]);
        let e = ca.stats.union(&cb.stats).error();
        (e - ca.error - cb.error).max(0.0)
    }

    /// Queues the extensions and mergers made possible by ray `k` joining `plane`.
    fn push_neighbours(&mut self, plane: u32, k: usize) {
        let links = self.links[k];
        for (bit, o) in grid::neighbours(k, self.width) {
            if links & bit == 0 {
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
                    let point = o as u32;
                    let entry = Entry::new(key, Action::Extend { plane, point });
                    self.heap.push(entry.item());
                }
            } else if lo != plane {
                let key = self.mrg_increment(plane, lo);
                if key.is_finite() && self.queued.lower(plane, lo, key) {
                    let entry = Entry::new(key, Action::Merge { a: plane, b: lo });
                    self.heap.push(entry.item());
                }
            }
        }
    }

    /// Settles the record of popped merge `popped` ([`queue::Queued`]): forgets it, and
    /// records `again` (re-keyed, to be queued again) if given.
    fn unqueue_merge(&mut self, popped: (u32, u32), again: Option<(u32, u32, f64)>) {
        match again {
            Some((a, b, key)) if queue::Queued::same(popped, (a, b)) => {
                self.queued.set(a, b, key);
            }
            Some((a, b, key)) => {
                self.queued.remove(popped.0, popped.1);
                self.queued.lower(a, b, key);
            }
            None => self.queued.remove(popped.0, popped.1),
        }
    }

    /// The least key queued in the heap or the sorted creates.
    fn peek_key(&self) -> Option<f64> {
        let h = self.heap.peek();
        let c = self.creates.get(self.next_create).copied();
        let least = match (h, c) {
            (Some(h), Some(c)) => h.min(c),
            (h, c) => h.or(c)?,
        };
        Some(Entry::from_item(least).key)
    }

    /// Pops the least entry of the heap and the sorted creates.
    fn pop(&mut self) -> Option<Entry> {
        let c = self.creates.get(self.next_create).copied();
        let item = match (self.heap.peek(), c) {
            (Some(h), Some(c)) if c < h => {
                self.next_create += 1;
                c
            }
            (None, Some(c)) => {
                self.next_create += 1;
                c
            }
            _ => self.heap.pop()?,
        };
        Some(Entry::from_item(item))
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
            let mut old = self.heap.take_all();
            old.extend(self.creates.drain(self.next_create..));
            self.next_create = 0;
            let mut fresh = Vec::new();
            for item in old {
                if let Some(e) = self.reevaluate(Entry::from_item(item))
                    && e.key <= self.params.max_increment_m2
                {
                    fresh.push(e);
                }
            }
            if fresh.is_empty() {
                return;
            }
            self.queued.clear();
            for e in &fresh {
                if let Action::Merge { a, b } = e.action() {
                    self.queued.lower(a, b, e.key);
                }
            }
            for e in fresh {
                self.heap.push(e.item());
            }
        }
    }

    /// The entry re-keyed for the current planes (`None` when it is void).
    fn reevaluate(&self, entry: Entry) -> Option<Entry> {
        let (key, action) = match entry.action() {
            Action::Create { point, mask } => {
                let k = point as usize;
                if !self.is_free(k) {
                    return None;
                }
                let cells = self.cells(k);
                let (need, _) = grid::SHAPES[mask as usize];
                if cells & need == need {
                    // The candidates only shrink as rays join planes: the best is still
                    // the best while its own cells are atomic.
                    return Some(entry);
                }
                let (key, mask) = self.best_create_in(k, cells)?;
                (key, Action::Create { point, mask })
            }
            Action::Extend { plane, point } => {
                if !self.is_free(point as usize) {
                    return None;
                }
                let plane = self.root(plane);
                let key = self.ext_increment(plane, point as usize);
                (key, Action::Extend { plane, point })
            }
            Action::Merge { a, b } => {
                let (a, b) = (self.root(a), self.root(b));
                if a == b {
                    return None;
                }
                (self.mrg_increment(a, b), Action::Merge { a, b })
            }
        };
        key.is_finite().then(|| Entry::new(key, action))
    }

    /// Lazy greedy loop (Algorithm 2): a popped candidate is re-evaluated for the current
    /// planes; it is executed when its current increment is still no larger than the next
    /// queued key, otherwise queued again with the new key.
    fn run_until_stop(&mut self) {
        while let Some(entry) = self.pop() {
            if self.plane_limit_reached() || !self.step(entry) {
                break;
            }
        }
    }

    /// Handles popped candidate `entry`; returns `false` when the clustering stops (the
    /// least increment exceeds `e`, Eq. 11.3, or the plane limit is reached).
    fn step(&mut self, entry: Entry) -> bool {
        let popped_merge = match entry.action() {
            Action::Extend { point, .. } => {
                self.pending[point as usize] = NONE;
                None
            }
            Action::Merge { a, b } => Some((a, b)),
            Action::Create { .. } => None,
        };
        let Some(current) = self.reevaluate(entry) else {
            if let Some(popped) = popped_merge {
                self.unqueue_merge(popped, None);
            }
            return true;
        };
        let action = current.action();
        if let Action::Extend { plane, point } = action {
            self.pending[point as usize] = plane;
        }
        let still_least =
            current.key <= entry.key || self.peek_key().is_none_or(|next| current.key <= next);
        let stop = still_least && self.stop(current.key);
        let requeue = !still_least || stop;
        if let Some(popped) = popped_merge {
            let again = match action {
                Action::Merge { a, b } if requeue => Some((a, b, current.key)),
                _ => None,
            };
            self.unqueue_merge(popped, again);
        }
        if requeue {
            self.heap.push(current.item());
        } else {
            self.execute(action);
        }
        !stop
    }

    fn execute(&mut self, action: Action) {
        match action {
            Action::Create { point, mask } => {
                if let Some(cells) = self.tetromino(point as usize, mask as usize) {
                    self.create(cells);
                }
            }
            Action::Extend { plane, point } => self.extend(plane, point as usize),
            Action::Merge { a, b } => self.merge(a, b),
        }
    }

    fn create(&mut self, cells: [usize; 4]) {
        let id = self.clusters.len() as u32;
        let stats = self.tetromino_stats(&cells);
        for pair in cells.windows(2) {
            self.next[pair[0]] = pair[1] as u32;
        }
        self.next[cells[3]] = NONE;
        self.clusters.push(Cluster {
            stats,
            error: stats.error(),
            head: cells[0] as u32,
            tail: cells[3] as u32,
            len: 4,
        });
        self.parent.push(id);
        for &c in &cells {
            self.label[c] = id;
            self.take(c);
        }
        self.plane_count -= 3;
        self.steps += 1;
        for &c in &cells {
            self.push_neighbours(id, c);
        }
    }

    /// Appends ray `k` to the member list of `plane`.
    fn append(&mut self, plane: u32, k: usize) {
        let cl = &mut self.clusters[plane as usize];
        if cl.len == 0 {
            cl.head = k as u32;
        } else {
            self.next[cl.tail as usize] = k as u32;
        }
        cl.tail = k as u32;
        cl.len += 1;
        self.next[k] = NONE;
    }

    fn extend(&mut self, plane: u32, k: usize) {
        let add = self.ray_stats(k);
        let cl = &mut self.clusters[plane as usize];
        cl.stats.add(&add);
        cl.error = cl.stats.error();
        self.append(plane, k);
        self.label[k] = plane;
        self.take(k);
        self.plane_count -= 1;
        self.steps += 1;
        self.push_neighbours(plane, k);
    }

    /// Merges planes `a` and `b`: the smaller one (by rays) is relabelled and its member
    /// list spliced onto the larger one's (union by size).
    fn merge(&mut self, a: u32, b: u32) {
        let (big, small) = if self.clusters[a as usize].len >= self.clusters[b as usize].len {
            (a, b)
        } else {
            (b, a)
        };
        let s = &self.clusters[small as usize];
        let (small_stats, head, tail, len) = (s.stats, s.head, s.tail, s.len);
        let mut m = head;
        for _ in 0..len {
            self.label[m as usize] = big;
            m = self.next[m as usize];
        }
        let s = &mut self.clusters[small as usize];
        (s.head, s.tail, s.len) = (NONE, NONE, 0);
        self.parent[small as usize] = big;
        if len > 0 {
            let cl = &self.clusters[big as usize];
            if cl.len == 0 {
                self.clusters[big as usize].head = head;
            } else {
                self.next[cl.tail as usize] = head;
            }
            self.clusters[big as usize].tail = tail;
        }
        let cl = &mut self.clusters[big as usize];
        cl.len += len;
        cl.stats.add(&small_stats);
        cl.error = cl.stats.error();
        self.plane_count -= 1;
        self.steps += 1;
    }

    /// The member rays of `plane` in list order.
    fn members(&self, plane: u32) -> impl Iterator<Item = usize> + '_ {
        let cl = &self.clusters[plane as usize];
        let mut m = cl.head;
        (0..cl.len).map(move |_| {
            let k = m as usize;
            m = self.next[k];
            k
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scramble_is_a_bijection_of_31_bit_ids() {
        let ids = (0..1u32 << 31)
            .step_by(99_991)
            .chain([1, 2, 499, 500, ID_MASK as u32]);
        for x in ids {
            assert!(u64::from(scramble(x)) <= ID_MASK);
            assert_eq!(unscramble(scramble(x)), x, "{x}");
        }
    }

    #[test]
    fn actions_survive_packing() {
        let big = ID_MASK as u32;
        for action in [
            Action::Create {
                point: big,
                mask: 16,
            },
            Action::Extend {
                plane: 7,
                point: big,
            },
            Action::Merge { a: big, b: 0 },
        ] {
            assert_eq!(
                format!("{:?}", Action::unpack(action.pack())),
                format!("{action:?}")
            );
        }
    }
}
