//! The block-sparse pattern of the normal equations and its symbolic Cholesky factorisation.
//!
//! The unknowns are the `(x, y, θ)` of the free nodes, one 3×3 block row and column each. The
//! upper triangle of `H` is stored column-major (compressed sparse columns): block column `b`
//! holds, for each free neighbour block `a < b` in increasing order, three rows `3a … 3a+2`,
//! then the upper triangle of its diagonal block. The pattern and faer's symbolic
//! factorisation (AMD ordering, simplicial or supernodal as faer chooses) depend only on the
//! edge set and the fixed nodes, so they are built once and reused by every iteration and by
//! later calls of `optimize` while the graph's structure is unchanged.

use faer::dyn_stack::{MemBuffer, StackReq};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::cholesky::{
    SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::{Par, Side};
use raypath_geometry::Pose2;

use super::Edge;
use crate::error::{Result, SlamError};

/// Marks a fixed node (no unknowns) or an edge without an off-diagonal block.
pub(super) const NONE: u32 = u32::MAX;

/// The pattern, its symbolic factorisation and every buffer one iteration needs.
pub(super) struct Structure {
    /// The graph's structure version this was built for.
    pub version: u64,
    /// Per node: its block index among the unknowns, or [`NONE`] when it is held fixed.
    pub free: Vec<u32>,
    /// Number of scalar unknowns (3 per free node).
    pub dim: usize,
    /// Column pointers of the upper triangle of `H` (length `dim + 1`).
    pub col_ptr: Vec<usize>,
    /// Row indices of the upper triangle of `H`, sorted within each column.
    pub row_idx: Vec<usize>,
    /// Position of each column's diagonal entry in the value array.
    pub diag_pos: Vec<usize>,
    /// Per edge: the rank of the lower block among the upper block's neighbours (the place of
    /// the edge's off-diagonal block), or [`NONE`] when an end is fixed.
    pub edge_block: Vec<u32>,
    /// faer's symbolic Cholesky factorisation; `None` when there are no unknowns.
    pub symbolic: Option<SymbolicCholesky<usize>>,
    /// Values of `H` (upper triangle, same layout as `row_idx`).
    pub h: Vec<f64>,
    /// `H + λI`, the matrix factorised.
    pub damped: Vec<f64>,
    /// The gradient vector `b = Σ Jᵀ Ω e`.
    pub b: Vec<f64>,
    /// The step Δ (the right-hand side `−b` before the solve).
    pub delta: Vec<f64>,
    /// Values of the Cholesky factor.
    pub l_values: Vec<f64>,
    /// Scratch memory of the numeric factorisation and the triangular solves.
    pub mem: MemBuffer,
    /// The poses before a trial step (Levenberg–Marquardt restores them on rejection).
    pub backup: Vec<Pose2>,
}

impl Structure {
    /// Builds the pattern for `edges` over `fixed.len()` nodes. A connected component without
    /// a fixed node would leave the problem singular (gauge freedom), so its lowest-index node
    /// is held fixed too; a node without edges is such a component on its own.
    pub fn build(version: u64, fixed: &[bool], edges: &[Edge]) -> Result<Self> {
        let free = free_blocks(fixed, edges);
        let n_free = free.iter().filter(|&&f| f != NONE).count();
        let dim = 3 * n_free;
        let (blk_ptr, blk_rows) = block_adjacency(&free, edges, n_free);
        let (col_ptr, row_idx, diag_pos) = scalar_pattern(&blk_ptr, &blk_rows);
        let edge_block = edges
            .iter()
            .map(|e| {
                let (fi, fj) = (free[e.from], free[e.to]);
                if fi == NONE || fj == NONE {
                    return NONE;
                }
                let (lo, hi) = (fi.min(fj), fi.max(fj));
                let rows = &blk_rows[blk_ptr[hi as usize]..blk_ptr[hi as usize + 1]];
                rows.binary_search(&lo).map_or(NONE, |k| k as u32)
            })
            .collect();
        let symbolic = if dim == 0 {
            None
        } else {
            let pattern = SymbolicSparseColMatRef::new_checked(dim, dim, &col_ptr, None, &row_idx);
            let symbolic = factorize_symbolic_cholesky(
                pattern,
                Side::Upper,
                SymmetricOrdering::Amd,
                Default::default(),
            )
            .map_err(|e| SlamError::Solver(format!("symbolic Cholesky factorisation: {e:?}")))?;
            Some(symbolic)
        };
        let (l_len, scratch) = match &symbolic {
            Some(s) => (
                s.len_val(),
                StackReq::any_of(&[
                    s.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
                    s.solve_in_place_scratch::<f64>(1, Par::Seq),
                ]),
            ),
            None => (0, StackReq::EMPTY),
        };
        let mem = MemBuffer::try_new(scratch)
            .map_err(|_| SlamError::Solver("out of memory for the factorisation".into()))?;
        let nnz = row_idx.len();
        Ok(Self {
            version,
            free,
            dim,
            col_ptr,
            row_idx,
            diag_pos,
            edge_block,
            symbolic,
            h: vec![0.0; nnz],
            damped: vec![0.0; nnz],
            b: vec![0.0; dim],
            delta: vec![0.0; dim],
            l_values: vec![0.0; l_len],
            mem,
            backup: Vec::with_capacity(fixed.len()),
        })
    }
}

/// Per node its block index, or [`NONE`] for fixed nodes and the anchor of every connected
/// component that has no fixed node.
fn free_blocks(fixed: &[bool], edges: &[Edge]) -> Vec<u32> {
    let n = fixed.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for e in edges {
        let (a, b) = (find(&mut parent, e.from), find(&mut parent, e.to));
        if a != b {
            // The smaller index becomes the root, so a root is its component's lowest node.
            parent[a.max(b)] = a.min(b);
        }
    }
    let mut anchored = vec![true; n];
    for (i, _) in fixed.iter().enumerate().filter(|(_, f)| **f) {
        let root = find(&mut parent, i);
        anchored[root] = false;
    }
    let mut free = vec![NONE; n];
    let mut next = 0u32;
    for (i, (&is_fixed, slot)) in fixed.iter().zip(free.iter_mut()).enumerate() {
        let root = find(&mut parent, i);
        let anchor = root == i && anchored[root];
        if !is_fixed && !anchor {
            *slot = next;
            next += 1;
        }
    }
    free
}

/// The distinct block pairs `(a, b)`, `a < b`, grouped by `b`: `blk_rows[blk_ptr[b]..blk_ptr[b+1]]`
/// are the sorted `a`.
fn block_adjacency(free: &[u32], edges: &[Edge], n_free: usize) -> (Vec<usize>, Vec<u32>) {
    let mut pairs: Vec<(u32, u32)> = edges
        .iter()
        .filter_map(|e| {
            let (fi, fj) = (free[e.from], free[e.to]);
            (fi != NONE && fj != NONE && fi != fj).then(|| (fi.max(fj), fi.min(fj)))
        })
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    let mut blk_ptr = vec![0usize; n_free + 1];
    for &(b, _) in &pairs {
        blk_ptr[b as usize + 1] += 1;
    }
    for b in 0..n_free {
        blk_ptr[b + 1] += blk_ptr[b];
    }
    (blk_ptr, pairs.into_iter().map(|(_, a)| a).collect())
}

/// Scalar column pointers, row indices and diagonal positions of the upper triangle.
fn scalar_pattern(blk_ptr: &[usize], blk_rows: &[u32]) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let n_free = blk_ptr.len() - 1;
    let nnz = 9 * blk_rows.len() + 6 * n_free;
    let mut col_ptr = Vec::with_capacity(3 * n_free + 1);
    let mut row_idx = Vec::with_capacity(nnz);
    let mut diag_pos = Vec::with_capacity(3 * n_free);
    col_ptr.push(0);
    for b in 0..n_free {
        let neighbours = &blk_rows[blk_ptr[b]..blk_ptr[b + 1]];
        for c in 0..3 {
            for &a in neighbours {
                let a = 3 * a as usize;
                row_idx.extend_from_slice(&[a, a + 1, a + 2]);
            }
            row_idx.extend((0..=c).map(|r| 3 * b + r));
            diag_pos.push(row_idx.len() - 1);
            col_ptr.push(row_idx.len());
        }
    }
    (col_ptr, row_idx, diag_pos)
}
