//! Global consistency of loop closures (ours): a verified match enters the pose graph only
//! when it agrees with the loops already there, or — where no loop is near — with the graph's
//! estimate and with a second candidate.
//!
//! A loop candidate says "node `n` is at `Z` in the frame of anchor `a`". Its world pose of the
//! node is `Q = X_a · Z`. Two predictions of that pose are tested against it:
//!
//! * **pairwise** (as in PCM, Mangelson et al. 2018, reduced to the nearest reference): an
//!   accepted loop `r` near the candidate in travel predicts `P = X_{a_r} · Z_r · L_{n_r}⁻¹ ·
//!   L_n`, where `L` are the front-end's local poses (accurate over a short path) and `X` the
//!   graph's poses of the two anchors;
//! * **graph**: without such a reference, `P = X_n`, the graph's current estimate.
//!
//! The error `E = Q⁻¹ P` is scored as `χ² = (E_x² + E_y²)/σ_t² + E_θ²/σ_θ²` with
//! `σ_θ² = 2σ_{loop,θ}² + (δ_θ d)²`, `σ_t² = 2σ_{loop,t}² + (δ_t d)² + σ_θ² ℓ²`, where `d` is
//! the path over which the front-end's drift (`δ_t` per metre, `δ_θ` rad per metre) enters and
//! `ℓ` the lever over which a heading error moves the prediction. A candidate whose `χ²`
//! exceeds [`ConsistencyConfig::chi2_gate`] is rejected. Without a reference, a candidate that
//! passes the graph test is held until [`ConsistencyConfig::min_support`] other held
//! candidates agree with it pairwise; held candidates nobody agrees with are dropped after
//! [`ConsistencyConfig::hold_travel_m`]. The graph test loses its power when `d` is large (the
//! first loop after a long excursion): then only the support of a second candidate and the
//! robust back-end stand between a wrong match and the map.

use raypath_geometry::{Pose2, wrap_angle};
use serde::{Deserialize, Serialize};

use crate::error::{Result, SlamError, require_positive};
use crate::graph::PoseGraph;

/// Parameters of the loop consistency test (see the module docs). Defaults are ours, chosen on
/// the raw Intel and MIT CSAIL logs and the simulated tests (`tests/robustness.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConsistencyConfig {
    /// A candidate whose χ² (3 degrees of freedom) exceeds this is rejected. Default 16.27,
    /// the 99.9 % quantile of χ²₃.
    pub chi2_gate: f64,
    /// σ of one loop measurement in this test: `(metres, radians)`. Default (0.15 m, 2°): the
    /// loop search refuses matches ambiguous by 0.3 m or 3°, so a right one is within about
    /// that of the truth.
    pub loop_sigma: [f64; 2],
    /// The front-end's drift per metre of path: `(fraction of the path, radians per metre)`.
    /// Default (0.02, 0.005): 2 % is the loop search's own growth of its window
    /// ([`crate::LoopSearchConfig::radius_growth`]); 0.005 rad/m (0.3°/m) is ours.
    pub drift: [f64; 2],
    /// Accepted loops whose node and anchor are together at most this far (along the path)
    /// from the candidate's are its references, metres. Default 20 m (ours).
    pub reference_travel_m: f64,
    /// A candidate without a reference enters the graph once this many held candidates agree
    /// with it (they enter with it); 0 lets it enter at once. Default 1 (ours).
    pub min_support: usize,
    /// Held candidates are dropped after the front-end has travelled this far past their node,
    /// metres. Default 5 m (ours; the loop search runs every 0.75 m of path).
    pub hold_travel_m: f64,
}

impl Default for ConsistencyConfig {
    fn default() -> Self {
        Self {
            chi2_gate: 16.27,
            loop_sigma: [0.15, 2f64.to_radians()],
            drift: [0.02, 0.005],
            reference_travel_m: 20.0,
            min_support: 1,
            hold_travel_m: 5.0,
        }
    }
}

impl ConsistencyConfig {
    /// Checks the parameters (errors name the field).
    pub fn validate(&self) -> Result<()> {
        require_positive("consistency.chi2_gate", self.chi2_gate)?;
        for v in self.loop_sigma {
            require_positive("consistency.loop_sigma", v)?;
        }
        for v in self.drift {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(SlamError::InvalidParameter {
                    name: "consistency.drift",
                    reason: format!("must be finite and ≥ 0, got {v}"),
                });
            }
        }
        require_positive("consistency.reference_travel_m", self.reference_travel_m)?;
        require_positive("consistency.hold_travel_m", self.hold_travel_m)?;
        Ok(())
    }
}

/// Counters of the consistency test.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ConsistencyStats {
    /// Candidates tested.
    pub checked: usize,
    /// Rejected against an accepted loop.
    pub rejected_pairwise: usize,
    /// Rejected against the graph's estimate.
    pub rejected_graph: usize,
    /// Held for support.
    pub held: usize,
    /// Held candidates dropped without support.
    pub dropped: usize,
}

