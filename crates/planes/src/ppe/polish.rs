//! The post-processing rounds of [`PpeParams::refine_rounds`] (not in the thesis; see the
//! crate docs) and the final exact refits of the planes (Schaefer 2020, Eq. 11.1–11.2).

use std::collections::HashMap;

use nalgebra::Vector3;
use rayon::prelude::*;

use super::{Action, Entry, NONE, Plane, Segmentation, State, grid, queue};
use crate::fit::refit;
#[cfg(doc)]
use crate::params::PpeParams;

impl State<'_> {
    /// The post-processing rounds of [`PpeParams::refine_rounds`].
    pub(super) fn polish(&mut self) {
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

    /// The plane `w` of every root plane with at least `min_points` rays.
    fn big_planes(&self) -> Vec<Option<Vector3<f64>>> {
        let min_points = self.params.min_points.max(4);
        self.clusters
            .iter()
            .enumerate()
            .map(|(id, cl)| {
                (self.parent[id] as usize == id && cl.len as usize >= min_points)
                    .then(|| cl.stats.solve().map(|(w, _)| w))
                    .flatten()
            })
            .collect()
    }

    /// The plane boundary ray `k` should move to, if any: the adjacent plane with the least
    /// residual (rays of small planes move only when it is at most `limit`).
    fn best_move(&self, k: usize, big: &[Option<Vector3<f64>>], limit: f64) -> Option<u32> {
        let own = self.label[k];
        let plane_of = |l: u32| big.get(l as usize).copied().flatten();
        let mut best: Option<(f64, u32)> = plane_of(own).map(|w| (self.residual(&w, k), own));
        let own_big = best.is_some();
        let mut boundary = false;
        let links = self.links[k];
        for (bit, o) in grid::neighbours(k, self.width) {
            if links & bit == 0 {
                continue;
            }
            let lo = self.label[o];
            if lo == NONE || lo == own {
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
        let (e, to) = best.filter(|_| boundary)?;
        (to != own && (own_big || e <= limit)).then_some(to)
    }

    /// One sweep of boundary refinement (the moves are chosen in parallel on the labels
    /// before the sweep, then applied in ray order); returns the number of rays moved.
    fn refine_boundary(&mut self) -> usize {
        let big = self.big_planes();
        let limit = self.params.max_increment_m2.sqrt();
        let moves: Vec<(usize, u32)> = (0..self.points.len())
            .into_par_iter()
            .with_min_len(4096)
            .filter(|&k| self.label[k] != NONE)
            .filter_map(|k| self.best_move(k, &big, limit).map(|to| (k, to)))
            .collect();
        for &(k, to) in &moves {
            let from = self.label[k];
            let ps = self.ray_stats(k);
            self.clusters[from as usize].stats.remove(&ps);
            self.clusters[to as usize].stats.add(&ps);
            self.label[k] = to;
        }
        if !moves.is_empty() {
            self.rebuild_members();
        }
        moves.len()
    }

    /// Rebuilds every member list from the labels (in ray order) and the plane errors.
    fn rebuild_members(&mut self) {
        for cl in &mut self.clusters {
            (cl.head, cl.tail, cl.len) = (NONE, NONE, 0);
        }
        for k in 0..self.points.len() {
            let l = self.label[k];
            if l != NONE {
                self.append(l, k);
            }
        }
        for cl in &mut self.clusters {
            cl.error = if cl.len >= 4 { cl.stats.error() } else { 0.0 };
        }
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
            for (bit, o) in [(grid::RIGHT, k + 1), (grid::DOWN, k + self.width)] {
                if self.links[k] & bit != 0 {
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
            self.clusters[a as usize].len >= 4 && self.clusters[b as usize].len >= 4
        });
        self.merge_pairs(pairs)
    }

    /// Candidate gaps of [`State::merge_occluded`] along rows and columns: (a, b, first gap
    /// ray, last gap ray, stride).
    fn occlusion_gaps(&self) -> Vec<(u32, u32, usize, usize, usize)> {
        let min_points = self.params.min_points.max(4);
        let is_big = |l: u32| {
            l != NONE
                && self
                    .clusters
                    .get(l as usize)
                    .is_some_and(|c| c.len as usize >= min_points)
        };
        let mut gaps = Vec::new();
        let lines = (0..self.height)
            .map(|row| (row * self.width, 1, self.width))
            .chain((0..self.width).map(|col| (col, self.width, self.height)));
        for (start, stride, len) in lines {
            // The last ray of the most recent distinct planes along the line.
            let mut recent: [(u32, usize); 4] = [(NONE, 0); 4];
            for i in 0..len {
                let k = start + i * stride;
                let l = self.label[k];
                if !is_big(l) {
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
        gaps
    }

    /// Merges planes that are pieces of one surface seen on both sides of an occluder:
    /// along a row or column, plane `a` ends, only rays **in front of** the joint plane of
    /// `a` and `b` follow (by more than three RMS residuals of the joint fit), then plane `b`
    /// begins; the merge is executed when its increment is at most `e`. Returns the number
    /// of merges.
    fn merge_occluded(&mut self) -> usize {
        // Joint plane and occlusion margin of each pair.
        type Joint = Option<(Vector3<f64>, f64)>;
        let mut cache: HashMap<(u32, u32), Joint> = HashMap::new();
        let mut pairs = Vec::new();
        for (a, b, first, last, stride) in self.occlusion_gaps() {
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
        let mut heap = queue::Queue::default();
        for (a, b) in pairs {
            let entry = Entry::new(self.mrg_increment(a, b), Action::Merge { a, b });
            if entry.key <= e_max {
                heap.push(entry.item());
            }
        }
        let mut merged = 0;
        while let Some(entry) = heap.pop().map(Entry::from_item) {
            let Action::Merge { a, b } = entry.action() else {
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
            if key > entry.key && heap.peek().is_some_and(|n| key > Entry::from_item(n).key) {
                heap.push(Entry::new(key, Action::Merge { a: ra, b: rb }).item());
                continue;
            }
            self.merge(ra, rb);
            merged += 1;
        }
        merged
    }

    /// The planes of at least `min_points` rays, refitted on the exact radial residuals
    /// (parallel over planes), largest first, and the labels of the rays.
    pub(super) fn finish(self) -> Segmentation {
        let min_points = self.params.min_points.max(4);
        let alive: Vec<u32> = (0..self.clusters.len() as u32)
            .filter(|&id| {
                let cl = &self.clusters[id as usize];
                self.parent[id as usize] == id && cl.len as usize >= min_points
            })
            .collect();
        let planes: Vec<Plane> = alive
            .into_par_iter()
            .filter_map(|id| {
                let (w0, _) = self.clusters[id as usize].stats.solve()?;
                let buf: Vec<Vector3<f64>> = self.members(id).map(|m| self.points[m]).collect();
                let fit = refit(w0, &buf)?;
                let mut index: Vec<usize> = self.members(id).collect();
                index.sort_unstable();
                Some(Plane { index, fit })
            })
            .collect();
        Segmentation::from_planes(
            self.width,
            self.height,
            self.points.len(),
            planes,
            self.steps,
        )
    }
}
