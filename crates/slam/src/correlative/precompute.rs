//! The precomputed max-pooled grids of one submap (Hess et al. 2016 §V.C).
//!
//! Level `h` holds, for every cell `(x, y)` a window may start at,
//! `M_precomp^h(x, y) = max { M(x', y') : x' ∈ [x, x + 2^h), y' ∈ [y, y + 2^h) }` (Hess
//! §V.C), with `M = 0` outside the grid. A branch-and-bound node of height `h` covers the
//! `2^h × 2^h` translations starting at its corner, so the sum of level-`h` values at the
//! scan's cells bounds every score below it (Hess §V.C). Windows may start up to
//! `2^h − 1` cells left of / below the grid, so level `h` is padded by that much on the low
//! sides. Each level is computed from the original grid by the `O(n)` sliding-window maximum
//! of van Herk (1992) and Gil & Werman (1993), per row, then per column.

use super::grid::ProbabilityGrid;

/// Largest number of levels kept (windows of up to 2¹⁵ cells).
pub const MAX_DEPTH: usize = 16;

/// Where one level lies in the shared storage.
#[derive(Clone, Copy, Debug, PartialEq)]
struct LevelLayout {
    offset: usize,
    width: usize,
    height: usize,
    /// `2^h − 1`: stored index `a` is the window starting at grid index `a − pad`.
    pad: usize,
}

/// A read-only view of one level for scoring.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LevelView<'a> {
    pub(crate) cells: &'a [u16],
    pub(crate) width: i64,
    pub(crate) height: i64,
    pub(crate) pad: i64,
}

/// The stack of max-pooled grids of one frozen submap: built once, reused by every query.
///
/// Values are the grid's 16-bit quantized probabilities, all levels in one contiguous
/// buffer (row-major per level).
#[derive(Clone, Debug)]
pub struct PrecomputedGrids {
    grid: ProbabilityGrid,
    layouts: Vec<LevelLayout>,
    cells: Vec<u16>,
}

impl PrecomputedGrids {
    /// Precomputes `depth` levels (`h = 0 … depth − 1`; Hess et al. use 7) of `grid`.
    /// `depth` is clamped to `1 ..= MAX_DEPTH`.
    pub fn new(grid: &ProbabilityGrid, depth: usize) -> Self {
        let depth = depth.clamp(1, MAX_DEPTH);
        let (w, h) = (grid.width(), grid.height());
        let mut layouts = Vec::with_capacity(depth);
        let mut total = 0;
        for level in 0..depth {
            let pad = (1usize << level) - 1;
            let layout = LevelLayout {
                offset: total,
                width: w + pad,
                height: h + pad,
                pad,
            };
            total += layout.width * layout.height;
            layouts.push(layout);
        }
        let mut cells = vec![0u16; total];
        let mut scratch = Scratch::default();
        for layout in &layouts {
            let end = layout.offset + layout.width * layout.height;
            if let Some(out) = cells.get_mut(layout.offset..end) {
                max_pool(grid, layout.pad + 1, out, &mut scratch);
            }
        }
        Self {
            grid: grid.clone(),
            layouts,
            cells,
        }
    }

    /// The grid the levels were computed from (level 0).
    pub fn grid(&self) -> &ProbabilityGrid {
        &self.grid
    }

    /// Number of levels.
    pub fn depth(&self) -> usize {
        self.layouts.len()
    }

    /// The value of level `h` for the `2^h × 2^h` window whose lower-left cell is `(i, j)`
    /// (grid indices, which may be negative down to `−(2^h − 1)`), as a probability; 0 where
    /// the window misses the grid or `h ≥ depth()`.
    pub fn max_value(&self, h: usize, i: i64, j: i64) -> f32 {
        self.view(h).map_or(0.0, |v| {
            let (a, b) = (i + v.pad, j + v.pad);
            if (0..v.width).contains(&a) && (0..v.height).contains(&b) {
                let q = v
                    .cells
                    .get((b * v.width + a) as usize)
                    .copied()
                    .unwrap_or(0);
                f32::from(q) / f32::from(super::grid::QUANT_MAX)
            } else {
                0.0
            }
        })
    }

    /// The view of level `h`, if it exists.
    pub(crate) fn view(&self, h: usize) -> Option<LevelView<'_>> {
        let l = self.layouts.get(h)?;
        Some(LevelView {
            cells: self.cells.get(l.offset..l.offset + l.width * l.height)?,
            width: l.width as i64,
            height: l.height as i64,
            pad: l.pad as i64,
        })
    }
}

