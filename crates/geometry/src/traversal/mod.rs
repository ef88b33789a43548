//! Exact ray traversal of uniform grids (Amanatides & Woo 1987).
//!
//! J. Amanatides and A. Woo, "A fast voxel traversal algorithm for ray tracing",
//! *Eurographics* 1987: a ray crosses a uniform grid cell by cell; per axis it keeps the ray
//! parameter `t` of the next cell boundary and steps along the axis whose boundary comes first.
//! [`Grid2::traverse`](crate::Grid2::traverse) and [`Grid3::traverse`](crate::Grid3::traverse)
//! return a [`Traversal`], an allocation-free iterator of [`CellCrossing`]s: every cell the
//! segment `origin + t · direction`, `t ∈ [0, length_m]`, passes through **inside the grid**,
//! in order, with the interval `[t_enter, t_exit]` it spends there. `t` is in metres because
//! directions are unit vectors, so `t_exit − t_enter` is the in-cell path length `d_i` that
//! the decay-rate model of Schaefer (2020, ch. 7) sums into `R_i = Σ d_i`.
//!
//! The contract is documented on [`Traversal`]. [`SlabWalk`] is a fast path for counting
//! the voxels segments cross (hit/miss grids): the same voxels, walked slab by slab along the
//! major axis without per-voxel `t` comparisons.

mod axis;
mod grid;
mod slab;
#[cfg(test)]
mod tests;

use axis::{axis_setup, boundary_t};
pub use slab::{SlabWalk, SlabWalkEnd};

/// One cell crossed by a traversal: which cell, and the ray parameter interval (metres along
/// the unit direction) the ray spends inside it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellCrossing<const N: usize> {
    /// The cell (per-axis indices, inside the grid).
    pub cell: [usize; N],
    /// The cell's linear index in the grid (x fastest), as from `linear_index`.
    pub index: usize,
    /// Where the ray enters the cell, in metres from the ray origin.
    pub t_enter: f64,
    /// Where the ray leaves the cell (or ends inside it), in metres from the ray origin;
    /// `t_exit >= t_enter`.
    pub t_exit: f64,
}

impl<const N: usize> CellCrossing<N> {
    /// The path length inside the cell in metres (`t_exit − t_enter`, zero at corners).
    #[inline]
    pub fn length(&self) -> f64 {
        self.t_exit - self.t_enter
    }
}

/// A crossing of a 2-D grid cell.
pub type CellCrossing2 = CellCrossing<2>;
/// A crossing of a 3-D grid cell (voxel).
pub type CellCrossing3 = CellCrossing<3>;

