//! Gauss–Newton and Levenberg–Marquardt on the sparse normal equations.
//!
//! Each iteration linearises every edge at the current poses (analytic Jacobians, see
//! [`se2`](super::se2)), weights its information by its robust kernel (iteratively reweighted
//! least squares), accumulates `H = Σ JᵀΩJ` and `b = Σ JᵀΩe` into the block-sparse pattern of
//! [`Structure`], factorises `H` (or `H + λI`) with faer's sparse Cholesky and solves
//! `H Δ = −b` (Grisetti et al. 2010, Sec. III; Kümmerle et al. 2011). The update is `x ← x + Δ`
//! on `(x, y, θ)` with θ wrapped.

use faer::dyn_stack::MemStack;
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use nalgebra::Matrix3;
use raypath_geometry::Pose2;

use super::config::{Method, SolverConfig};
use super::se2::{edge_error, error_and_jacobians};
use super::structure::{NONE, Structure};
use super::{Edge, EdgeKind, RobustKernel};
use crate::error::{Result, SlamError};

/// The kernels in force for one iteration: the configured ones widened by `mu`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Kernels {
    loop_closure: RobustKernel,
    sequential: RobustKernel,
}

impl Kernels {
    /// The configured kernels widened by `mu ≥ 1` (see [`Annealing`](super::Annealing)).
    pub fn new(config: &SolverConfig, mu: f64) -> Self {
        Self {
            loop_closure: config.loop_kernel.widened(mu),
            sequential: config.sequential_kernel.widened(mu),
        }
    }

    /// The kernel of an edge of `kind`.
    #[inline]
    fn of(&self, kind: EdgeKind) -> RobustKernel {
        match kind {
            EdgeKind::Loop => self.loop_closure,
            EdgeKind::Sequential => self.sequential,
        }
    }
}

/// Robust cost `Σ ρ(χ²)` and plain `Σ χ²`; with `scales`, also stores each edge's `√ρ'(χ²)`.
pub(super) fn evaluate(
    nodes: &[Pose2],
    edges: &[Edge],
    kernels: &Kernels,
    mut scales: Option<&mut [f64]>,
) -> (f64, f64) {
    let (mut cost, mut chi2_sum) = (0.0, 0.0);
    for (k, edge) in edges.iter().enumerate() {
        let e = edge_error(&nodes[edge.from], &nodes[edge.to], &edge.measurement);
        let chi2 = e.dot(&(edge.information * e));
        let kernel = kernels.of(edge.kind);
        cost += kernel.cost(chi2);
        chi2_sum += chi2;
        if let Some(scales) = scales.as_deref_mut() {
            scales[k] = kernel.weight(chi2).sqrt();
        }
    }
    (cost, chi2_sum)
}

/// The initial widening μ₀ of graduated non-convexity: the largest `χ²/width` over the edges
/// with a kernel, within `[1, max_start]`; 1 without annealing.
fn initial_widening(nodes: &[Pose2], edges: &[Edge], config: &SolverConfig) -> f64 {
    let Some(annealing) = config.annealing else {
        return 1.0;
    };
    let kernels = Kernels::new(config, 1.0);
    let mut mu: f64 = 1.0;
    for edge in edges {
        if let Some(width) = kernels.of(edge.kind).chi2_scale() {
            let e = edge_error(&nodes[edge.from], &nodes[edge.to], &edge.measurement);
            mu = mu.max(e.dot(&(edge.information * e)) / width);
        }
    }
    mu.min(annealing.max_start)
}

/// Adds the upper triangle of `m` to the diagonal block of block column `blk`.
#[inline]
fn add_diagonal(h: &mut [f64], col_ptr: &[usize], blk: usize, m: &Matrix3<f64>) {
    for c in 0..3 {
        // The last c + 1 entries of scalar column 3·blk + c are rows 3·blk … 3·blk + c.
        let start = col_ptr[3 * blk + c + 1] - (c + 1);
        for r in 0..=c {
            h[start + r] += m[(r, c)];
        }
    }
}

/// Adds `m` (rows of block `lo`, columns of block `hi > lo`) to the off-diagonal block, the
/// `rank`-th neighbour block of column `hi`.
#[inline]
fn add_off_diagonal(h: &mut [f64], col_ptr: &[usize], lo_rank: usize, hi: usize, m: &Matrix3<f64>) {
    for c in 0..3 {
        let start = col_ptr[3 * hi + c] + 3 * lo_rank;
        for r in 0..3 {
            h[start + r] += m[(r, c)];
        }
    }
}

