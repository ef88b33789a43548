//! Final polishing (ours): after the last optimisation of the node graph, every scan — not
//! only the nodes — is aligned by point-to-line ICP ([`raypath_geometry::LineTarget`]) to the next
//! [`PolishConfig::neighbours`] scans, each node's scan also to the scans of nodes that
//! revisit its place ([`PolishConfig::revisits`]), and one pose graph over all scans is
//! solved: the node graph's own edges (sequential, intra-submap, the accepted loop closures),
//! each non-node scan tied to its node by the front-end's relative pose, and the ICP edges
//! (the revisits' under the loop edges' robust kernel).
//!
//! Why: the front-end matches each scan against a submap grid of 5 cm cells, and the scans
//! between nodes are placed by that match alone; the relations of the SLAM benchmark
//! (Kümmerle et al. 2009) were made by aligning scan pairs and are checked at the centimetre
//! level. An ICP edge between two raw scans measures their relative pose without a grid's
//! quantisation, while the node graph's edges keep the map's global shape (loop closures).
//!
//! The information of an ICP edge is its mean per-correspondence information (the
//! Cauchy-weighted Jacobians of the point-to-line residuals, divided by their weight) times
//! [`PolishConfig::effective_points`] over [`PolishConfig::point_sigma_m`]²: an alignment
//! along a featureless corridor has (almost) no information along it, so the front-end's
//! edges decide there. Alignments that move the relative pose farther than
//! [`PolishConfig::max_correction`] are dropped (the ICP left its basin).

use nalgebra::Matrix3;
use rayon::prelude::*;
use raypath_geometry::{LineIcp, LineTarget, Pose2};

use crate::error::{Result, SlamError, require_positive};
use crate::graph::{Edge, EdgeKind, PoseGraph, SolverConfig};
use crate::output::ScanPose;

/// Settings of the polishing stage ([`crate::SlamConfig::polish`], off by default); the
/// defaults are ours, chosen on the Intel and MIT CSAIL logs' relation files (fr079 held out).
#[derive(Clone, Debug, PartialEq)]
pub struct PolishConfig {
    /// Each scan is aligned to this many following scans. Default 1: in our runs on Intel and
    /// MIT CSAIL, 2 lowered the relation-file errors a little further at twice the
    /// alignments; 1 keeps the stage cheap.
    pub neighbours: usize,
    /// Correspondence gates of the ICP stages, metres, narrowing. Default 0.15, 0.05 (the
    /// optimised poses are within centimetres of each other's alignment).
    pub gates_m: Vec<f64>,
    /// Gauss–Newton iterations per gate at most. Default 6.
    pub iterations: usize,
    /// Scale of the Cauchy weights of the point-to-line residuals, metres. Default 0.02 (the
    /// benchmark logs' range resolution is 1 cm).
    pub kernel_m: f64,
    /// Neighbours within this radius fit a target point's line, metres. Default 0.3.
    pub normal_radius_m: f64,
    /// σ of one point-to-line residual, metres. Default 0.01.
    pub point_sigma_m: f64,
    /// Number of independent correspondences an alignment counts as (its residuals are
    /// correlated: the same walls, the same range bias). Default 4.
    pub effective_points: f64,
    /// Alignments that move the relative pose by more than this translation (m) or angle
    /// (rad) are dropped. Default 0.1 m, 2°.
    pub max_correction: (f64, f64),
    /// Points farther from the sensor than this are left out of the alignment, metres.
    /// Default 15 m.
    pub max_range_m: f64,
    /// Each node's scan is also aligned to this many other nodes' scans near it in space but
    /// not in time (revisits: the loop relations of the benchmark), the nearest first.
    /// Default 2 (0: none).
    pub revisits: usize,
    /// A revisit lies within this distance of the node at the optimised poses, metres.
    /// Default 1 m.
    pub revisit_radius_m: f64,
    /// … and at least this many nodes away from it. Default 30.
    pub revisit_min_node_gap: usize,
    /// Iterations of the final solve at most (it starts at the optimised node graph's poses,
    /// near its optimum; the robust kernels are applied without annealing, the rejected loop
    /// closures being out already). Default 8.
    pub solver_iterations: usize,
}

impl Default for PolishConfig {
    fn default() -> Self {
        Self {
            neighbours: 1,
            gates_m: vec![0.15, 0.05],
            iterations: 6,
            kernel_m: 0.02,
            normal_radius_m: 0.3,
            point_sigma_m: 0.01,
            effective_points: 4.0,
            max_correction: (0.1, 2f64.to_radians()),
            max_range_m: 15.0,
            revisits: 2,
            revisit_radius_m: 1.0,
            revisit_min_node_gap: 30,
            solver_iterations: 8,
        }
    }
}

