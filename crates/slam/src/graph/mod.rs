//! Sparse SE(2) pose graph: nodes are robot poses, edges relative-pose constraints with an
//! information matrix; [`PoseGraph::optimize`] finds the poses that minimise
//! `Σ ρ(eᵀ Ω e)` over the edges.
//!
//! The edge error is `e = t2v(Z⁻¹ · (X_i⁻¹ X_j))` with analytic Jacobians (Grisetti et al.
//! 2010), the normal equations are assembled block-sparse and solved with faer's sparse
//! Cholesky factorisation, by Gauss–Newton or Levenberg–Marquardt, and robust kernels
//! (Huber, Cauchy, dynamic covariance scaling of Agarwal et al. 2013) are applied by
//! iteratively reweighted least squares — by default DCS on loop-closure edges only, so that a
//! wrong loop closure loses its weight instead of bending the map. The kernels start wide and
//! narrow over the first iterations (graduated non-convexity, Yang et al. 2020; see
//! [`Annealing`]): without that, a *correct* loop closure far from a drifted initial guess
//! would be rejected along with the wrong ones.
//!
//! The sparsity pattern of the normal equations, faer's symbolic factorisation (AMD ordering)
//! and all buffers are built once and reused by every iteration and by later `optimize` calls
//! until a node or edge is added or a fixed flag changes; an iteration allocates nothing.
//!
//! ```
//! use nalgebra::Matrix3;
//! use raypath_geometry::Pose2;
//! use raypath_slam::graph::{Edge, EdgeKind, PoseGraph, SolverConfig};
//!
//! // Three poses along x, odometry says 1 m steps, the initial guess is off.
//! let mut graph = PoseGraph::new();
//! let a = graph.add_node(Pose2::identity()); // node 0 is held fixed
//! let b = graph.add_node(Pose2::new(1.2, 0.1, 0.05));
//! let c = graph.add_node(Pose2::new(1.9, -0.2, 0.0));
//! let info = Matrix3::from_diagonal_element(100.0);
//! for (from, to) in [(a, b), (b, c)] {
//!     let measurement = Pose2::new(1.0, 0.0, 0.0);
//!     graph.add_edge(Edge { from, to, measurement, information: info, kind: EdgeKind::Sequential })?;
//! }
//! let report = graph.optimize(&SolverConfig::default())?;
//! assert!(report.converged && report.final_chi2 < 1e-12);
//! assert!((graph.nodes()[c].x() - 2.0).abs() < 1e-6);
//! # Ok::<(), raypath_slam::SlamError>(())
//! ```

mod config;
mod robust;
mod se2;
mod solver;
mod structure;
#[cfg(test)]
mod tests;

use std::time::Instant;

use nalgebra::{Matrix3, Vector3};
use raypath_geometry::Pose2;
use serde::{Deserialize, Serialize};

pub use config::{Method, SolveReport, SolverConfig};
pub use robust::{Annealing, RobustKernel};

use crate::error::{Result, SlamError};
use structure::Structure;

/// Which kind of constraint an edge is; robust kernels are chosen per kind
/// ([`SolverConfig::loop_kernel`], [`SolverConfig::sequential_kernel`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum EdgeKind {
    /// Between consecutive poses (odometry, scan matching against the local submap).
    Sequential,
    /// A loop closure; it may be wrong (perceptual aliasing).
    Loop,
}

/// A relative-pose constraint between two nodes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Edge {
    /// Index of the node the measurement is expressed in.
    pub from: usize,
    /// Index of the other node.
    pub to: usize,
    /// The measured `from_from_to = X_from⁻¹ · X_to`: the pose of `to` in `from`'s frame.
    pub measurement: Pose2,
    /// Information matrix (inverse covariance) over `(x, y, θ)` of the measurement, in
    /// `from`'s frame (1/m², 1/(m·rad), 1/rad²). Symmetric positive semi-definite.
    pub information: Matrix3<f64>,
    /// Sequential or loop closure.
    pub kind: EdgeKind,
}

