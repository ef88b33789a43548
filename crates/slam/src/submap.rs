//! Submaps: local occupancy (+ reflectivity) grids of a few dozen consecutive nodes.
//!
//! The front-end keeps two **active** submaps that overlap by half (Hess et al. 2016, §IV):
//! every node is inserted into both, and scans are matched against the older, more complete
//! one. A submap's frame is the sensor pose of its first node (its *anchor*), so a constraint
//! "node `i` seen at `submap_from_sensor` in submap `s`" is the relative pose between the
//! anchor node and node `i` in the pose graph. When a submap has twice the nodes per submap it
//! is **frozen**: cut to its observed box ([`MultiResMap::cropped_levels`]) and kept for loop
//! closure (branch-and-bound search on its probability grid, Gauss–Newton refinement on its
//! levels).

use std::sync::OnceLock;

use raypath_geometry::Pose2;
use raypath_reflectivity::{GridLevel, MapConfig, MultiResMap};

use crate::correlative::{PrecomputedGrids, ProbabilityGrid};
use crate::error::Result;

/// A submap being built.
#[derive(Clone, Debug)]
pub(crate) struct ActiveSubmap {
    /// The node whose sensor pose is the submap's frame.
    pub anchor: usize,
    /// The submap frame in the front-end's local frame.
    pub local_from_submap: Pose2,
    /// Path length of the front-end when the submap started, metres.
    pub start_travel_m: f64,
    /// The grids.
    pub map: MultiResMap,
    /// Nodes inserted, in order.
    pub nodes: Vec<usize>,
}

impl ActiveSubmap {
    /// An empty submap anchored at node `anchor` with local pose `local_from_submap`.
    pub fn new(
        config: &MapConfig,
        anchor: usize,
        local_from_submap: Pose2,
        travel_m: f64,
    ) -> Result<Self> {
        Ok(Self {
            anchor,
            local_from_submap,
            start_travel_m: travel_m,
            map: MultiResMap::new(config)?,
            nodes: Vec::new(),
        })
    }

    /// The finished submap (`None` when nothing was observed).
    pub fn freeze(self, depth: usize) -> Option<Submap> {
        let levels = self.map.cropped_levels(2)?;
        let finest = levels.first()?;
        let (res, o) = (finest.resolution_m(), finest.origin());
        let centre = [
            o[0] + finest.width() as f64 * res / 2.0,
            o[1] + finest.height() as f64 * res / 2.0,
        ];
        Some(Submap {
            anchor: self.anchor,
            nodes: self.nodes,
            centre,
            levels,
            depth,
            grids: OnceLock::new(),
        })
    }
}

/// A finished (frozen) submap.
#[derive(Debug)]
pub struct Submap {
    anchor: usize,
    nodes: Vec<usize>,
    centre: [f64; 2],
    levels: Vec<GridLevel>,
    depth: usize,
    grids: OnceLock<PrecomputedGrids>,
}

impl Submap {
    /// The node whose sensor pose is the submap frame.
    pub fn anchor(&self) -> usize {
        self.anchor
    }

    /// The nodes inserted into the submap, in order.
    pub fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    /// Replaces the node list (tests of the loop search).
    #[cfg(test)]
    pub(crate) fn set_nodes_for_test(&mut self, nodes: Vec<usize>) {
        self.nodes = nodes;
    }

    /// The centre of the observed box in the submap frame, metres.
    pub fn centre(&self) -> [f64; 2] {
        self.centre
    }

    /// The grids cut to the observed box, finest first (submap frame).
    pub fn levels(&self) -> &[GridLevel] {
        &self.levels
    }

    /// The max-pooled grids of the branch-and-bound search, built on first use.
    pub fn precomputed(&self) -> &PrecomputedGrids {
        self.grids.get_or_init(|| {
            let grid = match self.levels.first() {
                Some(level) => ProbabilityGrid::from_level(level, None),
                None => ProbabilityGrid::from_level(&GridLevel::new(1.0, [0.0, 0.0], 2, 2), None),
            };
            PrecomputedGrids::new(&grid, self.depth)
        })
    }

    /// Bytes held by the grids (for reports).
    pub fn bytes(&self) -> usize {
        self.levels
            .iter()
            .map(|l| l.width() * l.height() * 8)
            .sum::<usize>()
    }
}
