//! The discretized search space and the two searches over it: branch and bound (Hess et al.
//! 2016 §V, Algorithm 3) and brute force (Olson 2009's exhaustive correlation).
//!
//! Candidates are `(θ₀ + k·δθ, t₀ + (dx, dy)·r)` for `|k| ≤ ⌈W_θ/δθ⌉` and
//! `|dx|, |dy| ≤ ⌈W_x/r⌉` (Hess §V, the search window). For each `k` the points are rotated once and
//! placed at the initial translation, giving integer cells `c_i`; a candidate's score is
//! `Σ_i M(c_i + (dx, dy)) / n` (Hess §V, `M = 0` outside the grid), summed exactly in
//! 16-bit units. Offsets at which no point can land in the grid score 0 and are skipped.
//!
//! Ties are broken towards the initial guess: smaller `|k|` (then `k > 0` first), then
//! smaller `dx² + dy²`, then smaller `dx`, then `dy`. Both searches maximise the same total
//! order, so branch and bound returns exactly the brute-force optimum.

use raypath_geometry::Pose2;

use super::grid::{ProbabilityGrid, QUANT_MAX};
use super::precompute::{LevelView, PrecomputedGrids};
use super::{CorrelativeMatch, SearchWindow};

/// Largest number of (angle, point) pairs one query discretizes (128 MiB of cells).
pub const MAX_DISCRETE_POINTS: usize = 1 << 24;

/// Top-level candidates scored and sorted at once; larger searches go in chunks (still exact,
/// with a sort per chunk instead of one global sort).
const TOP_LEVEL_CHUNK: usize = 1 << 20;

/// Cells further than this from 0 are clamped (far beyond any grid or window).
const CELL_LIMIT: f64 = (1u64 << 30) as f64;

/// A point that is not finite: never inside the grid.
const NOWHERE: [i32; 2] = [i32::MIN, i32::MIN];

/// The scan discretized for every rotation of the window.
pub(crate) struct DiscreteScans {
    n_points: usize,
    k_max: i64,
    step_rad: f64,
    initial: Pose2,
    resolution_m: f64,
    /// `(2 k_max + 1) × n_points` cells, angle-major.
    cells: Vec<[i32; 2]>,
    /// Per angle, the inclusive offset range `[x_lo, x_hi, y_lo, y_hi]` that can score.
    ranges: Vec<Option<[i32; 4]>>,
}

impl DiscreteScans {
    /// Discretizes `points` for the window; `None` for an invalid query or an empty search.
    pub(crate) fn new(
        grid: &ProbabilityGrid,
        points: &[[f64; 2]],
        initial: Pose2,
        window: &SearchWindow,
        step_rad: f64,
    ) -> Option<Self> {
        let valid = !points.is_empty()
            && initial.is_finite()
            && window.linear_m.is_finite()
            && window.linear_m >= 0.0
            && window.angular_rad >= 0.0
            && !window.angular_rad.is_nan()
            && step_rad.is_finite()
            && step_rad > 0.0
            && grid.width() > 0
            && grid.height() > 0;
        if !valid {
            return None;
        }
        let res = grid.resolution_m();
        // Hess et al. 2016 §V: w_θ = ⌈W_θ / δθ⌉, the window at most a half turn each way.
        let k_max = (window.angular_rad.min(std::f64::consts::PI) / step_rad).ceil();
        let n_angles = 2.0 * k_max + 1.0;
        if n_angles * points.len() as f64 > MAX_DISCRETE_POINTS as f64 {
            return None;
        }
        let k_max = k_max as i64;
        // Hess et al. 2016 §V: w_x = ⌈W_x / r⌉.
        let w_lin = (window.linear_m / res).ceil().min(CELL_LIMIT) as i64;
        let mut scans = Self {
            n_points: points.len(),
            k_max,
            step_rad,
            initial,
            resolution_m: res,
            cells: Vec::with_capacity(n_angles as usize * points.len()),
            ranges: Vec::with_capacity(n_angles as usize),
        };
        for k in -k_max..=k_max {
            let range = scans.push_rotation(grid, points, k, w_lin);
            scans.ranges.push(range);
        }
        Some(scans)
    }