impl PolishConfig {
    /// The ICP iteration settings of these.
    pub(crate) fn icp(&self) -> LineIcp<'_> {
        LineIcp {
            gates_m: &self.gates_m,
            iterations: self.iterations,
            kernel_m: self.kernel_m,
        }
    }

    /// Checks the settings (errors name the field).
    pub fn validate(&self) -> Result<()> {
        if self.neighbours == 0
            || self.iterations == 0
            || self.gates_m.is_empty()
            || self.solver_iterations == 0
        {
            return Err(SlamError::InvalidParameter {
                name: "polish.neighbours / iterations / gates_m / solver_iterations",
                reason: "at least one neighbour, one iteration, one gate and one solver iteration"
                    .into(),
            });
        }
        for &gate in &self.gates_m {
            require_positive("polish.gates_m", gate)?;
        }
        for (name, v) in [
            ("polish.kernel_m", self.kernel_m),
            ("polish.normal_radius_m", self.normal_radius_m),
            ("polish.point_sigma_m", self.point_sigma_m),
            ("polish.effective_points", self.effective_points),
            ("polish.max_correction.0", self.max_correction.0),
            ("polish.max_correction.1", self.max_correction.1),
            ("polish.max_range_m", self.max_range_m),
            ("polish.revisit_radius_m", self.revisit_radius_m),
        ] {
            require_positive(name, v)?;
        }
        Ok(())
    }
}

/// A measured relative pose between scans `from` and `to` (`from_from_to`) with its
/// information.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ScanEdge {
    pub from: usize,
    pub to: usize,
    pub measurement: Pose2,
    pub information: Matrix3<f64>,
}

/// ICP edges between every scan and its next [`PolishConfig::neighbours`] scans, started at
/// the relative poses of `poses` (`world_from_sensor` per scan; `points[k]` are scan `k`'s
/// points in its sensor frame). Pairs that fail or move too far give no edge.
pub(crate) fn icp_edges(
    poses: &[Pose2],
    points: &[Vec<[f64; 2]>],
    config: &PolishConfig,
) -> Vec<ScanEdge> {
    let n = poses.len().min(points.len());
    let near = |k: usize| within_range(&points[k], config.max_range_m);
    (0..n)
        .into_par_iter()
        .flat_map_iter(|k| {
            let target = LineTarget::new(&near(k), config.normal_radius_m);
            let last = (k + config.neighbours).min(n.saturating_sub(1));
            let edges: Vec<ScanEdge> = match target {
                Some(target) => (k + 1..=last)
                    .filter_map(|j| scan_edge(&target, k, j, &near(j), poses, config))
                    .collect(),
                None => Vec::new(),
            };
            edges
        })
        .collect()
}

/// The points within `range` of the sensor.
fn within_range(points: &[[f64; 2]], range: f64) -> Vec<[f64; 2]> {
    points
        .iter()
        .copied()
        .filter(|p| p[0] * p[0] + p[1] * p[1] <= range * range)
        .collect()
}

/// ICP edges from each node's scan (`node_scan`) to up to [`PolishConfig::revisits`] other
/// nodes' scans within [`PolishConfig::revisit_radius_m`] at `poses` and at least
/// [`PolishConfig::revisit_min_node_gap`] nodes earlier, the nearest first.
pub(crate) fn revisit_edges(
    poses: &[Pose2],
    points: &[Vec<[f64; 2]>],
    node_scan: &[usize],
    config: &PolishConfig,
) -> Vec<ScanEdge> {
    use kiddo::{ImmutableKdTree, SquaredEuclidean};
    if config.revisits == 0 {
        return Vec::new();
    }
    let scans: Vec<usize> = node_scan
        .iter()
        .copied()
        .filter(|&k| k < poses.len() && k < points.len())
        .collect();
    let positions: Vec<[f64; 2]> = scans
        .iter()
        .map(|&k| [poses[k].x(), poses[k].y()])
        .collect();
    let tree = ImmutableKdTree::new_from_slice(&positions);
    let r2 = config.revisit_radius_m * config.revisit_radius_m;
    (0..scans.len())
        .into_par_iter()
        .flat_map_iter(|a| {
            let mut near = tree.within::<SquaredEuclidean>(&positions[a], r2);
            near.retain(|m| (m.item as usize) + config.revisit_min_node_gap <= a);
            near.truncate(config.revisits);
            let i = scans[a];
            let target = match near.is_empty() {
                true => None,
                false => LineTarget::new(
                    &within_range(&points[i], config.max_range_m),
                    config.normal_radius_m,
                ),
            };
            let edges: Vec<ScanEdge> = match target {
                Some(target) => near
                    .iter()
                    .filter_map(|m| {
                        let j = scans[m.item as usize];
                        let source = within_range(&points[j], config.max_range_m);
                        scan_edge(&target, i, j, &source, poses, config)
                    })
                    .collect(),
                None => Vec::new(),
            };
            edges
        })
        .collect()
}