/// The solver's cached pattern, symbolic factorisation and buffers; dropped on clone.
#[derive(Default)]
struct SolverCache(Option<Structure>);

impl Clone for SolverCache {
    fn clone(&self) -> Self {
        Self(None)
    }
}

impl std::fmt::Debug for SolverCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(if self.0.is_some() {
            "SolverCache(built)"
        } else {
            "SolverCache(empty)"
        })
    }
}

/// A graph of SE(2) poses and relative-pose constraints.
///
/// Node 0 is held fixed when it is added (it fixes the gauge); more nodes can be fixed with
/// [`set_fixed`](Self::set_fixed). A connected part of the graph without any fixed node is
/// anchored at its lowest-index node during optimisation.
#[derive(Clone, Debug, Default)]
pub struct PoseGraph {
    nodes: Vec<Pose2>,
    fixed: Vec<bool>,
    edges: Vec<Edge>,
    /// Per edge, `√ρ'(χ²)` at the end of the last optimisation.
    scales: Vec<f64>,
    /// Bumped whenever the sparsity pattern may change (nodes, edges, fixed flags).
    version: u64,
    cache: SolverCache,
}

impl PoseGraph {
    /// An empty graph.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a node at `pose` (the initial guess) and returns its index. Node 0 is held fixed.
    /// A non-finite pose is reported by [`optimize`](Self::optimize).
    pub fn add_node(&mut self, pose: Pose2) -> usize {
        let index = self.nodes.len();
        self.nodes.push(pose);
        self.fixed.push(index == 0);
        self.version += 1;
        index
    }

    /// Holds node `node` fixed (or frees it).
    ///
    /// # Panics
    /// When `node` is not a node index (a programming error, like slice indexing).
    pub fn set_fixed(&mut self, node: usize, fixed: bool) {
        if self.fixed[node] != fixed {
            self.fixed[node] = fixed;
            self.version += 1;
        }
    }

    /// True when node `node` is held fixed.
    ///
    /// # Panics
    /// When `node` is not a node index.
    pub fn is_fixed(&self, node: usize) -> bool {
        self.fixed[node]
    }

    /// Adds a constraint and returns its index.
    ///
    /// Errors with [`SlamError::BadInput`] when an end is not a node, both ends are the same
    /// node, the measurement or information is not finite, or the information is not
    /// symmetric positive semi-definite.
    pub fn add_edge(&mut self, edge: Edge) -> Result<usize> {
        let index = self.edges.len();
        validate_edge(&edge, index, self.nodes.len())?;
        self.edges.push(edge);
        self.scales.push(1.0);
        self.version += 1;
        Ok(index)
    }

    /// Switches edge `e` off: its information becomes zero, so it no longer acts on the
    /// poses, while the graph keeps its sparsity pattern (the cached factorisation stays
    /// valid). Used to take rejected loop closures out before the final optimisation.
    ///
    /// # Panics
    /// When `e` is not an edge index.
    pub fn switch_off(&mut self, e: usize) {
        self.edges[e].information = Matrix3::zeros();
    }

    /// The poses, indexed by node.
    pub fn nodes(&self) -> &[Pose2] {
        &self.nodes
    }

    /// Replaces the pose of node `i` (a new initial guess; the cached structure is kept).
    ///
    /// # Panics
    /// When `i` is not a node index.
    pub fn set_node(&mut self, i: usize, pose: Pose2) {
        self.nodes[i] = pose;
    }

    /// The edges, indexed by edge.
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// The error vector `t2v(Z⁻¹ · (X_from⁻¹ X_to))` of edge `e` at the current poses
    /// (metres, metres, radians in `(-π, π]`, in the measurement's frame).
    ///
    /// # Panics
    /// When `e` is not an edge index.
    pub fn edge_residual(&self, e: usize) -> Vector3<f64> {
        let edge = &self.edges[e];
        se2::edge_error(
            &self.nodes[edge.from],
            &self.nodes[edge.to],
            &edge.measurement,
        )
    }

