//! The SLAM pipeline: front-end → nodes and submaps → loop closure → pose graph.

use std::time::Instant;

use raypath_geometry::Pose2;
use raypath_io::sequence::PlanarFrame;
use raypath_reflectivity::{IntensityCorrection, MatcherConfig, ScanPoints};

use crate::config::{SlamConfig, information};
use crate::consistency::{LoopCandidate, LoopGate, View};
use crate::error::{Result, SlamError};
use crate::frontend::{FrontEnd, freeze_all};
use crate::graph::{Edge, EdgeKind, PoseGraph};
use crate::loops::{LoopCloser, LoopClosure, LoopSource};
use crate::output::{ScanPose, SlamOutput, SlamStats};
use crate::polish::{ScanNodes, polish};
use crate::submap::Submap;

/// Online 2-D SLAM over a stream of planar scans (see the crate docs for the pipeline).
///
/// Feed scans in time order with [`Slam::process`], then call [`Slam::finish`] for the
/// optimised trajectory, the submaps and the loop closures.
#[derive(Debug)]
pub struct Slam {
    config: SlamConfig,
    matcher: MatcherConfig,
    correction: Option<IntensityCorrection>,
    frontend: FrontEnd,
    loops: Option<LoopCloser>,
    graph: PoseGraph,
    /// Per node: (scan index, local pose).
    node_local: Vec<Pose2>,
    node_scan: Vec<usize>,
    /// The finished submap each node belongs to (the later one when it is in two).
    node_submap: Vec<Option<usize>>,
    submaps: Vec<Submap>,
    closures: Vec<LoopClosure>,
    scans: Vec<ScanPose>,
    points: ScanPoints,
    /// Every scan's points (sensor frame), kept for [`SlamConfig::polish`].
    polish_points: Vec<Vec<[f64; 2]>>,
    nodes_since_optimisation: usize,
    loops_since_optimisation: usize,
    travel_at_last_loop: f64,
    stats: SlamStats,
    /// The loop consistency test ([`crate::consistency`]); held candidates carry
    /// `(submap, score, source)`.
    gate: Option<LoopGate<(usize, f64, LoopSource)>>,
}

impl Slam {
    /// A SLAM run with `config`.
    pub fn new(config: SlamConfig) -> Result<Self> {
        config.validate()?;
        let loops = match &config.loops {
            Some(l) => Some(LoopCloser::new(*l, config.filter.max_range_m)?),
            None => None,
        };
        Ok(Self {
            gate: config.consistency.map(LoopGate::new),
            matcher: config.matcher,
            frontend: FrontEnd::new(&config),
            loops,
            config,
            correction: None,
            graph: PoseGraph::new(),
            node_local: Vec::new(),
            node_scan: Vec::new(),
            node_submap: Vec::new(),
            submaps: Vec::new(),
            closures: Vec::new(),
            scans: Vec::new(),
            points: ScanPoints::new(),
            polish_points: Vec::new(),
            nodes_since_optimisation: 0,
            loops_since_optimisation: 0,
            travel_at_last_loop: 0.0,
            stats: SlamStats::default(),
        })
    }

    /// Turns intensities into relative reflectivity with `correction` (for the reflectivity
    /// and combined residuals; Khan 2017 §3.3).
    pub fn with_correction(mut self, correction: IntensityCorrection) -> Self {
        self.correction = Some(correction);
        self
    }

    /// The configuration.
    pub fn config(&self) -> &SlamConfig {
        &self.config
    }

    /// Number of scans processed.
    pub fn scans(&self) -> usize {
        self.scans.len()
    }

    /// Number of nodes so far.
    pub fn nodes(&self) -> usize {
        self.node_local.len()
    }

    /// The submaps finished so far (indices for [`Slam::propose_loop_closure`]).
    pub fn submaps(&self) -> &[Submap] {
        &self.submaps
    }

    /// The current estimate of the latest scan's `world_from_sensor`.
    pub fn pose(&self) -> Option<Pose2> {
        self.scans.last().map(|s| self.world_from_local() * s.local)
    }

    /// Processes one frame: its scan, and its logged `world_from_laser` as odometry when
    /// [`SlamConfig::use_odometry`] is set. The scan is stamped with the sensor's time
    /// ([`PlanarFrame::sensor_stamp_secs`]: the CARMEN ipc time stamp, a bag's header stamp),
    /// so the trajectory joins with relation files and other tools by time.
    pub fn process(&mut self, frame: &PlanarFrame) -> Result<()> {
        let odometry = self
            .config
            .use_odometry
            .then_some(frame.world_from_laser)
            .filter(Pose2::is_finite);
        self.process_scan(frame.sensor_stamp_secs(), &frame.scan, odometry)
    }

