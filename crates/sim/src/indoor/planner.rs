//! Path planning for the simulated robot: a clearance grid, A* that prefers the middle of
//! corridors, and string pulling with a clearance check.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use nalgebra::Point2;
use rayon::prelude::*;

use crate::scene2::Scene2;

/// Cells of 10 cm with the distance of their centre to the nearest obstacle.
pub(crate) struct ClearanceGrid {
    resolution: f64,
    width: usize,
    height: usize,
    clearance: Vec<f32>,
}

const NEIGHBOURS: [(i64, i64, f64); 8] = [
    (1, 0, 1.0),
    (-1, 0, 1.0),
    (0, 1, 1.0),
    (0, -1, 1.0),
    (1, 1, std::f64::consts::SQRT_2),
    (1, -1, std::f64::consts::SQRT_2),
    (-1, 1, std::f64::consts::SQRT_2),
    (-1, -1, std::f64::consts::SQRT_2),
];

impl ClearanceGrid {
    /// The grid over `[0, width_m] × [0, height_m]`.
    pub(crate) fn new(scene: &Scene2, width_m: f64, height_m: f64, resolution: f64) -> Self {
        let width = (width_m / resolution).ceil().max(1.0) as usize;
        let height = (height_m / resolution).ceil().max(1.0) as usize;
        let clearance: Vec<f32> = (0..height)
            .into_par_iter()
            .flat_map_iter(|j| {
                (0..width).map(move |i| {
                    let c =
                        Point2::new((i as f64 + 0.5) * resolution, (j as f64 + 0.5) * resolution);
                    scene.distance(&c) as f32
                })
            })
            .collect();
        Self {
            resolution,
            width,
            height,
            clearance,
        }
    }

    pub(crate) fn len(&self) -> usize {
        self.clearance.len()
    }

    pub(crate) fn center(&self, cell: usize) -> Point2<f64> {
        let (i, j) = (cell % self.width, cell / self.width);
        Point2::new(
            (i as f64 + 0.5) * self.resolution,
            (j as f64 + 0.5) * self.resolution,
        )
    }

    pub(crate) fn cell(&self, p: &Point2<f64>) -> Option<usize> {
        let (i, j) = (
            (p.x / self.resolution).floor(),
            (p.y / self.resolution).floor(),
        );
        if i < 0.0 || j < 0.0 || i >= self.width as f64 || j >= self.height as f64 {
            return None;
        }
        Some(j as usize * self.width + i as usize)
    }

    pub(crate) fn clearance(&self, cell: usize) -> f64 {
        self.clearance.get(cell).map_or(0.0, |&c| f64::from(c))
    }

    fn neighbours(&self, cell: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let (i, j) = ((cell % self.width) as i64, (cell / self.width) as i64);
        NEIGHBOURS.iter().filter_map(move |&(di, dj, len)| {
            let (ni, nj) = (i + di, j + dj);
            (ni >= 0 && nj >= 0 && (ni as usize) < self.width && (nj as usize) < self.height)
                .then(|| (nj as usize * self.width + ni as usize, len))
        })
    }

    /// Cells reachable from `start` through cells with at least `min_clearance_m`.
    pub(crate) fn reachable(&self, start: usize, min_clearance_m: f64) -> Vec<bool> {
        let mut seen = vec![false; self.len()];
        if self.clearance(start) < min_clearance_m {
            return seen;
        }
        let mut stack = vec![start];
        if let Some(s) = seen.get_mut(start) {
            *s = true;
        }
        while let Some(c) = stack.pop() {
            for (n, _) in self.neighbours(c) {
                if !seen[n] && self.clearance(n) >= min_clearance_m {
                    seen[n] = true;
                    stack.push(n);
                }
            }
        }
        seen
    }

    /// A* from `start` to `goal` over cells with at least `min_clearance_m`; a step costs its
    /// length times `1 + 3·(1 − clearance/preferred)` below the preferred clearance, so paths
    /// keep to the middle of corridors and doors. Returns cell centres, start to goal.
    pub(crate) fn astar(
        &self,
        start: usize,
        goal: usize,
        min_clearance_m: f64,
        preferred_clearance_m: f64,
    ) -> Option<Vec<Point2<f64>>> {
        let n = self.len();
        let mut cost = vec![f64::INFINITY; n];
        let mut parent = vec![usize::MAX; n];
        let mut closed = vec![false; n];
        let goal_p = self.center(goal);
        let h = |c: usize| (self.center(c) - goal_p).norm();
        let mut open = BinaryHeap::new();
        *cost.get_mut(start)? = 0.0;
        // Non-negative f64 keys order like their bit patterns; ties break on the cell index.
        open.push(Reverse((h(start).to_bits(), start)));
        while let Some(Reverse((_, c))) = open.pop() {
            if c == goal {
                let mut path = vec![self.center(c)];
                let mut k = c;
                while k != start {
                    k = *parent.get(k)?;
                    path.push(self.center(k));
                }
                path.reverse();
                return Some(path);
            }
            if std::mem::replace(&mut closed[c], true) {
                continue;
            }
            for (m, len) in self.neighbours(c) {
                let clear = self.clearance(m);
                if closed[m] || clear < min_clearance_m {
                    continue;
                }
                let penalty = 1.0 + 3.0 * (1.0 - clear / preferred_clearance_m).max(0.0);
                let g = cost[c] + len * self.resolution * penalty;
                if g < cost[m] {
                    cost[m] = g;
                    parent[m] = c;
                    open.push(Reverse(((g + h(m)).to_bits(), m)));
                }
            }
        }
        None
    }
}

/// Whether every point of the segment `a`–`b` (sampled every 5 cm) is at least
/// `min_clearance_m` from the scene.
pub(crate) fn segment_clear(
    scene: &Scene2,
    a: &Point2<f64>,
    b: &Point2<f64>,
    min_clearance_m: f64,
) -> bool {
    let d = b - a;
    let steps = (d.norm() / 0.05).ceil().max(1.0) as usize;
    (0..=steps).all(|k| scene.distance(&(a + d * (k as f64 / steps as f64))) >= min_clearance_m)
}

/// Greedy string pulling: from each kept point, the straight piece reaches as far along
/// `path` as it stays `min_clearance_m` from the scene (neighbouring grid cells are always
/// connected).
pub(crate) fn shortcut(
    scene: &Scene2,
    path: &[Point2<f64>],
    min_clearance_m: f64,
) -> Vec<Point2<f64>> {
    let Some(&first) = path.first() else {
        return Vec::new();
    };
    let mut out = vec![first];
    let mut i = 0;
    while i + 1 < path.len() {
        let mut j = i + 1;
        while j + 1 < path.len() && segment_clear(scene, &path[i], &path[j + 1], min_clearance_m) {
            j += 1;
        }
        out.push(path[j]);
        i = j;
    }
    out
}