    /// `eᵀ Ω e` of edge `e` at the current poses, without any robust kernel.
    ///
    /// # Panics
    /// When `e` is not an edge index.
    pub fn edge_chi2(&self, e: usize) -> f64 {
        let r = self.edge_residual(e);
        r.dot(&(self.edges[e].information * r))
    }

    /// The robust scale `s = √ρ'(χ²)` of edge `e` at the end of the last
    /// [`optimize`](Self::optimize): its information was weighted by `s²`. For DCS this is
    /// the `s` of Agarwal et al. 2013; 1 = full trust (also before any optimisation).
    ///
    /// # Panics
    /// When `e` is not an edge index.
    pub fn edge_weight(&self, e: usize) -> f64 {
        self.scales[e]
    }

    /// `Σ eᵀ Ω e` over all edges at the current poses.
    pub fn chi2(&self) -> f64 {
        (0..self.edges.len()).map(|e| self.edge_chi2(e)).sum()
    }

    /// Moves the free nodes to minimise `Σ ρ(eᵀΩe)` (see the module docs).
    ///
    /// The sparsity pattern and the symbolic factorisation are cached and reused while no
    /// node or edge is added and no fixed flag changes. Errors: [`SlamError::InvalidParameter`]
    /// for a bad `config`, [`SlamError::BadInput`] for a non-finite pose,
    /// [`SlamError::Solver`] when Gauss–Newton meets a singular system (poses are left at the
    /// last iterate).
    pub fn optimize(&mut self, config: &SolverConfig) -> Result<SolveReport> {
        let start = Instant::now();
        config.validate()?;
        if let Some(i) = self.nodes.iter().position(|p| !p.is_finite()) {
            return Err(SlamError::BadInput(format!(
                "pose graph: node {i} has a non-finite pose {:?}",
                self.nodes[i]
            )));
        }
        let final_kernels = solver::Kernels::new(config, 1.0);
        let (initial_cost, initial_chi2) =
            solver::evaluate(&self.nodes, &self.edges, &final_kernels, None);
        let mut structure = match self.cache.0.take() {
            Some(s) if s.version == self.version => s,
            _ => Structure::build(self.version, &self.fixed, &self.edges)?,
        };
        let outcome = if structure.dim == 0 {
            Ok((0, true))
        } else {
            solver::run(&mut self.nodes, &self.edges, config, &mut structure)
        };
        self.cache.0 = Some(structure);
        let (final_cost, final_chi2) = solver::evaluate(
            &self.nodes,
            &self.edges,
            &final_kernels,
            Some(&mut self.scales),
        );
        let (iterations, converged) = outcome?;
        Ok(SolveReport {
            iterations,
            initial_chi2,
            final_chi2,
            initial_cost,
            final_cost,
            converged,
            seconds: start.elapsed().as_secs_f64(),
        })
    }
}

/// Checks an edge before it enters the graph of `n_nodes` nodes (it would be edge `index`).
fn validate_edge(edge: &Edge, index: usize, n_nodes: usize) -> Result<()> {
    let bad = |reason: String| {
        Err(SlamError::BadInput(format!(
            "pose graph edge {index}: {reason}"
        )))
    };
    for end in [edge.from, edge.to] {
        if end >= n_nodes {
            return bad(format!(
                "node {end} does not exist (the graph has {n_nodes} nodes)"
            ));
        }
    }
    if edge.from == edge.to {
        return bad(format!("both ends are node {}", edge.from));
    }
    if !edge.measurement.is_finite() {
        return bad(format!("non-finite measurement {:?}", edge.measurement));
    }
    let info = &edge.information;
    if !info.iter().all(|v| v.is_finite()) {
        return bad(format!("non-finite information {info:?}"));
    }
    let scale = info.amax();
    if (info - info.transpose()).amax() > 1e-9 * scale {
        return bad(format!("information is not symmetric: {info:?}"));
    }
    let min_eigenvalue = info.symmetric_eigenvalues().min();
    if min_eigenvalue < -1e-12 * scale {
        return bad(format!(
            "information is not positive semi-definite (eigenvalue {min_eigenvalue}): {info:?}"
        ));
    }
    Ok(())
}