/// A loop candidate: node `node` at `anchor_from_node` in the frame of node `anchor`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LoopCandidate {
    pub node: usize,
    pub anchor: usize,
    pub anchor_from_node: Pose2,
}

/// An accepted loop: the candidate and its pose-graph edge.
#[derive(Clone, Copy, Debug)]
struct Accepted {
    loop_: LoopCandidate,
    edge: usize,
    /// Whether an optimisation has run since it entered.
    optimised: bool,
}

/// The gate's state; `T` is what the pipeline needs to add a candidate's edge later.
#[derive(Debug)]
pub(crate) struct LoopGate<T> {
    config: ConsistencyConfig,
    /// Front-end path length at each node, metres.
    travel: Vec<f64>,
    accepted: Vec<Accepted>,
    held: Vec<(LoopCandidate, T)>,
    pub stats: ConsistencyStats,
}

/// What the gate needs from the pipeline: the graph's poses and edge weights, the front-end's
/// local node poses, and the robust weight below which a loop no longer counts.
pub(crate) struct View<'a> {
    pub graph: &'a PoseGraph,
    pub local: &'a [Pose2],
    pub reject_weight: f64,
}

impl<T> LoopGate<T> {
    pub fn new(config: ConsistencyConfig) -> Self {
        Self {
            config,
            travel: Vec::new(),
            accepted: Vec::new(),
            held: Vec::new(),
            stats: ConsistencyStats::default(),
        }
    }

    /// Records node `node`'s path length (call for every node, in order).
    pub fn add_node(&mut self, node: usize, travel_m: f64) {
        self.travel.resize(node, travel_m);
        self.travel.push(travel_m);
        let limit = travel_m - self.config.hold_travel_m;
        let before = self.held.len();
        let travel = &self.travel;
        self.held
            .retain(|(c, _)| travel.get(c.node).is_some_and(|&t| t >= limit));
        self.stats.dropped += before - self.held.len();
    }

    /// Records that `candidate` entered the graph as edge `edge`.
    pub fn accepted(&mut self, candidate: LoopCandidate, edge: usize) {
        self.accepted.push(Accepted {
            loop_: candidate,
            edge,
            optimised: false,
        });
    }

    /// Marks every accepted loop as optimised (call after each optimisation).
    pub fn optimised(&mut self) {
        for a in &mut self.accepted {
            a.optimised = true;
        }
    }

    fn t(&self, node: usize) -> f64 {
        self.travel.get(node).copied().unwrap_or(0.0)
    }

    /// Tests `candidate`; returns the candidates that enter the graph now (it and any held
    /// ones that support it), possibly none.
    pub fn check(
        &mut self,
        candidate: LoopCandidate,
        payload: T,
        view: &View<'_>,
    ) -> Vec<(LoopCandidate, T)> {
        self.stats.checked += 1;
        let c = &self.config;
        // The nearest accepted loop still in force (in travel along both ends).
        let reference = self
            .accepted
            .iter()
            .filter(|a| !a.optimised || view.graph.edge_weight(a.edge) >= view.reject_weight)
            .map(|a| (self.pair_travel(&a.loop_, &candidate), a.loop_))
            .filter(|(d, _)| *d <= c.reference_travel_m)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((_, r)) = reference {
            if !self.pair_consistent(&r, &candidate, view) {
                self.stats.rejected_pairwise += 1;
                return Vec::new();
            }
            return vec![(candidate, payload)];
        }
        if !self.graph_consistent(&candidate, view) {
            self.stats.rejected_graph += 1;
            return Vec::new();
        }
        if c.min_support == 0 {
            return vec![(candidate, payload)];
        }
        let support: Vec<usize> = (0..self.held.len())
            .filter(|&k| self.pair_consistent(&self.held[k].0, &candidate, view))
            .collect();
        if support.len() < c.min_support {
            self.stats.held += 1;
            self.held.push((candidate, payload));
            return Vec::new();
        }
        let mut out = Vec::with_capacity(support.len() + 1);
        for k in support.into_iter().rev() {
            out.push(self.held.remove(k));
        }
        out.reverse();
        out.push((candidate, payload));
        out
    }

    /// Path between two loops' nodes plus path between their anchors, metres.
    fn pair_travel(&self, a: &LoopCandidate, b: &LoopCandidate) -> f64 {
        (self.t(a.node) - self.t(b.node)).abs() + (self.t(a.anchor) - self.t(b.anchor)).abs()
    }

    /// χ² of `E = Q⁻¹ P` with the drift over `d` metres and a heading lever of `lever` metres.
    fn chi2(&self, q: Pose2, p: Pose2, d: f64, lever: f64) -> f64 {
        let c = &self.config;
        let e = q.inverse() * p;
        let s_theta2 = 2.0 * c.loop_sigma[1].powi(2) + (c.drift[1] * d).powi(2);
        let s_t2 =
            2.0 * c.loop_sigma[0].powi(2) + (c.drift[0] * d).powi(2) + s_theta2 * lever * lever;
        e.translation().norm_squared() / s_t2 + wrap_angle(e.theta()).powi(2) / s_theta2
    }