/// Accumulates `H` and `b` at the current poses; returns the robust cost there.
fn linearize(nodes: &[Pose2], edges: &[Edge], kernels: &Kernels, s: &mut Structure) -> f64 {
    s.h.fill(0.0);
    s.b.fill(0.0);
    let mut cost = 0.0;
    for (k, edge) in edges.iter().enumerate() {
        let (e, a, b) =
            error_and_jacobians(&nodes[edge.from], &nodes[edge.to], &edge.measurement, true);
        let chi2 = e.dot(&(edge.information * e));
        let kernel = kernels.of(edge.kind);
        cost += kernel.cost(chi2);
        let (fi, fj) = (s.free[edge.from], s.free[edge.to]);
        if fi == NONE && fj == NONE {
            continue;
        }
        // IRLS: the information weighted by ρ'(χ²) at the current poses.
        let omega = edge.information * kernel.weight(chi2);
        let omega_e = omega * e;
        let omega_a = omega * a;
        let omega_b = omega * b;
        if fi != NONE {
            let i = fi as usize;
            add_diagonal(&mut s.h, &s.col_ptr, i, &(a.transpose() * omega_a));
            add_gradient(&mut s.b, i, &(a.transpose() * omega_e));
        }
        if fj != NONE {
            let j = fj as usize;
            add_diagonal(&mut s.h, &s.col_ptr, j, &(b.transpose() * omega_b));
            add_gradient(&mut s.b, j, &(b.transpose() * omega_e));
        }
        let rank = s.edge_block[k];
        if rank != NONE {
            let rank = rank as usize;
            if fi < fj {
                let m = a.transpose() * omega_b; // H_ij
                add_off_diagonal(&mut s.h, &s.col_ptr, rank, fj as usize, &m);
            } else {
                let m = b.transpose() * omega_a; // H_ji = H_ijᵀ
                add_off_diagonal(&mut s.h, &s.col_ptr, rank, fi as usize, &m);
            }
        }
    }
    cost
}

#[inline]
fn add_gradient(b: &mut [f64], blk: usize, g: &nalgebra::Vector3<f64>) {
    b[3 * blk] += g.x;
    b[3 * blk + 1] += g.y;
    b[3 * blk + 2] += g.z;
}

/// Solves `(H + λI) Δ = −b` into `s.delta`. False when the matrix is not numerically
/// positive definite (or the step is not finite).
fn solve_step(s: &mut Structure, lambda: f64) -> bool {
    let Some(symbolic) = s.symbolic.as_ref() else {
        return true;
    };
    s.damped.copy_from_slice(&s.h);
    for &p in &s.diag_pos {
        s.damped[p] += lambda;
    }
    for (d, b) in s.delta.iter_mut().zip(&s.b) {
        *d = -b;
    }
    let pattern = SymbolicSparseColMatRef::new_checked(s.dim, s.dim, &s.col_ptr, None, &s.row_idx);
    let matrix = SparseColMatRef::new(pattern, &s.damped);
    let llt = match symbolic.factorize_numeric_llt::<f64>(
        &mut s.l_values,
        matrix,
        Side::Upper,
        LltRegularization::default(),
        Par::Seq,
        MemStack::new(&mut s.mem),
        Default::default(),
    ) {
        Ok(llt) => llt,
        // The only error of the numeric factorisation: a non-positive pivot.
        Err(_) => return false,
    };
    let rhs = MatMut::from_column_major_slice_mut(&mut s.delta, s.dim, 1);
    llt.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, MemStack::new(&mut s.mem));
    s.delta.iter().all(|d| d.is_finite())
}

/// `x ← x ⊞ Δ`: plain addition on `(x, y, θ)`, θ wrapped by the pose's unit complex number.
fn apply_step(nodes: &mut [Pose2], s: &Structure) {
    for (pose, &f) in nodes.iter_mut().zip(&s.free) {
        if f != NONE {
            let d = &s.delta[3 * f as usize..3 * f as usize + 3];
            *pose = Pose2::new(pose.x() + d[0], pose.y() + d[1], pose.theta() + d[2]);
        }
    }
}

/// A step whose largest component is below this (metres, radians) ends the iterations:
/// near an exactly consistent graph the cost tends to 0 and its relative decrease stays large
/// (the step test of Madsen, Nielsen & Tingleff 2004, Sec. 3.2, with an absolute tolerance).
const STEP_TOLERANCE: f64 = 1e-10;

/// The largest component of the last step Δ.
fn step_norm(s: &Structure) -> f64 {
    s.delta.iter().fold(0.0, |m, d| m.max(d.abs()))
}