    /// Appends the cells of the points rotated by `θ₀ + k·δθ` at the initial translation and
    /// returns the offsets within `±w_lin` at which some point lands in the grid.
    fn push_rotation(
        &mut self,
        grid: &ProbabilityGrid,
        points: &[[f64; 2]],
        k: i64,
        w_lin: i64,
    ) -> Option<[i32; 4]> {
        let theta = self.initial.theta() + k as f64 * self.step_rad;
        let (s, c) = theta.sin_cos();
        let (x0, y0) = (self.initial.x(), self.initial.y());
        let [ox, oy] = grid.origin();
        let res = grid.resolution_m();
        let (mut lo, mut hi) = ([i64::MAX; 2], [i64::MIN; 2]);
        for p in points {
            // The cell as `GridLevel::cell_of` computes it (division, not a reciprocal).
            let x = ((c * p[0] - s * p[1] + x0 - ox) / res).floor();
            let y = ((s * p[0] + c * p[1] + y0 - oy) / res).floor();
            if !(x.is_finite() && y.is_finite()) {
                self.cells.push(NOWHERE);
                continue;
            }
            let cell = [
                x.clamp(-CELL_LIMIT, CELL_LIMIT) as i32,
                y.clamp(-CELL_LIMIT, CELL_LIMIT) as i32,
            ];
            for a in 0..2 {
                lo[a] = lo[a].min(i64::from(cell[a]));
                hi[a] = hi[a].max(i64::from(cell[a]));
            }
            self.cells.push(cell);
        }
        let size = [grid.width() as i64, grid.height() as i64];
        let mut range = [0i32; 4];
        for a in 0..2 {
            // Some point lands inside along axis a iff offset ∈ [−hi, size − 1 − lo].
            let from = (-w_lin).max(-hi[a]);
            let to = w_lin.min(size[a] - 1 - lo[a]);
            if from > to {
                return None;
            }
            range[2 * a] = from as i32;
            range[2 * a + 1] = to as i32;
        }
        Some(range)
    }

    fn n_angles(&self) -> usize {
        self.ranges.len()
    }

    fn angle_cells(&self, angle: usize) -> &[[i32; 2]] {
        let from = angle * self.n_points;
        self.cells.get(from..from + self.n_points).unwrap_or(&[])
    }

    /// The signed rotation step count of angle index `angle`.
    fn k(&self, angle: usize) -> i64 {
        angle as i64 - self.k_max
    }

    /// Tie-break rank of an angle: 0, +1, −1, +2, −2, …
    fn rank(&self, angle: usize) -> u32 {
        let k = self.k(angle);
        (if k > 0 { 2 * k - 1 } else { -2 * k }) as u32
    }

    /// Smallest integer sum whose mean reaches `min_score` (at least 1: a pose that puts no
    /// point on the map is never a match); `None` for a non-finite `min_score`.
    fn threshold(&self, min_score: f64) -> Option<u64> {
        if !min_score.is_finite() {
            return None;
        }
        let full = self.n_points as f64 * f64::from(QUANT_MAX);
        // Start from ⌈min_score · full⌉ and correct its rounding so that exactly the sums
        // whose reported score `sum / full` is ≥ min_score pass.
        let mut t = (min_score * full).ceil().clamp(1.0, full + 1.0) as u64;
        while t > 1 && (t - 1) as f64 / full >= min_score {
            t -= 1;
        }
        while (t as f64) / full < min_score && (t as f64) <= full {
            t += 1;
        }
        Some(t)
    }

    fn to_match(&self, best: &Best, candidates_scored: usize) -> Option<CorrelativeMatch> {
        if !best.found {
            return None;
        }
        let k = self.k(best.angle as usize);
        let r = self.resolution_m;
        Some(CorrelativeMatch {
            submap_from_sensor: Pose2::new(
                self.initial.x() + f64::from(best.key.dx) * r,
                self.initial.y() + f64::from(best.key.dy) * r,
                self.initial.theta() + k as f64 * self.step_rad,
            ),
            score: best.sum as f64 / (self.n_points as f64 * f64::from(QUANT_MAX)),
            candidates_scored,
        })
    }
}