    fn pair_consistent(&self, r: &LoopCandidate, c: &LoopCandidate, view: &View<'_>) -> bool {
        let nodes = view.graph.nodes();
        let (Some(&xa_r), Some(&xa_c), Some(&l_r), Some(&l_c)) = (
            nodes.get(r.anchor),
            nodes.get(c.anchor),
            view.local.get(r.node),
            view.local.get(c.node),
        ) else {
            return true;
        };
        let step = l_r.inverse() * l_c;
        let p = xa_r * r.anchor_from_node * step;
        let q = xa_c * c.anchor_from_node;
        let lever = step.translation().norm() + (xa_r.inverse() * xa_c).translation().norm();
        self.chi2(q, p, self.pair_travel(r, c), lever) <= self.config.chi2_gate
    }

    /// The candidate against the graph's estimate of its node, with the drift along the
    /// shortest path from its anchor to its node that the graph's loops already hold.
    fn graph_consistent(&self, c: &LoopCandidate, view: &View<'_>) -> bool {
        let nodes = view.graph.nodes();
        let (Some(&xa), Some(&xn)) = (nodes.get(c.anchor), nodes.get(c.node)) else {
            return true;
        };
        let (tn, ta) = (self.t(c.node), self.t(c.anchor));
        // The drift enters over the shortest path from anchor to node through one optimised
        // loop still in force (anchor → one end of the loop, other end → node), never more
        // than the path from the anchor to the node itself.
        let d = self
            .accepted
            .iter()
            .filter(|a| a.optimised && view.graph.edge_weight(a.edge) >= view.reject_weight)
            .map(|a| {
                let (ln, la) = (self.t(a.loop_.node), self.t(a.loop_.anchor));
                ((ta - la).abs() + (tn - ln).abs()).min((ta - ln).abs() + (tn - la).abs())
            })
            .fold((tn - ta).abs(), f64::min)
            .max(0.0);
        let q = xa * c.anchor_from_node;
        let lever = c.anchor_from_node.translation().norm();
        self.chi2(q, xn, d, lever) <= self.config.chi2_gate
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{Edge, EdgeKind};
    use nalgebra::Matrix3;

    /// A straight path of `n` nodes 1 m apart along x, its graph, and a gate that has seen it.
    fn setup(n: usize) -> (PoseGraph, Vec<Pose2>, LoopGate<()>) {
        let mut graph = PoseGraph::new();
        let mut local = Vec::new();
        let mut gate = LoopGate::new(ConsistencyConfig::default());
        for k in 0..n {
            let p = Pose2::new(k as f64, 0.0, 0.0);
            graph.add_node(p);
            local.push(p);
            gate.add_node(k, k as f64);
            if k > 0 {
                graph
                    .add_edge(Edge {
                        from: k - 1,
                        to: k,
                        measurement: Pose2::new(1.0, 0.0, 0.0),
                        information: Matrix3::identity(),
                        kind: EdgeKind::Sequential,
                    })
                    .unwrap();
            }
        }
        (graph, local, gate)
    }

    #[test]
    fn a_loop_that_agrees_with_the_graph_passes_one_that_does_not_fails() {
        let (graph, local, mut gate) = setup(60);
        let view = View {
            graph: &graph,
            local: &local,
            reject_weight: 0.5,
        };
        // Node 50 seen from anchor 45 where the graph has it: consistent.
        let right = LoopCandidate {
            node: 50,
            anchor: 45,
            anchor_from_node: Pose2::new(5.05, 0.02, 0.01),
        };
        assert!(gate.graph_consistent(&right, &view));
        // 2 m and 30° off, 5 m of path between anchor and node: inconsistent.
        let wrong = LoopCandidate {
            anchor_from_node: Pose2::new(3.0, 1.0, 0.5),
            ..right
        };
        assert!(!gate.graph_consistent(&wrong, &view));
        // Held, then released by a second consistent candidate; the wrong one is rejected.
        assert!(gate.check(right, (), &view).is_empty());
        assert_eq!(gate.stats.held, 1);
        let second = LoopCandidate {
            node: 51,
            anchor: 45,
            anchor_from_node: Pose2::new(6.0, -0.03, 0.0),
        };
        assert_eq!(gate.check(second, (), &view).len(), 2);
        gate.accepted(right, 0);
        gate.accepted(second, 1);
        assert!(gate.check(wrong, (), &view).is_empty());
        assert_eq!(gate.stats.rejected_pairwise, 1);
    }

    #[test]
    fn held_candidates_expire() {
        let (graph, local, mut gate) = setup(30);
        let view = View {
            graph: &graph,
            local: &local,
            reject_weight: 0.5,
        };
        let c = LoopCandidate {
            node: 29,
            anchor: 2,
            anchor_from_node: Pose2::new(27.0, 0.0, 0.0),
        };
        assert!(gate.check(c, (), &view).is_empty());
        gate.add_node(30, 40.0);
        assert_eq!(gate.stats.dropped, 1);
        assert!(gate.held.is_empty());
    }
}