/// The outcome of the iterations: (iterations, converged).
pub(super) type Outcome = (usize, bool);

/// Gauss–Newton or Levenberg–Marquardt (by `config.method`) from the current poses.
pub(super) fn run(
    nodes: &mut [Pose2],
    edges: &[Edge],
    config: &SolverConfig,
    s: &mut Structure,
) -> Result<Outcome> {
    let factor = config.annealing.map_or(1.0, |a| a.factor);
    let mut mu = initial_widening(nodes, edges, config);
    let mut lm = LmState {
        lambda: f64::NAN,
        nu: 2.0,
    };
    for iteration in 0..config.max_iterations {
        let kernels = Kernels::new(config, mu);
        let cost = linearize(nodes, edges, &kernels, s);
        let new_cost = match config.method {
            Method::GaussNewton => gauss_newton_step(nodes, edges, &kernels, s, iteration)?,
            Method::LevenbergMarquardt => lm.step(nodes, edges, &kernels, s, cost, config),
        };
        let annealing = mu > 1.0;
        mu = (mu / factor).max(1.0);
        if annealing {
            continue;
        }
        match new_cost {
            // No damped step lowers the cost: a minimum to working precision.
            None => return Ok((iteration + 1, true)),
            Some(new_cost)
                if (cost - new_cost).abs() <= config.tolerance * cost
                    || step_norm(s) <= STEP_TOLERANCE =>
            {
                return Ok((iteration + 1, true));
            }
            Some(_) => {}
        }
    }
    Ok((config.max_iterations, false))
}

/// One Gauss–Newton step on the linearised system; returns the new cost.
fn gauss_newton_step(
    nodes: &mut [Pose2],
    edges: &[Edge],
    kernels: &Kernels,
    s: &mut Structure,
    iteration: usize,
) -> Result<Option<f64>> {
    if !solve_step(s, 0.0) {
        return Err(SlamError::Solver(format!(
            "Gauss–Newton iteration {iteration}: H is not positive definite (an unobservable \
             degree of freedom, e.g. zero information); use Levenberg–Marquardt"
        )));
    }
    apply_step(nodes, s);
    let (new_cost, _) = evaluate(nodes, edges, kernels, None);
    if !new_cost.is_finite() {
        return Err(SlamError::Solver(format!(
            "Gauss–Newton iteration {iteration}: the cost became {new_cost}"
        )));
    }
    Ok(Some(new_cost))
}

/// Levenberg–Marquardt's damping λ and its growth factor ν.
struct LmState {
    lambda: f64,
    nu: f64,
}

impl LmState {
    /// Tries damped steps on the linearised system until one lowers `cost` (kept, new cost
    /// returned) or the retries run out (poses unchanged, `None`).
    fn step(
        &mut self,
        nodes: &mut [Pose2],
        edges: &[Edge],
        kernels: &Kernels,
        s: &mut Structure,
        cost: f64,
        config: &SolverConfig,
    ) -> Option<f64> {
        if self.lambda.is_nan() {
            let max_diagonal = s.diag_pos.iter().map(|&p| s.h[p]).fold(0.0, f64::max);
            self.lambda = config.lm_tau
                * if max_diagonal > 0.0 {
                    max_diagonal
                } else {
                    1.0
                };
        }
        for _ in 0..=config.lm_max_retries {
            if !solve_step(s, self.lambda) {
                self.reject();
                continue;
            }
            // Decrease predicted by the quadratic model: Δᵀ(λΔ − b) (cost without the ½).
            let predicted: f64 = s
                .delta
                .iter()
                .zip(&s.b)
                .map(|(d, b)| d * (self.lambda * d - b))
                .sum();
            if predicted.is_nan() || predicted <= 1e-12 * cost {
                // The model promises no decrease to working precision: a minimum (retrying
                // with more damping would only shrink the step further).
                return None;
            }
            s.backup.clear();
            s.backup.extend_from_slice(nodes);
            apply_step(nodes, s);
            let (trial, _) = evaluate(nodes, edges, kernels, None);
            let rho = (cost - trial) / predicted;
            if trial.is_finite() && predicted > 0.0 && rho > 0.0 {
                // Nielsen's update (Madsen, Nielsen & Tingleff 2004, Sec. 3.2).
                self.lambda *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
                self.nu = 2.0;
                return Some(trial);
            }
            nodes.copy_from_slice(&s.backup);
            self.reject();
        }
        None
    }

    fn reject(&mut self) {
        self.lambda *= self.nu;
        self.nu *= 2.0;
    }
}
