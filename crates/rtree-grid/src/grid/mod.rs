//! The Rtree variable-resolution occupancy grid (Khan 2017, §2.5).

mod cells;
mod fuse;
mod id_bits;
mod query;
mod ray;
mod split;
#[cfg(test)]
mod tests;

use nalgebra::Point3;
use raypath_geometry::{PointCloud, Pose3};

use crate::config::{FusionRule, GridConfig, Selection, SensorModel, logit};
use crate::fused_index::FusedIndex;
use crate::index::LatticeIndex;
use crate::key::{Key, KeyBox, pack, unpack};
use crate::rtree::{OrderError, RTree};

pub use query::{Cuboid, Occupancy};

/// A leaf cell: its box of base cubes and its log-odds (stored together, once, in the
/// tree's item table).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Cell {
    bx: KeyBox,
    log_odds: f32,
}

/// Errors of the grid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GridError {
    /// The R-tree order is invalid.
    #[error(transparent)]
    Order(#[from] OrderError),
    /// A parameter is out of range.
    #[error("invalid grid parameter: {0}")]
    Parameter(String),
}

/// What one [`RtreeGrid::insert_scan`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ScanUpdate {
    /// Beams used (finite end points).
    pub beams: usize,
    /// Beams whose end point lies outside the 16-bit lattice (beyond
    /// [`lattice_half_extent_m`](crate::key::lattice_half_extent_m) of the origin on some axis):
    /// their end cube is not updated and their ray only where it is on the lattice.
    pub off_lattice: usize,
    /// Distinct base cubes updated as free.
    pub free_keys: usize,
    /// Distinct base cubes updated as occupied.
    pub occupied_keys: usize,
    /// Cells created.
    pub created: usize,
    /// Successful fusion steps.
    pub fusions: usize,
    /// Fused cells split back into base cubes.
    pub splits: usize,
}

/// Sizes of the map.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct GridStats {
    /// Leaf cells (cubes and fused cuboids).
    pub leaves: usize,
    /// Leaves with probability above the occupancy threshold.
    pub occupied_leaves: usize,
    /// Fused leaves (more than one base cube).
    pub fused_leaves: usize,
    /// R-tree nodes (the MBRCs of the hierarchy, root included).
    pub nodes: usize,
    /// R-tree height.
    pub height: usize,
    /// Base cubes covered by leaves (the volume in units of r³).
    pub base_cubes: u64,
    /// Bytes allocated by the map (tree arena with the cells, look-up indexes).
    pub bytes: usize,
}

/// The Rtree variable-resolution occupancy grid: leaf cells are lattice-aligned cuboids in
/// an [`RTree`], updated with log-odds (Eq. 2.7) and fused after each scan (§2.5.2).
#[derive(Clone, Debug)]
pub struct RtreeGrid {
    config: GridConfig,
    /// The leaf cells: boxes and log-odds (as the items' values) by cell id.
    tree: RTree,
    free_cells: Vec<u32>,
    index: LatticeIndex,
    fused: FusedIndex,
    fused_cells: usize,
    pending: cells::Pending,
    l_hit: f32,
    l_miss: f32,
    l_min: f32,
    l_max: f32,
    l_threshold: f32,
    scans: u64,
    free_keys: Vec<u64>,
    occupied_keys: Vec<u64>,
    touched_fused: Vec<(u32, bool)>,
    touched_exact: Vec<(u32, u64, bool)>,
    /// Fusion seeds: the cells selected since the last fusion pass.
    selected: fuse::Seeds,
    /// Fusion scratch: a slab's member cells.
    members: Vec<u32>,
    /// Cells of the running fusion pass that cannot grow.
    settled: fuse::Settled,
    recent: ray::RecentKeys,
}

/// The valid points of `cloud` in the world frame.
fn world_points(world_from_sensor: &Pose3, cloud: &PointCloud) -> Vec<Point3<f64>> {
    (0..cloud.len())
        .filter(|&i| cloud.is_valid(i))
        .map(|i| world_from_sensor.transform_point(&cloud.point_f64(i)))
        .collect()
}