/// The ICP edge from scan `i` (the target) to scan `j` (its points `source`), when the
/// alignment succeeds within [`PolishConfig::max_correction`].
fn scan_edge(
    target: &LineTarget,
    i: usize,
    j: usize,
    source: &[[f64; 2]],
    poses: &[Pose2],
    config: &PolishConfig,
) -> Option<ScanEdge> {
    let start = poses[i].inverse() * poses[j];
    let a = target.align(source, start, &config.icp())?;
    let moved = start.inverse() * a.target_from_source;
    if moved.translation().norm() > config.max_correction.0
        || moved.theta().abs() > config.max_correction.1
    {
        return None;
    }
    // The ICP's information is in the target frame's left-increment coordinates; the graph's
    // edge error is the right increment of the measurement: Ω_right = Adᵀ Ω_left Ad.
    let ad = adjoint(&a.target_from_source);
    let scale = config.effective_points / (config.point_sigma_m * config.point_sigma_m);
    let information = ad.transpose() * (a.mean_information * scale) * ad;
    let information = 0.5 * (information + information.transpose());
    information
        .iter()
        .all(|v| v.is_finite())
        .then_some(ScanEdge {
            from: i,
            to: j,
            measurement: a.target_from_source,
            information,
        })
}

/// The adjoint of an SE(2) pose `T`: a right increment `ξ` equals the left increment
/// `Ad(T) ξ` (`T · exp(ξ) = exp(Ad(T) ξ) · T`), to first order.
fn adjoint(t: &Pose2) -> Matrix3<f64> {
    let (c, s) = (t.theta().cos(), t.theta().sin());
    Matrix3::new(c, -s, t.y(), s, c, -t.x(), 0.0, 0.0, 1.0)
}

/// The scans' node bookkeeping the polishing graph needs.
pub(crate) struct ScanNodes<'a> {
    /// Every scan, in order.
    pub scans: &'a [ScanPose],
    /// The scan index of each node.
    pub node_scan: &'a [usize],
    /// The front-end's local pose of each node.
    pub node_local: &'a [Pose2],
}

/// Polishes `poses` (`world_from_sensor` per scan, from the optimised node graph `graph`):
/// one pose graph over all scans with the node graph's edges (switched-off ones left out),
/// the front-end ties of the non-node scans (information `sequential`) and the ICP edges of
/// [`icp_edges`] and [`revisit_edges`] (the latter as loop edges, under the solver's robust
/// kernel), solved with `solver`. Returns the polished poses and the number of ICP
/// edges.
pub(crate) fn polish(
    poses: &[Pose2],
    points: &[Vec<[f64; 2]>],
    graph: &PoseGraph,
    nodes: &ScanNodes<'_>,
    sequential: &Matrix3<f64>,
    config: &PolishConfig,
    solver: &SolverConfig,
) -> Result<(Vec<Pose2>, usize)> {
    if poses.len() < 2 || points.len() != poses.len() {
        return Ok((poses.to_vec(), 0));
    }
    let edges = icp_edges(poses, points, config);
    let revisits = revisit_edges(poses, points, nodes.node_scan, config);
    let mut full = PoseGraph::new();
    for p in poses {
        full.add_node(*p);
    }
    for e in graph.edges() {
        if e.information.iter().all(|v| *v == 0.0) {
            continue;
        }
        let (Some(&from), Some(&to)) = (nodes.node_scan.get(e.from), nodes.node_scan.get(e.to))
        else {
            continue;
        };
        full.add_edge(Edge { from, to, ..*e })?;
    }
    for (k, s) in nodes.scans.iter().enumerate() {
        let (Some(&from), Some(local)) =
            (nodes.node_scan.get(s.node), nodes.node_local.get(s.node))
        else {
            continue;
        };
        if s.is_node || from == k {
            continue;
        }
        full.add_edge(Edge {
            from,
            to: k,
            measurement: local.inverse() * s.local,
            information: *sequential,
            kind: EdgeKind::Sequential,
        })?;
    }
    for e in &edges {
        full.add_edge(Edge {
            from: e.from,
            to: e.to,
            measurement: e.measurement,
            information: e.information,
            kind: EdgeKind::Sequential,
        })?;
    }
    for e in &revisits {
        full.add_edge(Edge {
            from: e.from,
            to: e.to,
            measurement: e.measurement,
            information: e.information,
            kind: EdgeKind::Loop,
        })?;
    }
    full.optimize(&SolverConfig {
        max_iterations: config.solver_iterations,
        annealing: None,
        ..*solver
    })?;
    Ok((full.nodes().to_vec(), edges.len() + revisits.len()))
}

#[cfg(test)]
mod tests;
