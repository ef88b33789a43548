//! The Rtree variable-resolution occupancy grid (Khan 2017, ch. 2).
//!
//! A 3-D occupancy grid whose leaf cells are axis-aligned cuboids kept in an R-tree of order
//! (d, M) (Guttman 1984; thesis §2.4). Cells are created only when a beam touches them, as
//! base cubes of edge `r` on one global lattice (OctoMap's key lattice, [`key`]), and
//! updated with log-odds (Eq. 2.7) using OctoMap's parameters ([`GridConfig`], §2.6). After
//! every scan, selected cells that are clamped (P ≤ μ_min or ≥ μ_max) try to double along the
//! search directions (Eq. 2.8) and fuse with the cells of the slab they grow into
//! (Eqs. 2.9–2.11, [`RtreeGrid::insert_scan`]) — resolution adaptation, §2.5.2. Free space
//! and flat walls become a few large cuboids, so the map needs fewer leaves than a pruned
//! octree.
//!
//! # Design
//!
//! * **Own R-tree, not `rstar`.** The thesis needs the quadratic split, deletion with
//!   Guttman's condense/re-insert of fused cells, and in-place updates of leaf payloads;
//!   `rstar` implements the R*-tree (different split and forced re-insertion), has no
//!   payload update by id and stores generic `f64` envelopes. [`RTree`] is an arena: flat
//!   vectors with `M` child slots per node (the `M + 1`-th entry of an overflowing node
//!   waits beside the arena for its split), a box block per inner node, item records stored
//!   once by item id — no per-node heap allocation; boxes are 16-bit lattice keys
//!   ([`KeyBox`], 12 bytes).
//! * **A cell is one 16-byte record.** Its box and its 4-byte log-odds (the item's value)
//!   sit together in the tree's item table, so a look-up reads both in one memory access;
//!   updating occupancy never touches the hierarchy.
//! * **Look-ups without the tree.** A lattice index maps an unfused base cube to its cell,
//!   a fused-cell index (each fused cell under the 4³ blocks it touches, tagged with the
//!   2³ octants it covers there) finds the fused cell holding a cube: a scan update or a
//!   fusion slab check is one or two hash probes, never an R-tree descent (both are
//!   Robin Hood tables of 6-byte slots; the keys of a 2³ block have neighbouring slots).
//! * **One tree update per scan.** Between public calls the tree holds exactly the leaves;
//!   during a scan cells are created and deleted in the indexes only, and the net change is
//!   applied once at the end — Guttman's Delete for the dead cells (as one batch: entries
//!   leave their nodes, then one bottom-up CondenseTree pass), then Insert for the new ones
//!   in lattice order. Cells created and fused away within a scan (fusion chains, split
//!   pieces) never enter the tree.
//! * **Batched scans.** A scan is traversed once (exact voxel traversal on the lattice) into a
//!   vector of packed keys — a small direct-mapped cache drops the repeats of neighbouring beams —
//!   then sorted and de-duplicated (occupied wins over free, OctoMap's `insertPointCloud` rule; the
//!   thesis does not say) and applied; fused cells get one update per scan.
//! * **Fusion only from selected cells** (§2.5.2, Fig. 2.6): end-point cells plus traversed cells
//!   drawn at random ([`Selection`]); only clamped candidates are kept. Slabs are checked cube
//!   by cube along their rows, jumping over each cell found (corners first for slabs of more
//!   than 64 cubes).
//! * **Fusion interval** ([`GridConfig::fusion_interval_scans`], default 1 = the thesis):
//!   fusing every k scans (seeds accumulate; [`RtreeGrid::fuse_pending`] runs them) saves
//!   the split / re-fuse churn of the equal-value rule on a moving sensor. Scans inserted as
//!   one batch ([`RtreeGrid::insert_clouds`], which fuses after the last) also leave the tree
//!   alone between fusion passes, so cells fused at the pass never enter it.
//! * **Settled cells.** Within a fusion pass a slab that failed keeps failing, so a cell
//!   whose six slabs failed is not searched again by later seeds inside it (with seeds from
//!   every updated cell, most seeds land in a cell fused or settled before).
//! * **Compaction.** Fusion frees cell ids and nodes; once half the ids are dead, an `O(n)`
//!   pass renumbers cells in tree order and rebuilds the arenas and indexes
//!   ([`RtreeGrid::compact`]); [`RtreeGrid::shrink_to_fit`] also sizes the indexes tight.
//!
//! Per scan with `n` beams crossing `c` distinct cubes: traversal `O(Σ beam cells)`, sorting
//! `O(c log c)`, updates `O(c)` hash probes, fusion `O(|T| + Σ V)` probes for `|T|` selected
//! cells and `V` cubes per checked slab, and `O(M log_d N)` per cell the scan adds to or
//! removes from the tree (plus splits and re-insertions).
//!
//! # Errata and decisions
//!
//! * A slab fuses only if it is **exactly tiled** by leaves lying completely inside it, all
//!   clamped with the polarity of `g_i` — coverage and non-overlap checks the thesis omits.
//! * The fused probability is the equal-weight mean over the cells (g_i included).
//! * Search directions try + before − per axis.
//! * Selected cells start fusions in Morton order of their lower corners (the thesis gives
//!   no order); a selected cell fused into a larger one or split since it was selected starts
//!   from the cell now holding its lower corner. The leaves depend on the scans only, not on
//!   M, cell ids or the tree's shape.
//! * Beam samples: each de-duplicated traversed cell is a candidate with probability
//!   `1 / spacing` (the thesis samples cells at random along each beam by its length but gives
//!   no number; `⌈len / (s·r)⌉` random positions per beam give the same expected number, and
//!   drawing from the traversed cells needs no extra look-ups).
//! * Fused cells are updated as a whole, as in the thesis (unless split, below).
//! * M and d were lost with the figure legends: M = 8, d = ⌈0.4·M⌉ by default.
//! * Beams longer than [`GridConfig::max_range_m`] are cut and free only (OctoMap's rule).
//! * Optional splitting of fused cells back into base cubes when an update would take them
//!   out of the clamped state ([`GridConfig::split_on_unclamp`], the thesis' future work).
//!   Splitting is exact and has no size limit: the changed base cubes are cut out and the
//!   rest of the cuboid is covered by halving cuboids (`O(k log V)` pieces).
//!
//! # Extension beyond Khan 2017: equal-value fusion
//!
//! [`FusionRule::EqualValue`] fuses cells whose log-odds are bit-equal `f32`s, clamped or
//! not — OctoMap's pruning rule (8 siblings with equal log-odds become their parent), but
//! with cuboids grown in the thesis' search-direction order. The thesis' clamped rule fuses
//! little when cells are seen a few times (a moving car at 0.2 m), while OctoMap prunes all
//! the free space a single scan sees once. The map stays exact: a scan's updates inside a
//! fused cell are collected; if they change every base cube to one value the cell is
//! updated whole, otherwise it is split (changed cubes plus halving cuboids with the old
//! value) before the updates apply, so every base cube carries the log-odds of an unfused
//! lattice (property-tested).
//!
//! # Example
//!
//! ```
//! use nalgebra::Point3;
//! use raypath_rtree_grid::{GridConfig, Occupancy, RtreeGrid};
//!
//! let mut grid = RtreeGrid::new(GridConfig::default()).unwrap();
//! // A wall at x = 4 m seen ten times from the origin.
//! let wall: Vec<Point3<f64>> = (0..20)
//!     .flat_map(|i| (0..10).map(move |j| Point3::new(4.1, -1.0 + 0.1 * f64::from(i), 0.05 + 0.1 * f64::from(j))))
//!     .collect();
//! for _ in 0..10 {
//!     grid.insert_scan(&Point3::origin(), &wall);
//! }
//! assert_eq!(grid.classify(&Point3::new(4.1, 0.0, 0.5)), Occupancy::Occupied);
//! assert_eq!(grid.classify(&Point3::new(2.0, 0.0, 0.5)), Occupancy::Free);
//! assert_eq!(grid.classify(&Point3::new(-2.0, 0.0, 0.5)), Occupancy::Unknown);
//! let stats = grid.stats();
//! assert!(stats.fused_leaves > 0 && stats.leaves < stats.base_cubes as usize);
//! ```

pub mod config;
mod export;
mod fused_index;
mod grid;
mod index;
pub mod key;
mod robin;
pub mod rtree;

pub use config::{FusionRule, GridConfig, Selection, SensorModel};
pub use grid::{Cuboid, GridError, GridStats, Occupancy, RtreeGrid, ScanUpdate};
pub use key::KeyBox;
pub use rtree::RTree;