impl std::ops::AddAssign for ScanUpdate {
    fn add_assign(&mut self, other: Self) {
        self.beams += other.beams;
        self.off_lattice += other.off_lattice;
        self.free_keys += other.free_keys;
        self.occupied_keys += other.occupied_keys;
        self.created += other.created;
        self.fusions += other.fusions;
        self.splits += other.splits;
    }
}

/// Keys looked up ahead of their updates in a scan.
const LOOKAHEAD: usize = 16;

/// Slack when comparing a log-odds with a clamping bound.
const CLAMP_EPS: f32 = 1e-4;

impl RtreeGrid {
    /// An empty grid.
    pub fn new(config: GridConfig) -> Result<Self, GridError> {
        let bad = |what: &str| Err(GridError::Parameter(what.to_owned()));
        if !(config.resolution_m.is_finite() && config.resolution_m > 0.0) {
            return bad("resolution must be positive and finite");
        }
        let probs = [
            config.prob_hit,
            config.prob_miss,
            config.clamp_min,
            config.clamp_max,
            config.occupancy_threshold,
        ];
        if !probs.iter().all(|p| *p > 0.0 && *p < 1.0) {
            return bad("probabilities must lie in (0, 1)");
        }
        if !(config.clamp_min < 0.5 && config.clamp_max > 0.5) {
            return bad("clamping bounds must enclose 0.5");
        }
        if !(config.prob_hit > 0.5 && config.prob_miss < 0.5) {
            return bad("P_occ must exceed 0.5 and P_free lie below 0.5");
        }
        if let Some(r) = config.max_range_m {
            if r.is_nan() || r <= 0.0 {
                return bad("max range must be positive");
            }
        }
        if config.fusion_interval_scans == 0 {
            return bad("fusion interval must be at least one scan");
        }
        if let Selection::BeamSamples { spacing_cells } = config.selection {
            if !(spacing_cells >= 1.0 && spacing_cells.is_finite()) {
                return bad("sample spacing must be at least one cell");
            }
        }
        let tree = RTree::new(config.min_entries, config.max_entries)?;
        Ok(Self {
            config,
            tree,
            free_cells: Vec::new(),
            index: LatticeIndex::default(),
            fused: FusedIndex::default(),
            fused_cells: 0,
            pending: cells::Pending::default(),
            l_hit: logit(config.prob_hit) as f32,
            l_miss: logit(config.prob_miss) as f32,
            l_min: logit(config.clamp_min) as f32,
            l_max: logit(config.clamp_max) as f32,
            l_threshold: logit(config.occupancy_threshold) as f32,
            scans: 0,
            free_keys: Vec::new(),
            occupied_keys: Vec::new(),
            touched_fused: Vec::new(),
            touched_exact: Vec::new(),
            selected: fuse::Seeds::default(),
            recent: ray::RecentKeys::new(),
            members: Vec::new(),
            settled: fuse::Settled::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &GridConfig {
        &self.config
    }

    /// The R-tree of the leaf cells (read-only).
    pub fn tree(&self) -> &RTree {
        &self.tree
    }

    /// Number of scans inserted.
    pub fn scans(&self) -> u64 {
        self.scans
    }

    /// Number of leaf cells.
    pub fn num_leaves(&self) -> usize {
        self.tree.len()
    }

    /// The cell `id` (box and log-odds from the tree's item table; NaN log-odds for a dead
    /// id).
    #[inline]
    fn cell(&self, id: u32) -> Cell {
        match self.tree.item(id) {
            Some((bx, bits)) => Cell {
                bx,
                log_odds: f32::from_bits(bits),
            },
            None => Cell {
                bx: KeyBox::cube([0; 3]),
                log_odds: f32::NAN,
            },
        }
    }

    /// The log-odds of cell `id` (NaN for a dead id).
    #[inline]
    fn lo(&self, id: u32) -> f32 {
        self.tree.item_value(id).map_or(f32::NAN, f32::from_bits)
    }

    /// Sets the log-odds of cell `id`.
    #[inline]
    fn set_lo(&mut self, id: u32, log_odds: f32) {
        self.tree.set_item_value(id, log_odds.to_bits());
    }

    /// Inserts one scan of a sensor at `world_from_sensor` with points in the sensor frame;
    /// invalid (NaN) points are skipped.
    pub fn insert_cloud(&mut self, world_from_sensor: &Pose3, cloud: &PointCloud) -> ScanUpdate {
        let origin = Point3::from(world_from_sensor.translation());
        self.insert_scan(&origin, &world_points(world_from_sensor, cloud))
    }

    /// Inserts scans one after the other (sensor pose, points in the sensor frame; invalid
    /// points skipped), fusing when [`GridConfig::fusion_interval_scans`] says so and once more
    /// after the last: the leaves are those of [`Self::insert_cloud`] per scan followed by
    /// [`Self::fuse_pending`]. Faster with a fusion interval above one scan: the cells of the
    /// scans between two fusion passes enter the R-tree only after the pass, so the cells it
    /// fuses never do. Returns the counters summed over the scans.
    pub fn insert_clouds<'a>(
        &mut self,
        scans: impl IntoIterator<Item = (&'a Pose3, &'a PointCloud)>,
    ) -> ScanUpdate {
        let mut total = ScanUpdate::default();
        for (world_from_sensor, cloud) in scans {
            let origin = Point3::from(world_from_sensor.translation());
            let points = world_points(world_from_sensor, cloud);
            total += self.insert_scan_with(&origin, &points, false);
        }
        total.fusions += self.fuse_pending();
        total
    }

    /// Inserts one scan: beams from `origin_m` to each end point (world frame, metres).
    /// Updates every touched cell once (occupied wins over free), then fuses (§2.5.3).
    pub fn insert_scan(&mut self, origin_m: &Point3<f64>, points_m: &[Point3<f64>]) -> ScanUpdate {
        self.insert_scan_with(origin_m, points_m, true)
    }

    /// [`Self::insert_scan`]; without `commit`, the new cells enter the R-tree only when a
    /// fusion pass runs (the caller fuses at the end).
    fn insert_scan_with(
        &mut self,
        origin_m: &Point3<f64>,
        points_m: &[Point3<f64>],
        commit: bool,
    ) -> ScanUpdate {
        let mut update = ScanUpdate::default();
        let mut free_keys = std::mem::take(&mut self.free_keys);
        let mut occupied_keys = std::mem::take(&mut self.occupied_keys);
        self.gather_keys(
            origin_m,
            points_m,
            &mut free_keys,
            &mut occupied_keys,
            &mut update,
        );
        update.free_keys = free_keys.len();
        update.occupied_keys = occupied_keys.len();
        // Cells selected by earlier scans of this fusion interval stay selected.
        let mut selected = std::mem::take(&mut self.selected);
        self.update_keys(&free_keys, &occupied_keys, &mut selected, &mut update);
        self.apply_fused_updates();
        self.apply_exact_updates(&mut selected, &mut update);
        self.scans += 1;
        self.selected = selected;
        let interval = u64::from(self.config.fusion_interval_scans);
        let fuse = self.config.fusion && self.scans % interval == 0;
        if fuse {
            update.fusions += self.fuse_seeds();
        } else {
            self.selected.tidy();
        }
        if fuse || commit {
            self.commit();
        }
        if self.free_cells.len() > 4096 && self.free_cells.len() * 2 > self.tree.item_slots() {
            self.compact();
        }
        self.free_keys = free_keys;
        self.occupied_keys = occupied_keys;
        update
    }

    /// Applies a scan's de-duplicated keys (free, then occupied) and selects fusion seeds.
    fn update_keys(
        &mut self,
        free_keys: &[u64],
        occupied_keys: &[u64],
        selected: &mut fuse::Seeds,
        update: &mut ScanUpdate,
    ) {
        // §2.5.2, Fig. 2.6: end-point cells always start fusions; each cell a beam traversed does
        // so with probability 1 / spacing (the thesis samples random cells along each beam by its
        // length, with no number; ⌈len / (s·r)⌉ per beam gives the same expected number, drawn
        // here from the de-duplicated traversed cells).
        let beam = self.config.model == SensorModel::BeamBased;
        let sample_probability = match self.config.selection {
            _ if !beam || !self.config.fusion => 0.0,
            Selection::BeamSamples { spacing_cells } => 1.0 / spacing_cells,
            Selection::UpdatedCells => 1.0,
        };
        let mut rng = ray::SplitMix::new(self.config.seed ^ self.scans.wrapping_mul(0x9E37_79B9));
        let fusion = self.config.fusion;
        // Look-ups run a chunk of keys ahead of the updates (independent memory accesses
        // overlap): they stay valid, as fused cells do not change during this loop (their
        // updates are queued) and the cube a key creates is no other key's. Sorted keys run
        // along x, so the fused cell of the last key often holds the next one.
        let mut last_fused: Option<(u32, KeyBox)> = None;
        let mut found = [None; LOOKAHEAD];
        for (keys, hit) in [(free_keys, false), (occupied_keys, true)] {
            for chunk in keys.chunks(LOOKAHEAD) {
                for (slot, &packed) in found.iter_mut().zip(chunk) {
                    let key = unpack(packed);
                    *slot = match last_fused.filter(|(_, bx)| bx.contains_key(key)) {
                        Some(cell) => Some(cell),
                        None => self.lookup(key),
                    };
                    if let Some(cell) = slot.filter(|(_, bx)| bx.volume() > 1) {
                        last_fused = Some(cell);
                    }
                }
                for (&cell, &packed) in found.iter().zip(chunk) {
                    let (id, bx) = self.update_key(unpack(packed), cell, hit, update);
                    let chosen = fusion
                        && (hit
                            || sample_probability >= 1.0
                            || rng.next_f64() < sample_probability);
                    // Only cells that may fuse start fusions (checked again when fusing).
                    if chosen && self.may_fuse(self.lo(id)) {
                        selected.push(&bx);
                    }
                }
            }
        }
    }

    /// Runs the fusions of the cells selected since the last fusion pass (those of the
    /// scans inside a [`GridConfig::fusion_interval_scans`]); returns the fusion steps.
    pub fn fuse_pending(&mut self) -> usize {
        let steps = self.fuse_seeds();
        self.commit();
        steps
    }

    #[inline]
    fn updated(&self, log_odds: f32, hit: bool) -> f32 {
        let delta = if hit { self.l_hit } else { self.l_miss };
        (log_odds + delta).clamp(self.l_min, self.l_max) // Eq. (2.7), clamped
    }

    /// Applies one update to the cell holding `key` (`found`, looked up; created when
    /// `None`) and returns the cell; updates of fused cells are queued and applied once per
    /// scan.
    fn update_key(
        &mut self,
        key: Key,
        found: Option<(u32, KeyBox)>,
        hit: bool,
        update: &mut ScanUpdate,
    ) -> (u32, KeyBox) {
        let Some((id, bx)) = found else {
            let l = self.updated(0.0, hit);
            update.created += 1;
            let bx = KeyBox::cube(key);
            return (self.create_cell(bx, l), bx);
        };
        let l = self.lo(id);
        if bx.volume() == 1 {
            self.set_lo(id, self.updated(l, hit));
            return (id, bx);
        }
        if !self.exact_updates() {
            self.touched_fused.push((id, hit));
        } else if !self.keeps_value(l, self.updated(l, hit)) {
            self.touched_exact.push((id, pack(key), hit));
        }
        (id, bx)
    }

    /// Updates every fused cell touched this scan once; occupied wins.
    fn apply_fused_updates(&mut self) {
        let mut touched = std::mem::take(&mut self.touched_fused);
        // Sort by id, hits last, so the last entry per id is the winning one.
        touched.sort_unstable();
        for (i, &(id, hit)) in touched.iter().enumerate() {
            if touched.get(i + 1).is_some_and(|next| next.0 == id) {
                continue;
            }
            let l = self.lo(id);
            if !l.is_nan() {
                self.set_lo(id, self.updated(l, hit));
            }
        }
        touched.clear();
        self.touched_fused = touched;
    }

    /// Whether fused cells are kept exact (split when an update changes part of them).
    #[inline]
    fn exact_updates(&self) -> bool {
        self.config.split_on_unclamp || self.config.fusion_rule == FusionRule::EqualValue
    }

    /// Whether an update from `old` to `new` leaves a fused cell's value as it is: bit-equal
    /// under [`FusionRule::EqualValue`], clamped at the same bound under the thesis' rule.
    #[inline]
    fn keeps_value(&self, old: f32, new: f32) -> bool {
        match self.config.fusion_rule {
            FusionRule::EqualValue => old.to_bits() == new.to_bits(),
            FusionRule::Clamped => {
                self.is_clamped(old).is_some() && self.is_clamped(old) == self.is_clamped(new)
            }
        }
    }

    /// Whether a cell with this log-odds may start or join a fusion.
    #[inline]
    fn may_fuse(&self, log_odds: f32) -> bool {
        match self.config.fusion_rule {
            FusionRule::EqualValue => !log_odds.is_nan(),
            FusionRule::Clamped => self.is_clamped(log_odds).is_some(),
        }
    }

    /// `Some(true)` when clamped occupied, `Some(false)` when clamped free.
    #[inline]
    fn is_clamped(&self, log_odds: f32) -> Option<bool> {
        if log_odds >= self.l_max - CLAMP_EPS {
            Some(true)
        } else if log_odds <= self.l_min + CLAMP_EPS {
            Some(false)
        } else {
            None
        }
    }

    /// Sizes of the map.
    pub fn stats(&self) -> GridStats {
        let mut stats = GridStats {
            leaves: self.tree.len(),
            nodes: self.tree.num_nodes(),
            height: self.tree.height(),
            fused_leaves: self.fused_cells,
            bytes: self.memory_bytes(),
            ..GridStats::default()
        };
        self.tree.for_each_item(&mut |id, bx| {
            stats.base_cubes += bx.volume();
            if self.lo(id) > self.l_threshold {
                stats.occupied_leaves += 1;
            }
        });
        stats
    }

    /// Bytes allocated by the map: the tree arena (with the cells' boxes and log-odds), the
    /// free list, the lattice and fused-cell indexes, the bit set of cells not yet in the
    /// tree and the pending fusion seeds (excluding per-scan scratch vectors).
    pub fn memory_bytes(&self) -> usize {
        self.tree.memory_bytes()
            + self.free_cells.capacity() * 4
            + self.index.memory_bytes()
            + self.fused.memory_bytes()
            + self.pending.memory_bytes()
            + self.selected.memory_bytes()
            + size_of::<Self>()
    }

    /// Renumbers the cells and rebuilds the arenas without the holes left by fusion
    /// (`O(n)`; runs automatically after a scan once half the cell ids are dead). The
    /// look-up indexes are rebuilt with room to grow to twice their size.
    pub fn compact(&mut self) {
        self.compact_with(2);
    }

    /// [`Self::compact`] with index room for `room` times the current cells.
    fn compact_with(&mut self, room: usize) {
        self.commit();
        self.tree.compact();
        self.free_cells = Vec::new();
        self.pending.shrink_to_fit();
        self.rebuild_indexes(room);
    }

    /// Compacts the map and releases spare capacity (per-scan scratch, vector slack, index
    /// room).
    pub fn shrink_to_fit(&mut self) {
        self.compact_with(1);
        self.tree.shrink_to_fit();
        self.free_cells.shrink_to_fit();
        self.free_keys = Vec::new();
        self.occupied_keys = Vec::new();
        self.selected.shrink_to_fit(); // pending fusion seeds are kept
        self.touched_fused = Vec::new();
        self.touched_exact = Vec::new();
        self.members = Vec::new();
        self.settled = fuse::Settled::default();
    }
}