/// Reused buffers of the sliding maximum.
#[derive(Default)]
struct Scratch {
    line: Vec<u16>,
    prefix: Vec<u16>,
    suffix: Vec<u16>,
    rows: Vec<u16>,
}

/// Writes into `out` (`(w + k − 1) × (h + k − 1)`, row-major) the maximum of `grid` over the
/// `k × k` window starting at each cell from `(−(k − 1), −(k − 1))`: rows first into a
/// `(w + k − 1) × h` buffer, then columns.
fn max_pool(grid: &ProbabilityGrid, k: usize, out: &mut [u16], s: &mut Scratch) {
    let (w, h) = (grid.width(), grid.height());
    if w == 0 || h == 0 {
        return; // nothing to pool: `out` stays 0
    }
    let pw = w + k - 1;
    s.rows.clear();
    s.rows.resize(pw * h, 0);
    for (row_in, row_out) in grid
        .cells()
        .chunks_exact(w)
        .zip(s.rows.chunks_exact_mut(pw))
    {
        s.line.clear();
        s.line.resize(k - 1, 0);
        s.line.extend_from_slice(row_in);
        s.line.resize(w + 2 * (k - 1), 0);
        sliding_max(&s.line, k, &mut s.prefix, &mut s.suffix, row_out);
    }
    sliding_max_rows(&s.rows, pw, k, &mut s.prefix, &mut s.suffix, out);
}

/// Sliding-window maximum of width `k` over `input` into `out` (length `n − k + 1`) in
/// `O(n)`, independent of `k` (van Herk 1992; Gil & Werman 1993): in blocks of `k`,
/// `g` = running max from each block's start, `f` = running max to each block's end, and
/// `max(input[s .. s + k]) = max(f[s], g[s + k − 1])`.
fn sliding_max(input: &[u16], k: usize, g: &mut Vec<u16>, f: &mut Vec<u16>, out: &mut [u16]) {
    g.clear();
    g.extend_from_slice(input);
    f.clear();
    f.extend_from_slice(input);
    for block in g.chunks_mut(k) {
        for i in 1..block.len() {
            block[i] = block[i].max(block[i - 1]);
        }
    }
    for block in f.chunks_mut(k) {
        for i in (0..block.len().saturating_sub(1)).rev() {
            block[i] = block[i].max(block[i + 1]);
        }
    }
    for (s, o) in out.iter_mut().enumerate() {
        *o = f[s].max(g[s + k - 1]);
    }
}

/// [`sliding_max`] down the columns of `input` (rows of `width`, zero-padded by `k − 1` rows
/// above and below), whole rows at a time so the inner loops run over contiguous memory.
/// `out` has `rows + k − 1` rows.
fn sliding_max_rows(
    input: &[u16],
    width: usize,
    k: usize,
    g: &mut Vec<u16>,
    f: &mut Vec<u16>,
    out: &mut [u16],
) {
    let n = input.len() / width + 2 * (k - 1);
    for buf in [&mut *g, &mut *f] {
        buf.clear();
        buf.resize((k - 1) * width, 0);
        buf.extend_from_slice(input);
        buf.resize(n * width, 0);
    }
    let block_len = k * width;
    for block in g.chunks_mut(block_len) {
        for r in 1..block.len() / width {
            let (done, rest) = block.split_at_mut(r * width);
            let prev = &done[(r - 1) * width..];
            for (x, &p) in rest[..width].iter_mut().zip(prev) {
                *x = (*x).max(p);
            }
        }
    }
    for block in f.chunks_mut(block_len) {
        for r in (0..(block.len() / width).saturating_sub(1)).rev() {
            let (head, next) = block.split_at_mut((r + 1) * width);
            for (x, &p) in head[r * width..].iter_mut().zip(&next[..width]) {
                *x = (*x).max(p);
            }
        }
    }
    for (s, row) in out.chunks_exact_mut(width).enumerate() {
        let (fs, gs) = (
            &f[s * width..(s + 1) * width],
            &g[(s + k - 1) * width..(s + k) * width],
        );
        for ((o, &a), &b) in row.iter_mut().zip(fs).zip(gs) {
            *o = a.max(b);
        }
    }
}
