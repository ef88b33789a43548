//! The Rtree variable-resolution occupancy grid (Khan 2017, §2.5).

mod cache;
mod fuse;
mod query;
mod ray;
mod split;
#[cfg(test)]
mod tests;

use nalgebra::Point3;
use raypath_geometry::{PointCloud, Pose3};

use crate::config::{FusionRule, GridConfig, Selection, SensorModel, logit};
use crate::coverage::FusedCoverage;
use crate::index::LatticeIndex;
use crate::key::{Key, KeyBox, key_of, pack, unpack};
use crate::rtree::{OrderError, RTree};

pub use query::{Cuboid, Occupancy};

/// A leaf cell: its box of base cubes (stored once, in the tree) and its log-odds
/// (4 bytes, in `log_odds`).
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
    /// Bytes allocated by the map (tree arena, cells, lattice index).
    pub bytes: usize,
}

/// The Rtree variable-resolution occupancy grid: leaf cells are lattice-aligned cuboids in
/// an [`RTree`], updated with log-odds (Eq. 2.7) and fused after each scan (§2.5.2).
#[derive(Clone, Debug)]
pub struct RtreeGrid {
    config: GridConfig,
    tree: RTree,
    log_odds: Vec<f32>,
    free_cells: Vec<u32>,
    index: LatticeIndex,
    fused_cells: usize,
    coverage: FusedCoverage,
    last_fused: Option<(u32, KeyBox)>,
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
    selected: Vec<u32>,
    recent: ray::RecentKeys,
    fused_cache: cache::FusedCache,
}

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
            log_odds: Vec::new(),
            free_cells: Vec::new(),
            index: LatticeIndex::default(),
            fused_cells: 0,
            coverage: FusedCoverage::default(),
            last_fused: None,
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
            selected: Vec::new(),
            recent: ray::RecentKeys::new(),
            fused_cache: cache::FusedCache::new(),
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

    #[inline]
    fn key_of_cell(tree: &RTree) -> impl Fn(u32) -> Key + '_ {
        move |id| tree.item_box(id).map_or([0; 3], |b| b.lo)
    }

    /// The cell `id` (box from the tree, log-odds; NaN log-odds for a dead id).
    #[inline]
    fn cell(&self, id: u32) -> Cell {
        Cell {
            bx: self.tree.item_box(id).unwrap_or(KeyBox::cube([0; 3])),
            log_odds: self.log_odds[id as usize],
        }
    }

    /// Inserts one scan of a sensor at `world_from_sensor` with points in the sensor frame;
    /// invalid (NaN) points are skipped.
    pub fn insert_cloud(&mut self, world_from_sensor: &Pose3, cloud: &PointCloud) -> ScanUpdate {
        let origin = world_from_sensor.translation();
        let points: Vec<Point3<f64>> = (0..cloud.len())
            .filter(|&i| cloud.is_valid(i))
            .map(|i| world_from_sensor.transform_point(&cloud.point_f64(i)))
            .collect();
        self.insert_scan(&Point3::from(origin), &points)
    }

    /// Inserts one scan: beams from `origin_m` to each end point (world frame, metres).
    /// Updates every touched cell once (occupied wins over free), then fuses (§2.5.3).
    pub fn insert_scan(&mut self, origin_m: &Point3<f64>, points_m: &[Point3<f64>]) -> ScanUpdate {
        let mut update = ScanUpdate::default();
        let r = self.config.resolution_m;
        let origin = [origin_m.x, origin_m.y, origin_m.z];
        let beam = self.config.model == SensorModel::BeamBased;
        // §2.5.2, Fig. 2.6: end-point cells always start fusions; each cell a beam traversed does
        // so with probability 1 / spacing (the thesis samples random cells along each beam by its
        // length, with no number; ⌈len / (s·r)⌉ per beam gives the same expected number, drawn
        // here from the de-duplicated traversed cells).
        let sample_probability = match self.config.selection {
            _ if !beam || !self.config.fusion => 0.0,
            Selection::BeamSamples { spacing_cells } => 1.0 / spacing_cells,
            Selection::UpdatedCells => 1.0,
        };
        let mut free_keys = std::mem::take(&mut self.free_keys);
        let mut occupied_keys = std::mem::take(&mut self.occupied_keys);
        free_keys.clear();
        occupied_keys.clear();
        let mut recent = std::mem::replace(&mut self.recent, ray::RecentKeys { slots: Vec::new() });
        recent.clear();
        let mut rng = ray::SplitMix(self.config.seed ^ self.scans.wrapping_mul(0x9E37_79B9));
        for p in points_m {
            let mut end = [p.x, p.y, p.z];
            if !end.iter().all(|v| v.is_finite()) {
                continue;
            }
            let d = [end[0] - origin[0], end[1] - origin[1], end[2] - origin[2]];
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let mut hit = true;
            if let Some(max) = self.config.max_range_m {
                if len > max {
                    let s = max / len;
                    end = [
                        origin[0] + d[0] * s,
                        origin[1] + d[1] * s,
                        origin[2] + d[2] * s,
                    ];
                    hit = false;
                }
            }
            update.beams += 1;
            match key_of(end, r) {
                Some(k) if hit => occupied_keys.push(pack(k)),
                Some(_) => {}
                None => update.off_lattice += 1,
            }
            if beam {
                ray::ray_keys_with(origin, end, r, |k| {
                    if recent.insert(k) {
                        free_keys.push(k);
                    }
                });
            }
        }
        self.recent = recent;
        occupied_keys.sort_unstable();
        occupied_keys.dedup();
        free_keys.sort_unstable();
        free_keys.dedup();
        // Occupied wins: drop free keys that are also hit (both lists are sorted).
        {
            let mut j = 0;
            free_keys.retain(|k| {
                while j < occupied_keys.len() && occupied_keys[j] < *k {
                    j += 1;
                }
                !(j < occupied_keys.len() && occupied_keys[j] == *k)
            });
        }
        update.free_keys = free_keys.len();
        update.occupied_keys = occupied_keys.len();
        // Cells selected by earlier scans of this fusion interval stay selected.
        let mut selected = std::mem::take(&mut self.selected);
        let fusion = self.config.fusion;
        for (keys, hit) in [(&free_keys, false), (&occupied_keys, true)] {
            for &packed in keys.iter() {
                let id = self.update_key(unpack(packed), hit, &mut update);
                let Some(id) = id else { continue };
                let chosen = fusion
                    && (hit || sample_probability >= 1.0 || rng.next_f64() < sample_probability);
                // Only cells that may fuse start fusions (checked again when fusing).
                if chosen && self.may_fuse(self.log_odds[id as usize]) {
                    selected.push(id);
                }
            }
        }
        self.apply_fused_updates();
        self.apply_exact_updates(&mut selected, &mut update);
        self.scans += 1;
        self.selected = selected;
        if fusion && self.scans % u64::from(self.config.fusion_interval_scans) == 0 {
            update.fusions += self.fuse_pending();
        }
        if self.free_cells.len() > 4096 && self.free_cells.len() * 2 > self.log_odds.len() {
            self.compact();
        }
        self.free_keys = free_keys;
        self.occupied_keys = occupied_keys;
        update
    }

    /// Runs the fusions of the cells selected since the last fusion pass (those of the
    /// scans inside a [`GridConfig::fusion_interval_scans`]); returns the fusion steps.
    pub fn fuse_pending(&mut self) -> usize {
        let mut selected = std::mem::take(&mut self.selected);
        selected.sort_unstable();
        selected.dedup();
        let mut steps = 0;
        for &id in &selected {
            steps += self.fuse(id);
        }
        selected.clear();
        self.selected = selected;
        steps
    }

    /// The id of the cell containing base cube `key`.
    fn cell_id_of_key(&self, key: Key) -> Option<u32> {
        if let Some(id) = self.index.get(key, Self::key_of_cell(&self.tree)) {
            return Some(id);
        }
        if !self.coverage.may_contain(key) {
            return None;
        }
        self.tree.find_containing(key).map(|(id, _)| id)
    }

    /// The live fused cell containing `key` if the last-found cell or the block cache
    /// knows it (no tree search).
    #[inline]
    fn fused_hint(&self, key: Key) -> Option<u32> {
        if let Some((id, _)) = self.last_fused.filter(|&(_, bx)| bx.contains_key(key)) {
            return Some(id);
        }
        let id = self.fused_cache.get(key)?;
        let bx = self.tree.item_box(id)?;
        let l = self.log_odds.get(id as usize)?;
        (!l.is_nan() && bx.volume() > 1 && bx.contains_key(key)).then_some(id)
    }

    /// The fused cell containing `key` (not in the lattice index): the last one found, the
    /// block cache, then an R-tree point query.
    fn find_fused(&mut self, key: Key) -> Option<(u32, KeyBox)> {
        if let Some(found) = self.last_fused.filter(|&(_, bx)| bx.contains_key(key)) {
            return Some(found);
        }
        if let Some(id) = self.fused_hint(key) {
            let found = (id, self.tree.item_box(id).unwrap_or(KeyBox::cube(key)));
            self.last_fused = Some(found);
            return Some(found);
        }
        let found = self.tree.find_containing(key)?;
        self.fused_cache.put(key, found.0);
        self.last_fused = Some(found);
        Some(found)
    }

    #[inline]
    fn updated(&self, log_odds: f32, hit: bool) -> f32 {
        let delta = if hit { self.l_hit } else { self.l_miss };
        (log_odds + delta).clamp(self.l_min, self.l_max) // Eq. (2.7), clamped
    }

    /// Applies one update to the cell holding `key` (creating it) and returns the cell id;
    /// updates of fused cells are queued and applied once per scan.
    fn update_key(&mut self, key: Key, hit: bool, update: &mut ScanUpdate) -> Option<u32> {
        if let Some(id) = self.index.get(key, Self::key_of_cell(&self.tree)) {
            let l = self.log_odds[id as usize];
            self.log_odds[id as usize] = self.updated(l, hit);
            return Some(id);
        }
        if self.coverage.may_contain(key) {
            // Sorted keys run along x: the previous fused cell often holds the next key too.
            if let Some((id, _)) = self.find_fused(key) {
                if self.exact_updates() {
                    let l = self.log_odds[id as usize];
                    if !self.keeps_value(l, self.updated(l, hit)) {
                        self.touched_exact.push((id, pack(key), hit));
                    }
                    return Some(id);
                }
                self.touched_fused.push((id, hit));
                return Some(id);
            }
        }
        let l = self.updated(0.0, hit);
        let id = self.create_cell(KeyBox::cube(key), l);
        update.created += 1;
        Some(id)
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
            let l = self.log_odds[id as usize];
            if !l.is_nan() {
                self.log_odds[id as usize] = self.updated(l, hit);
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

    fn create_cell(&mut self, bx: KeyBox, log_odds: f32) -> u32 {
        let id = if let Some(id) = self.free_cells.pop() {
            self.log_odds[id as usize] = log_odds;
            id
        } else {
            self.log_odds.push(log_odds);
            (self.log_odds.len() - 1) as u32
        };
        self.tree.insert(id, bx);
        if bx.volume() == 1 {
            self.index.insert(bx.lo, id, Self::key_of_cell(&self.tree));
        } else {
            self.fused_cells += 1;
            self.coverage.add(&bx);
        }
        id
    }

    fn delete_cell(&mut self, id: u32) -> Cell {
        self.last_fused = None;
        let cell = self.cell(id);
        if cell.bx.volume() == 1 {
            self.index.remove(cell.bx.lo, Self::key_of_cell(&self.tree));
        } else {
            self.fused_cells -= 1;
            self.coverage.remove(&cell.bx);
        }
        self.tree.remove(id);
        self.log_odds[id as usize] = f32::NAN;
        self.free_cells.push(id);
        cell
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
            if self.log_odds[id as usize] > self.l_threshold {
                stats.occupied_leaves += 1;
            }
        });
        stats
    }

    /// Bytes allocated by the map: the tree arena (with the cell boxes), the log-odds (4 B per cell), the free
    /// list and the lattice index (excluding per-scan scratch vectors).
    pub fn memory_bytes(&self) -> usize {
        self.tree.memory_bytes()
            + self.log_odds.capacity() * size_of::<f32>()
            + self.free_cells.capacity() * 4
            + self.index.memory_bytes()
            + self.coverage.memory_bytes()
            + size_of::<Self>()
    }

    /// Renumbers the cells and rebuilds the arenas without the holes left by fusion
    /// (`O(n)`; runs automatically after a scan once half the cell ids are dead).
    pub fn compact(&mut self) {
        self.last_fused = None;
        self.fused_cache.clear();
        let map = self.tree.compact();
        let mut log_odds = vec![0.0f32; self.tree.len()];
        for (old, &new) in map.iter().enumerate() {
            if let (Some(slot), Some(&l)) = (log_odds.get_mut(new as usize), self.log_odds.get(old))
            {
                *slot = l;
            }
        }
        self.log_odds = log_odds;
        self.free_cells = Vec::new();
        // Pending fusion seeds follow the renumbering (dead ids are dropped).
        self.selected = self
            .selected
            .iter()
            .filter_map(|&old| map.get(old as usize).copied())
            .filter(|&new| new != u32::MAX)
            .collect();
        let mut index = LatticeIndex::with_capacity(self.tree.len() - self.fused_cells);
        let tree = &self.tree;
        tree.for_each_item(&mut |id, bx| {
            if bx.volume() == 1 {
                index.insert(bx.lo, id, Self::key_of_cell(tree));
            }
        });
        self.index = index;
    }

    /// Compacts the map and releases spare capacity (per-scan scratch and vector slack).
    pub fn shrink_to_fit(&mut self) {
        self.compact();
        self.tree.shrink_to_fit();
        self.log_odds.shrink_to_fit();
        self.free_cells.shrink_to_fit();
        self.free_keys = Vec::new();
        self.occupied_keys = Vec::new();
        self.selected.shrink_to_fit(); // pending fusion seeds are kept
        self.touched_fused = Vec::new();
        self.touched_exact = Vec::new();
    }
}