/// Σ of the level's values at `cells + (dx, dy)` (0 outside): the exact score at level 0,
/// an upper bound over the `2^h × 2^h` block at level `h` (Hess et al. 2016 §V.C).
#[inline]
fn score(view: &LevelView<'_>, cells: &[[i32; 2]], dx: i32, dy: i32) -> u64 {
    let ox = i64::from(dx) + view.pad;
    let oy = i64::from(dy) + view.pad;
    let (w, h) = (view.width as u64, view.height as u64);
    let mut sum = 0u64;
    for c in cells {
        let a = (i64::from(c[0]) + ox) as u64; // negative → huge → outside
        let b = (i64::from(c[1]) + oy) as u64;
        if a < w && b < h {
            sum += u64::from(view.cells[(b * w + a) as usize]);
        }
    }
    sum
}

/// The tie-break key of a candidate: smaller is preferred among equal scores.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Key {
    rank: u32,
    d2: u64,
    dx: i32,
    dy: i32,
}

/// The best candidate so far; starts as a virtual candidate at the threshold that every
/// real candidate reaching the threshold beats.
struct Best {
    sum: u64,
    key: Key,
    angle: u32,
    found: bool,
}

impl Best {
    fn new(threshold: u64) -> Self {
        Self {
            sum: threshold,
            key: Key {
                rank: u32::MAX,
                d2: u64::MAX,
                dx: i32::MAX,
                dy: i32::MAX,
            },
            angle: 0,
            found: false,
        }
    }

    /// Whether a subtree with upper bound `bound` and key lower bound `(rank, d2)` may hold a
    /// candidate that beats the best (branch-and-bound pruning, Hess Algorithm 3).
    fn may_beat(&self, bound: u64, rank: u32, d2: u64) -> bool {
        bound > self.sum || (bound == self.sum && (rank, d2) <= (self.key.rank, self.key.d2))
    }

    /// Offers a fully evaluated candidate.
    fn offer(&mut self, sum: u64, key: Key, angle: u32) {
        if sum > self.sum || (sum == self.sum && key < self.key) {
            *self = Self {
                sum,
                key,
                angle,
                found: true,
            };
        }
    }
}

fn min_abs(lo: i32, hi: i32) -> u64 {
    if lo <= 0 && hi >= 0 {
        0
    } else {
        u64::from(lo.unsigned_abs().min(hi.unsigned_abs()))
    }
}

/// A branch-and-bound node: the `2^h × 2^h` offsets from `(x, y)` at one angle.
#[derive(Clone, Copy, Debug, Default)]
struct Node {
    angle: u32,
    x: i32,
    y: i32,
    bound: u64,
    rank: u32,
    d2: u64,
}

impl Node {
    /// A node with its bound on `view` and its key lower bound within `range`.
    fn new(scans: &DiscreteScans, view: &LevelView<'_>, angle: usize, x: i32, y: i32) -> Self {
        let [_, x_hi, _, y_hi] = scans.ranges[angle].unwrap_or_default();
        let side = (view.pad as i32).saturating_add(1);
        let d2x = min_abs(x, x.saturating_add(side - 1).min(x_hi));
        let d2y = min_abs(y, y.saturating_add(side - 1).min(y_hi));
        Self {
            angle: angle as u32,
            x,
            y,
            bound: score(view, scans.angle_cells(angle), x, y),
            rank: scans.rank(angle),
            d2: d2x * d2x + d2y * d2y,
        }
    }

    /// Best first: larger bound, then smaller key lower bound.
    fn order(a: &Self, b: &Self) -> std::cmp::Ordering {
        b.bound
            .cmp(&a.bound)
            .then((a.rank, a.d2).cmp(&(b.rank, b.d2)))
            .then((a.angle, a.x, a.y).cmp(&(b.angle, b.x, b.y)))
    }
}

/// The branch-and-bound search of one query.
struct Search<'a> {
    grids: &'a PrecomputedGrids,
    scans: &'a DiscreteScans,
    best: Best,
    scored: usize,
}

