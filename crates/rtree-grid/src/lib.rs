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
//!   payload-in-place update by id and stores `f64`/generic envelopes. [`RTree`] is an
//!   arena (flat vectors, `M + 1` entry slots per node, no per-node heap allocation) over
//!   16-bit integer boxes ([`KeyBox`], 12 bytes), so a leaf entry costs 16 bytes.
//! * **Payload outside the tree.** Cells are `(box, log-odds)` records of 16 bytes in an
//!   arena; the tree stores their ids. Updating occupancy never touches the tree.
//! * **O(1) updates of unfused cells.** A lattice index (open addressing, 4 bytes per slot)
//!   maps a base-cube key to its cell, so a scan update is a hash probe, not an R-tree
//!   descent; only keys missing from the index (new cells or cells inside fused cuboids)
//!   search the tree.
//! * **Batched scans.** A scan is traversed once into vectors of packed keys, sorted and
//!   de-duplicated (occupied wins over free, OctoMap's `insertPointCloud` rule, our
//!   decision §2.D), then applied; fused cells get at most one update per scan.
//! * **Fusion only from selected cells**, as in the thesis (§2.F.1): end-point cells plus
//!   cells sampled along each beam ([`Selection`]).
//!
//! Per scan with `n` beams crossing `c` distinct cubes: traversal `O(c)`, sorting
//! `O(c log c)`, updates `O(c)` hash probes plus `O(log N)` tree work for each new cell, and
//! fusion `O(|T| · (log N + k))` for `|T|` selected cells and `k` leaves per slab query.
//!
//! # Errata and decisions (spec §2.F.4 flags)
//!
//! * A slab fuses only if it is **exactly tiled** by leaves lying completely inside it, all
//!   clamped with the polarity of `g_i` — coverage and non-overlap checks the thesis omits.
//! * The fused probability is the equal-weight mean over the cells (g_i included).
//! * Cells removed earlier in the same pass are skipped; + before − per axis.
//! * M and d were lost with the figure legends: M = 8, d = ⌈0.4·M⌉ by default.
//! * Beams longer than [`GridConfig::max_range_m`] are cut and free only (OctoMap's rule).
//! * Optional splitting of fused cells back into base cubes when an update would take them
//!   out of the clamped state ([`GridConfig::split_on_unclamp`], the thesis' future work).
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
mod coverage;
mod export;
mod grid;
mod index;
pub mod key;
pub mod rtree;

pub use config::{GridConfig, Selection, SensorModel};
pub use grid::{Cuboid, GridError, GridStats, Occupancy, RtreeGrid, ScanUpdate};
pub use key::KeyBox;
pub use rtree::RTree;