/// The iterator of cells a segment crosses inside a grid, from
/// [`Grid2::traverse`](crate::Grid2::traverse) or [`Grid3::traverse`](crate::Grid3::traverse)
/// (Amanatides & Woo 1987).
///
/// # Contract
///
/// * **Clipping.** The segment is first clipped to the grid box with
///   [`Aabb3::clip_segment`](crate::Aabb3::clip_segment); rays may start and end outside the
///   grid. The first crossing starts at the clipped start, each `t_enter` equals the previous
///   `t_exit`, and the last crossing ends at the clipped end, so the lengths sum to the clipped
///   length up to rounding of the sum (relative 1e-12 in practice).
/// * **Face neighbours.** Consecutive cells differ by one step along one axis. Where the ray
///   passes exactly through an edge or a corner, the walk steps one axis at a time and reports
///   the intermediate cells with zero length (`t_enter == t_exit`); ties between axes step
///   the higher axis first (z before y before x). No cell is skipped or repeated.
/// * **First cell.** The cell the segment occupies just after its start: a start exactly on a
///   face, moving towards lower indices, begins in the lower cell (unless, by rounding, the
///   coordinate never leaves that face: then the axis counts as not moving, below).
/// * **Last cell.** For an endpoint inside the grid it is [`Grid3::cell_of`](crate::Grid3::cell_of)
///   of the endpoint: a point on a shared face belongs to the cell with the larger index, so a
///   ray that ends exactly on a face it reaches moving towards higher indices ends with a
///   zero-length crossing of the next cell. When the grid box cuts the segment, the last cell
///   is the one the segment occupies just before it leaves.
/// * **Degenerate input.** Zero-length segments, segments whose part inside the grid has zero
///   length (they only touch its boundary), negative or NaN lengths and non-finite origins or
///   directions yield **nothing**. A length of `+∞` traces the ray until it leaves the grid.
/// * **Axis-parallel rays** (zero direction components, or a coordinate that rounding keeps
///   constant over the segment) never step along those axes. A ray
///   lying in a cell face is reported in the cells on its larger-index side, like
///   [`Grid3::cell_of`](crate::Grid3::cell_of) — except on the grid's upper boundary face,
///   where it is reported in the last layer of cells.
///
/// # Numerics and speed
///
/// The cells are found by counting: the first and last cells are computed from the clipped
/// start and end points, which fixes how many steps each axis takes; the boundary parameters
/// `t = (boundary − origin) / direction` only order the steps. Each `t` is computed from its
/// boundary index (no accumulation of `tDelta`), clamped to the clipped interval and made
/// non-decreasing. So the walk always terminates at the right cell, never leaves the grid and
/// never needs a bounds check on the cell. The iterator is a plain struct (no heap), implements
/// [`ExactSizeIterator`], and overrides [`Iterator::fold`] with a tight loop, so `sum`,
/// `for_each` and friends run without per-item `Option` checks.
#[derive(Clone, Debug)]
pub struct Traversal<const N: usize> {
    /// The current cell.
    cell: [usize; N],
    /// Linear index of the current cell.
    index: usize,
    /// Where the ray entered the current cell.
    t_cur: f64,
    /// The clipped end of the segment.
    t_end: f64,
    /// Per axis: `t` of the next boundary to cross (≤ `t_end`), or `+∞` when the axis has no
    /// steps left.
    t_next: [f64; N],
    /// Per axis: index of the next boundary to cross (exact small integers in `f64`).
    boundary: [f64; N],
    /// Per axis: `±1` boundary step.
    boundary_step: [f64; N],
    /// Per axis: steps left.
    remaining: [usize; N],
    /// Per axis: `±1` as a wrapping `usize`.
    cell_step: [usize; N],
    /// Per axis: `±stride` as a wrapping `usize`.
    index_step: [usize; N],
    /// Per axis: grid origin minus ray origin, metres.
    origin_offset: [f64; N],
    /// Per axis: `1 / direction`.
    inv_direction: [f64; N],
    /// Cell edge in metres.
    cell_size: f64,
    /// Steps left over all axes.
    steps_left: usize,
    /// True once the last crossing was yielded (or for an empty traversal).
    finished: bool,
}

/// A traversal of a 2-D grid.
pub type Traversal2 = Traversal<2>;
/// A traversal of a 3-D grid.
pub type Traversal3 = Traversal<3>;

/// The grid geometry a traversal needs, as plain arrays.
pub(crate) struct GridSpec<const N: usize> {
    pub origin: [f64; N],
    pub cell_size: f64,
    pub dims: [usize; N],
}

/// A segment already clipped to the grid box.
pub(crate) struct ClippedSegment<const N: usize> {
    pub origin: [f64; N],
    pub direction: [f64; N],
    /// Clipped start and end (`t_start < t_end`, both finite).
    pub t_start: f64,
    pub t_end: f64,
    /// True when the grid box, not the segment's own end, bounds `t_end`.
    pub clipped_at_end: bool,
}

impl<const N: usize> Traversal<N> {
    /// The traversal that yields nothing.
    pub fn empty() -> Self {
        Self {
            cell: [0; N],
            index: 0,
            t_cur: 0.0,
            t_end: 0.0,
            t_next: [f64::INFINITY; N],
            boundary: [0.0; N],
            boundary_step: [0.0; N],
            remaining: [0; N],
            cell_step: [0; N],
            index_step: [0; N],
            origin_offset: [0.0; N],
            inv_direction: [0.0; N],
            cell_size: 1.0,
            steps_left: 0,
            finished: true,
        }
    }

    /// Sets up the walk of a segment that is already clipped to the grid.
    pub(crate) fn new(grid: &GridSpec<N>, segment: &ClippedSegment<N>) -> Self {
        let mut walk = Self::empty();
        walk.finished = false;
        walk.t_cur = segment.t_start;
        walk.t_end = segment.t_end;
        walk.cell_size = grid.cell_size;
        let mut stride = 1usize;
        for axis in 0..N {
            let dim = grid.dims[axis];
            let setup = axis_setup(
                segment.origin[axis],
                segment.direction[axis],
                grid.origin[axis],
                grid.cell_size,
                dim,
                segment.t_start,
                segment.t_end,
                segment.clipped_at_end,
            );
            walk.cell[axis] = setup.start;
            walk.index += setup.start * stride;
            walk.remaining[axis] = setup.steps;
            walk.steps_left += setup.steps;
            walk.origin_offset[axis] = setup.offset;
            walk.inv_direction[axis] = setup.inv;
            walk.boundary[axis] = setup.boundary;
            walk.t_next[axis] = setup.t_next;
            if setup.up {
                walk.boundary_step[axis] = 1.0;
                walk.cell_step[axis] = 1;
                walk.index_step[axis] = stride;
            } else {
                walk.boundary_step[axis] = -1.0;
                walk.cell_step[axis] = usize::MAX; // −1, wrapping
                walk.index_step[axis] = stride.wrapping_neg();
            }
            stride *= dim;
        }
        walk
    }