impl Search<'_> {
    /// Visits `nodes` (sorted best first) at height `h`: prune, or descend.
    fn visit(&mut self, nodes: &[Node], h: usize) {
        for node in nodes {
            if !self.best.may_beat(node.bound, node.rank, node.d2) {
                if node.bound < self.best.sum {
                    break; // sorted: every later node is bounded lower
                }
                continue;
            }
            if h == 0 {
                let key = Key {
                    rank: node.rank,
                    d2: node.d2,
                    dx: node.x,
                    dy: node.y,
                };
                self.best.offer(node.bound, key, node.angle);
            } else {
                self.branch(node, h);
            }
        }
    }

    /// Splits a node of height `h ≥ 1` into its (up to) four children of height `h − 1`,
    /// scores them on level `h − 1` and visits them best first.
    fn branch(&mut self, node: &Node, h: usize) {
        let Some(view) = self.grids.view(h - 1) else {
            return;
        };
        let angle = node.angle as usize;
        let [_, x_hi, _, y_hi] = self.scans.ranges[angle].unwrap_or_default();
        let half = 1i32 << (h - 1);
        let mut children = [Node::default(); 4];
        let mut n = 0;
        for (ox, oy) in [(0, 0), (half, 0), (0, half), (half, half)] {
            let (x, y) = (node.x.saturating_add(ox), node.y.saturating_add(oy));
            if x <= x_hi && y <= y_hi {
                children[n] = Node::new(self.scans, &view, angle, x, y);
                n += 1;
            }
        }
        self.scored += n;
        let children = &mut children[..n];
        children.sort_unstable_by(Node::order);
        self.visit(children, h - 1);
    }
}

/// Branch and bound over the discretized window (Hess et al. 2016 Algorithm 3).
/// `depth` levels at most (clamped to `1 ..= grids.depth()`).
pub(crate) fn branch_and_bound(
    grids: &PrecomputedGrids,
    scans: &DiscreteScans,
    min_score: f64,
    depth: usize,
) -> Option<CorrelativeMatch> {
    let threshold = scans.threshold(min_score)?;
    let top = depth.clamp(1, grids.depth()) - 1;
    let view = grids.view(top)?;
    let stride = 1usize << top;
    let mut search = Search {
        grids,
        scans,
        best: Best::new(threshold),
        scored: 0,
    };
    let mut nodes: Vec<Node> = Vec::new();
    let flush = |nodes: &mut Vec<Node>, search: &mut Search<'_>| {
        search.scored += nodes.len();
        nodes.sort_unstable_by(Node::order);
        search.visit(nodes, top);
        nodes.clear();
    };
    // The lowest-resolution candidates C₀ (Hess Algorithm 3, line 1), best first.
    for angle in 0..scans.n_angles() {
        let Some([x_lo, x_hi, y_lo, y_hi]) = scans.ranges[angle] else {
            continue;
        };
        for y in (y_lo..=y_hi).step_by(stride) {
            for x in (x_lo..=x_hi).step_by(stride) {
                nodes.push(Node::new(scans, &view, angle, x, y));
                if nodes.len() >= TOP_LEVEL_CHUNK {
                    flush(&mut nodes, &mut search);
                }
            }
        }
    }
    flush(&mut nodes, &mut search);
    scans.to_match(&search.best, search.scored)
}

/// Scores every candidate of the discretized window on the grid itself.
pub(crate) fn brute_force(
    grid: &ProbabilityGrid,
    scans: &DiscreteScans,
    min_score: f64,
) -> Option<CorrelativeMatch> {
    let threshold = scans.threshold(min_score)?;
    let view = LevelView {
        cells: grid.cells(),
        width: grid.width() as i64,
        height: grid.height() as i64,
        pad: 0,
    };
    let mut best = Best::new(threshold);
    let mut scored = 0;
    for angle in 0..scans.n_angles() {
        let Some([x_lo, x_hi, y_lo, y_hi]) = scans.ranges[angle] else {
            continue;
        };
        let cells = scans.angle_cells(angle);
        let rank = scans.rank(angle);
        for dy in y_lo..=y_hi {
            for dx in x_lo..=x_hi {
                let sum = score(&view, cells, dx, dy);
                let d2 = min_abs(dx, dx).pow(2) + min_abs(dy, dy).pow(2);
                let key = Key { rank, d2, dx, dy };
                best.offer(sum, key, angle as u32);
                scored += 1;
            }
        }
    }
    scans.to_match(&best, scored)
}