    /// Processes one scan taken at `stamp_secs` with the odometry pose `odometry`
    /// (`world_from_sensor` in the odometry frame; `None`: no odometry).
    pub fn process_scan(
        &mut self,
        stamp_secs: f64,
        scan: &raypath_geometry::Scan2,
        odometry: Option<Pose2>,
    ) -> Result<()> {
        if !stamp_secs.is_finite() {
            return Err(SlamError::BadInput(format!(
                "scan {}: time stamp {stamp_secs} is not finite",
                self.scans.len()
            )));
        }
        let t0 = Instant::now();
        self.points
            .fill_from_scan(scan, &self.config.filter, self.correction.as_ref());
        if self.config.polish.is_some() {
            self.polish_points.push(self.points.points().to_vec());
        }
        let local = self.frontend.track(&self.points, odometry, stamp_secs);
        let node = if self.frontend.wants_node(&self.config) {
            Some(self.add_node(stamp_secs, local)?)
        } else {
            None
        };
        self.scans.push(ScanPose {
            stamp_secs,
            local,
            node: self.node_local.len().saturating_sub(1),
            is_node: node.is_some(),
        });
        self.stats.frontend_seconds += t0.elapsed().as_secs_f64();
        if let Some(node) = node {
            self.close_loops(node, scan);
            self.nodes_since_optimisation += 1;
            if self.nodes_since_optimisation >= self.config.optimize_every_nodes
                && self.loops_since_optimisation > 0
            {
                self.optimise()?;
            }
        }
        Ok(())
    }

    /// The map from the front-end's local frame to the optimised world frame (through the
    /// latest node).
    fn world_from_local(&self) -> Pose2 {
        match (self.graph.nodes().last(), self.node_local.last()) {
            (Some(world), Some(local)) => *world * local.inverse(),
            _ => Pose2::identity(),
        }
    }

    fn add_node(&mut self, _stamp_secs: f64, local: Pose2) -> Result<usize> {
        let world = self.world_from_local() * local;
        let node = self.graph.add_node(world);
        if let Some(&prev) = self.node_local.last() {
            // Across a failed match the step is the odometry's, with its uncertainty.
            let sigma = if self.frontend.failed_since_node() {
                &self.config.tracking.fallback_sigma
            } else {
                &self.config.sequential_sigma
            };
            self.graph.add_edge(Edge {
                from: node - 1,
                to: node,
                measurement: prev.inverse() * local,
                information: information(sigma),
                kind: EdgeKind::Sequential,
            })?;
        }
        self.node_local.push(local);
        if let Some(gate) = self.gate.as_mut() {
            gate.add_node(node, self.frontend.travel_m());
        }
        self.node_scan.push(self.scans.len());
        self.node_submap.push(None);
        let mut intra = Vec::with_capacity(2);
        let finished = self
            .frontend
            .insert(&self.config, node, &self.points, &mut intra)?;
        if self.config.intra_submap_edges {
            for (anchor, submap_from_sensor) in intra {
                self.graph.add_edge(Edge {
                    from: anchor,
                    to: node,
                    measurement: submap_from_sensor,
                    information: information(&self.config.sequential_sigma),
                    kind: EdgeKind::Sequential,
                })?;
            }
        }
        let depth = self.config.loops.map_or(1, |l| l.correlative.depth);
        for submap in freeze_all(finished, depth) {
            let k = self.submaps.len();
            for &n in submap.nodes() {
                if let Some(slot) = self.node_submap.get_mut(n) {
                    *slot = Some(k);
                }
            }
            self.submaps.push(submap);
        }
        Ok(node)
    }

    fn close_loops(&mut self, node: usize, scan: &raypath_geometry::Scan2) {
        let Some(loops) = self.loops.as_mut() else {
            return;
        };
        let t0 = Instant::now();
        loops.describe(node, scan);
        let every = self.config.loops.map_or(1, |l| l.every_nodes);
        if node % every != 0 {
            self.stats.loop_seconds += t0.elapsed().as_secs_f64();
            return;
        }
        let travel = self.frontend.travel_m() - self.travel_at_last_loop;
        let found = loops.search(
            node,
            &self.points,
            self.graph.nodes(),
            &self.node_submap,
            &self.submaps,
            &self.matcher,
            travel,
        );
        for (submap, submap_from_sensor, score, source) in found {
            self.propose_loop(node, submap, submap_from_sensor, score, source);
        }
        self.stats.loop_seconds += t0.elapsed().as_secs_f64();
    }

    /// Proposes a loop closure of the latest node: seen at `submap_from_sensor` in finished
    /// submap `submap` (an index into the submaps finished so far) with match score `score`.
    /// It passes the same consistency test as the loop search's own matches
    /// ([`SlamConfig::consistency`]) before it enters the pose graph, so an external loop
    /// source (or a test) can offer loops without being trusted blindly. Returns whether it
    /// entered now (a held candidate may enter later, with a supporting one).
    pub fn propose_loop_closure(
        &mut self,
        submap: usize,
        submap_from_sensor: Pose2,
        score: f64,
        source: LoopSource,
    ) -> bool {
        let Some(node) = self.node_local.len().checked_sub(1) else {
            return false;
        };
        self.propose_loop(node, submap, submap_from_sensor, score, source)
    }

