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
//! The candidates live in one lazy priority queue: an entry records the versions of the
//! planes it was computed for; a popped entry whose planes changed since is re-evaluated
//! and pushed again, so only the actions at the front of the queue are ever recomputed.
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
    /// implementation computes it (errata 8).
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
    if width == 0 || height == 0 || width.checked_mul(height) != Some(points.len()) {
        return Err(PlaneError::NotOrganized {
            width,
            height,
            len: points.len(),
        });
    }
    if points.len() >= NONE as usize {
        return Err(PlaneError::Parameter {
            name: "points",
            reason: "too many rays".into(),
        });
    }
    let mut state = State::new(points, width, height, params);
    state.run();
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
        version: u32,
    },
    Merge {
        a: u32,
        b: u32,
        va: u32,
        vb: u32,
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
    version: u32,
    parent: u32,
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
    clusters: Vec<Cluster>,
    heap: BinaryHeap<Entry>,
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
            clusters: Vec::new(),
            heap: BinaryHeap::new(),
            plane_count,
            steps: 0,
        };
        let chunk = n
            .div_ceil(rayon::current_num_threads().max(1) * 8)
            .max(1024);
        let entries: Vec<Entry> = (0..n)
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
        s.heap = BinaryHeap::from(entries);
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
                let key = self.ext_increment(plane, o);
                if key.is_finite() {
                    let version = self.clusters[plane as usize].version;
                    self.heap.push(Entry {
                        key,
                        action: Action::Extend {
                            plane,
                            point: o as u32,
                            version,
                        },
                    });
                }
            } else if lo != plane {
                let key = self.mrg_increment(plane, lo);
                if key.is_finite() {
                    let (va, vb) = (
                        self.clusters[plane as usize].version,
                        self.clusters[lo as usize].version,
                    );
                    self.heap.push(Entry {
                        key,
                        action: Action::Merge {
                            a: plane,
                            b: lo,
                            va,
                            vb,
                        },
                    });
                }
            }
        }
    }

    fn stop(&self, key: f64) -> bool {
        key > self.params.max_increment_m2
            || self
                .params
                .max_planes
                .is_some_and(|n| self.plane_count <= n)
    }

    /// Runs the clustering; when the least fresh increment exceeds `e`, re-evaluates every
    /// queued candidate once (stale keys are not lower bounds) and resumes if any is now
    /// admissible; candidates still above `e` are dropped.
    fn run(&mut self) {
        loop {
            self.run_until_stop();
            if self
                .params
                .max_planes
                .is_some_and(|n| self.plane_count <= n)
            {
                return;
            }
            let old = std::mem::take(&mut self.heap).into_vec();
            let mut fresh = Vec::new();
            for entry in old {
                if let Some(e) = self.reevaluate(entry) {
                    if e.key <= self.params.max_increment_m2 {
                        fresh.push(e);
                    }
                }
            }
            if fresh.is_empty() {
                return;
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
            Action::Extend { plane, point, .. } => {
                if self.label[point as usize] != NONE {
                    return None;
                }
                let r = self.root(plane);
                let key = self.ext_increment(r, point as usize);
                let version = self.clusters[r as usize].version;
                key.is_finite().then_some(Entry {
                    key,
                    action: Action::Extend {
                        plane: r,
                        point,
                        version,
                    },
                })
            }
            Action::Merge { a, b, .. } => {
                let (ra, rb) = (self.root(a), self.root(b));
                if ra == rb {
                    return None;
                }
                let key = self.mrg_increment(ra, rb);
                let (va, vb) = (
                    self.clusters[ra as usize].version,
                    self.clusters[rb as usize].version,
                );
                key.is_finite().then_some(Entry {
                    key,
                    action: Action::Merge {
                        a: ra,
                        b: rb,
                        va,
                        vb,
                    },
                })
            }
        }
    }

    fn run_until_stop(&mut self) {
        while let Some(entry) = self.heap.pop() {
            if self
                .params
                .max_planes
                .is_some_and(|n| self.plane_count <= n)
            {
                break;
            }
            match entry.action {
                Action::Create { point, mask } => {
                    let k = point as usize;
                    match self.tetromino(k, mask as usize) {
                        Some(cells) => {
                            if self.stop(entry.key) {
                                self.heap.push(entry);
                                break;
                            }
                            self.create(cells, entry.key);
                        }
                        None => {
                            if let Some((key, mask)) = self.best_create(k) {
                                self.heap.push(Entry {
                                    key,
                                    action: Action::Create { point, mask },
                                });
                            }
                        }
                    }
                }
                Action::Extend {
                    plane,
                    point,
                    version,
                } => {
                    let k = point as usize;
                    if self.label[k] != NONE {
                        continue;
                    }
                    let r = self.root(plane);
                    let v = self.clusters[r as usize].version;
                    if r != plane || v != version {
                        let key = self.ext_increment(r, k);
                        if key.is_finite() {
                            self.heap.push(Entry {
                                key,
                                action: Action::Extend {
                                    plane: r,
                                    point,
                                    version: v,
                                },
                            });
                        }
                        continue;
                    }
                    if self.stop(entry.key) {
                        self.heap.push(entry);
                        break;
                    }
                    self.extend(r, k);
                }
                Action::Merge { a, b, va, vb } => {
                    let (ra, rb) = (self.root(a), self.root(b));
                    if ra == rb {
                        continue;
                    }
                    let (wa, wb) = (
                        self.clusters[ra as usize].version,
                        self.clusters[rb as usize].version,
                    );
                    if ra != a || rb != b || wa != va || wb != vb {
                        let key = self.mrg_increment(ra, rb);
                        if key.is_finite() {
                            self.heap.push(Entry {
                                key,
                                action: Action::Merge {
                                    a: ra,
                                    b: rb,
                                    va: wa,
                                    vb: wb,
                                },
                            });
                        }
                        continue;
                    }
                    if self.stop(entry.key) {
                        self.heap.push(entry);
                        break;
                    }
                    self.merge(ra, rb);
                }
            }
        }
    }

    fn create(&mut self, cells: [usize; 4], _key: f64) {
        let id = self.clusters.len() as u32;
        let stats = self.tetromino_stats(&cells);
        self.clusters.push(Cluster {
            stats,
            error: stats.error(),
            members: cells.iter().map(|&c| c as u32).collect(),
            version: 0,
            parent: id,
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
        cl.version += 1;
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
        cl.version += 1;
        self.plane_count -= 1;
        self.steps += 1;
    }

    fn finish(self) -> Segmentation {
        let mut planes: Vec<Plane> = Vec::new();
        let mut buf = Vec::new();
        for (id, cl) in self.clusters.iter().enumerate() {
            if cl.parent as usize != id || cl.members.len() < self.params.min_points.max(4) {
                continue;
            }
            let Some((w0, _)) = cl.stats.solve() else {
                continue;
            };
            buf.clear();
            buf.extend(cl.members.iter().map(|&m| self.points[m as usize]));
            let Some(fit) = refine(w0, &buf, 1e-6, 20) else {
                continue;
            };
            let mut index: Vec<usize> = cl.members.iter().map(|&m| m as usize).collect();
            index.sort_unstable();
            planes.push(Plane { index, fit });
        }
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