    /// `t` of the next boundary along `axis`, clamped to the segment end (a NaN from
    /// overflow also becomes `t_end`: the comparison is false).
    #[inline(always)]
    fn boundary_t(&self, axis: usize) -> f64 {
        boundary_t(
            self.origin_offset[axis],
            self.boundary[axis],
            self.cell_size,
            self.inv_direction[axis],
            self.t_end,
        )
    }

    /// The crossing of the current cell, then one step into the next cell along the axis
    /// whose boundary comes first (ties: the higher axis). Only called while
    /// `steps_left > 0`.
    ///
    /// The axis choice is a branch per comparison and every arm indexes the state with a
    /// constant, so once inlined the whole state lives in registers and branch prediction
    /// hides the latency of the `t` computation. The classic branch-free 8-entry lookup table
    /// was measured 2–3× slower: its dynamic axis index forces the state through memory.
    #[inline(always)]
    fn step(&mut self) -> CellCrossing<N> {
        let t = self.t_next;
        match N {
            2 => {
                if t[1] <= t[0] {
                    self.advance(1)
                } else {
                    self.advance(0)
                }
            }
            3 => {
                if t[0] < t[1] {
                    if t[0] < t[2] {
                        self.advance(0)
                    } else {
                        self.advance(2)
                    }
                } else if t[1] < t[2] {
                    self.advance(1)
                } else {
                    self.advance(2)
                }
            }
            _ => {
                let mut best = N - 1;
                for axis in (0..N).rev() {
                    if t[axis] < t[best] {
                        best = axis;
                    }
                }
                self.advance(best)
            }
        }
    }

    /// Yields the current cell and steps along `axis`.
    #[inline(always)]
    fn advance(&mut self, axis: usize) -> CellCrossing<N> {
        let t_boundary = self.t_next[axis];
        // Non-decreasing even if rounding puts a boundary before the current entry.
        let t_exit = if t_boundary > self.t_cur {
            t_boundary
        } else {
            self.t_cur
        };
        let crossing = CellCrossing {
            cell: self.cell,
            index: self.index,
            t_enter: self.t_cur,
            t_exit,
        };
        self.t_cur = t_exit;
        self.cell[axis] = self.cell[axis].wrapping_add(self.cell_step[axis]);
        self.index = self.index.wrapping_add(self.index_step[axis]);
        self.steps_left -= 1;
        self.remaining[axis] -= 1;
        self.boundary[axis] += self.boundary_step[axis];
        self.t_next[axis] = if self.remaining[axis] == 0 {
            f64::INFINITY
        } else {
            self.boundary_t(axis)
        };
        crossing
    }

    /// The crossing of the last cell, which ends at the segment end.
    #[inline(always)]
    fn finish(&mut self) -> CellCrossing<N> {
        self.finished = true;
        CellCrossing {
            cell: self.cell,
            index: self.index,
            t_enter: self.t_cur,
            t_exit: if self.t_end > self.t_cur {
                self.t_end
            } else {
                self.t_cur
            },
        }
    }
}

impl<const N: usize> Iterator for Traversal<N> {
    type Item = CellCrossing<N>;

    #[inline]
    fn next(&mut self) -> Option<CellCrossing<N>> {
        if self.steps_left > 0 {
            Some(self.step())
        } else if self.finished {
            None
        } else {
            Some(self.finish())
        }
    }

    #[inline]
    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = self.len();
        (n, Some(n))
    }

    #[inline]
    fn fold<B, F>(mut self, init: B, mut f: F) -> B
    where
        F: FnMut(B, CellCrossing<N>) -> B,
    {
        let mut acc = init;
        if self.finished {
            return acc;
        }
        while self.steps_left > 0 {
            acc = f(acc, self.step());
        }
        f(acc, self.finish())
    }
}

impl<const N: usize> ExactSizeIterator for Traversal<N> {
    #[inline]
    fn len(&self) -> usize {
        if self.finished {
            0
        } else {
            self.steps_left + 1
        }
    }
}

impl<const N: usize> std::iter::FusedIterator for Traversal<N> {}

impl<const N: usize> Default for Traversal<N> {
    fn default() -> Self {
        Self::empty()
    }
}