    /// Tests a loop candidate and adds the edges of the ones that enter; whether it did.
    fn propose_loop(
        &mut self,
        node: usize,
        submap: usize,
        submap_from_sensor: Pose2,
        score: f64,
        source: LoopSource,
    ) -> bool {
        let Some(anchor) = self.submaps.get(submap).map(Submap::anchor) else {
            return false;
        };
        let candidate = LoopCandidate {
            node,
            anchor,
            anchor_from_node: submap_from_sensor,
        };
        let entering = match self.gate.as_mut() {
            Some(gate) => {
                let view = View {
                    graph: &self.graph,
                    local: &self.node_local,
                    reject_weight: self.config.reject_weight,
                };
                gate.check(candidate, (submap, score, source), &view)
            }
            None => vec![(candidate, (submap, score, source))],
        };
        let mut entered = false;
        for (c, (submap, score, source)) in entering {
            let edge = Edge {
                from: c.anchor,
                to: c.node,
                measurement: c.anchor_from_node,
                information: information(&self.config.loop_sigma),
                kind: EdgeKind::Loop,
            };
            if let Ok(edge) = self.graph.add_edge(edge) {
                if let Some(gate) = self.gate.as_mut() {
                    gate.accepted(c, edge);
                }
                self.closures.push(LoopClosure {
                    node: c.node,
                    submap,
                    anchor: c.anchor,
                    submap_from_sensor: c.anchor_from_node,
                    score,
                    source,
                    edge,
                });
                self.loops_since_optimisation += 1;
                self.travel_at_last_loop = self.frontend.travel_m();
                entered |= c == candidate;
            }
        }
        entered
    }

    fn optimise(&mut self) -> Result<()> {
        let t0 = Instant::now();
        let report = self.graph.optimize(&self.config.solver)?;
        self.stats.optimisations += 1;
        self.stats.final_chi2 = report.final_chi2;
        if let Some(gate) = self.gate.as_mut() {
            gate.optimised();
        }
        self.nodes_since_optimisation = 0;
        self.loops_since_optimisation = 0;
        self.stats.optimise_seconds += t0.elapsed().as_secs_f64();
        Ok(())
    }

    /// Finishes the run: freezes the active submaps, optimises once more and returns the
    /// trajectory of every scan in the optimised world frame.
    pub fn finish(mut self) -> Result<SlamOutput> {
        let depth = self.config.loops.map_or(1, |l| l.correlative.depth);
        let last = self.frontend.finish();
        for submap in freeze_all(last, depth) {
            self.submaps.push(submap);
        }
        if self.graph.nodes().len() > 1 {
            self.optimise()?;
        }
        let loop_stats = self.loops.as_ref().map(|l| l.stats).unwrap_or_default();
        let (accepted, rejected): (Vec<_>, Vec<_>) = std::mem::take(&mut self.closures)
            .into_iter()
            .partition(|c| self.graph.edge_weight(c.edge) >= self.config.reject_weight);
        if !rejected.is_empty() {
            // Rejected loop closures leave the graph before a last optimisation, so no
            // discounted wrong edge pulls on the result.
            for c in &rejected {
                self.graph.switch_off(c.edge);
            }
            self.optimise()?;
        }
        let mut nodes = self.graph.nodes().to_vec();
        let mut world_from_sensor: Vec<Pose2> = self
            .scans
            .iter()
            .map(|s| match (nodes.get(s.node), self.node_local.get(s.node)) {
                (Some(world), Some(local)) => *world * local.inverse() * s.local,
                _ => s.local,
            })
            .collect();
        if let Some(config) = &self.config.polish {
            let t0 = Instant::now();
            let scan_nodes = ScanNodes {
                scans: &self.scans,
                node_scan: &self.node_scan,
                node_local: &self.node_local,
            };
            let sequential = information(&self.config.sequential_sigma);
            let (polished, edges) = polish(
                &world_from_sensor,
                &self.polish_points,
                &self.graph,
                &scan_nodes,
                &sequential,
                config,
                &self.config.solver,
            )?;
            world_from_sensor = polished;
            nodes = self
                .node_scan
                .iter()
                .zip(&nodes)
                .map(|(&k, &n)| world_from_sensor.get(k).copied().unwrap_or(n))
                .collect();
            self.stats.polish_edges = edges;
            self.stats.polish_seconds = t0.elapsed().as_secs_f64();
        }
        let stats = SlamStats {
            loops: loop_stats,
            tracking: self.frontend.stats,
            consistency: self.gate.as_ref().map(|g| g.stats).unwrap_or_default(),
            ..self.stats
        };
        Ok(SlamOutput {
            scans: self.scans,
            world_from_sensor,
            nodes,
            node_scan: self.node_scan,
            submaps: self.submaps,
            loop_closures: accepted,
            rejected_loop_closures: rejected,
            graph: self.graph,
            stats,
        })
    }
}
