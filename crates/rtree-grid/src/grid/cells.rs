//! The leaf cells between R-tree updates: creation, deletion, point look-up and the
//! per-scan commit of the changes to the R-tree.
//!
//! During a scan every look-up goes through the lattice index (unfused base cubes) and the
//! fused-cell index, never through the tree, so the tree need not follow each step of the
//! scan: cells created and fused away within one scan (fusion chains, split pieces that
//! re-fuse) never enter it. [`RtreeGrid::commit`] applies the net change once per scan —
//! Guttman's Delete for the cells of the tree that died, then Insert for the new cells that
//! live (Khan 2017, §2.4) — so between public calls the tree holds exactly the leaves.

use super::id_bits::IdBits;
use super::{Cell, RtreeGrid};
use crate::index::LatticeIndex;
use crate::key::{Key, KeyBox, pack};
use crate::rtree::RTree;

/// The box read for an id with none (never contains a cube the grid asks about).
const KEYLESS: KeyBox = KeyBox {
    lo: [u16::MAX; 3],
    hi: [0; 3],
};

/// The leaf-set changes not yet applied to the R-tree.
#[derive(Clone, Debug, Default)]
pub(super) struct Pending {
    /// Cells created since the last commit (some may have died since).
    created: Vec<u32>,
    /// One bit per cell id: created since the last commit and alive.
    fresh: IdBits,
    /// Cells of the tree deleted since the last commit (their ids are reused after it).
    dead: Vec<u32>,
    /// Commit scratch: the live new cells (lattice order key, id, box).
    order: Vec<(u64, u32, KeyBox)>,
}

impl Pending {
    #[inline]
    fn set(&mut self, id: u32) {
        self.fresh.insert(id);
    }

    /// Clears the bit of `id`; returns whether it was set.
    #[inline]
    fn take(&mut self, id: u32) -> bool {
        self.fresh.remove(id)
    }

    /// Bytes of the bit set (the lists are per-scan scratch).
    pub(super) fn memory_bytes(&self) -> usize {
        self.fresh.memory_bytes()
    }

    /// Releases spare capacity (nothing may be pending).
    pub(super) fn shrink_to_fit(&mut self) {
        *self = Self::default();
    }
}

impl RtreeGrid {
    /// The key of cell `id`'s lower corner (the key of an unfused cell).
    #[inline]
    pub(super) fn key_of_cell(tree: &RTree) -> impl Fn(u32) -> Key + '_ {
        move |id| tree.item_box(id).map_or([u16::MAX; 3], |b| b.lo)
    }

    /// The box of cell `id` as the indexes read it.
    #[inline]
    fn box_of_cell(tree: &RTree) -> impl Fn(u32) -> KeyBox + '_ {
        move |id| tree.item_box(id).unwrap_or(KEYLESS)
    }

    /// The cell containing base cube `key`, with its box: a lattice-index probe (unfused
    /// cubes), then the fused-cell index.
    #[inline]
    pub(super) fn lookup(&self, key: Key) -> Option<(u32, KeyBox)> {
        let tree = &self.tree;
        let id = match self.index.get(key, Self::key_of_cell(tree)) {
            Some(id) => id,
            None => self.fused.find(key, Self::box_of_cell(tree))?,
        };
        Some((id, Self::box_of_cell(tree)(id)))
    }

    /// The id of the cell containing base cube `key`.
    #[inline]
    pub(super) fn cell_id_of_key(&self, key: Key) -> Option<u32> {
        self.lookup(key).map(|(id, _)| id)
    }

    /// Creates a cell (in the indexes now, in the tree at the next commit).
    pub(super) fn create_cell(&mut self, bx: KeyBox, log_odds: f32) -> u32 {
        let id = match self.free_cells.pop() {
            Some(id) => id,
            None => self.tree.item_slots() as u32,
        };
        self.tree.store_item(id, bx, log_odds.to_bits());
        self.settled.unmark(id);
        self.pending.set(id);
        self.pending.created.push(id);
        let tree = &self.tree;
        if bx.volume() == 1 {
            self.index.insert(bx.lo, id, Self::key_of_cell(tree));
        } else {
            self.fused_cells += 1;
            self.fused.insert(id, &bx, Self::box_of_cell(tree));
        }
        id
    }

    /// Deletes a cell from the indexes (from the tree at the next commit); a cell created
    /// since the last commit frees its id at once.
    pub(super) fn delete_cell(&mut self, id: u32) -> Cell {
        let cell = self.cell(id);
        if cell.bx.volume() == 1 {
            self.index.remove(cell.bx.lo, Self::key_of_cell(&self.tree));
        } else {
            self.fused_cells -= 1;
            self.fused.remove(id, &cell.bx);
        }
        self.set_lo(id, f32::NAN);
        if self.pending.take(id) {
            self.free_cells.push(id);
        } else {
            self.pending.dead.push(id);
        }
        cell
    }

    /// Rebuilds both indexes from the cells of the tree with room for `room` times as many
    /// (nothing pending).
    pub(super) fn rebuild_indexes(&mut self, room: usize) {
        let mut index = LatticeIndex::with_capacity(room * (self.tree.len() - self.fused_cells));
        let mut fused = Vec::with_capacity(self.fused_cells);
        let tree = &self.tree;
        tree.for_each_item(&mut |id, bx| {
            if bx.volume() == 1 {
                index.place(bx.lo, id, Self::key_of_cell(tree));
            } else {
                fused.push((id, *bx));
            }
        });
        self.index = index;
        self.fused.rebuild(&fused, room, Self::box_of_cell(tree));
    }

    /// Applies the changes since the last commit to the R-tree: removes the dead cells (one
    /// batch: a single CondenseTree pass, no dead entry re-inserted), then inserts the live
    /// new ones in lattice order (z, y, x of the lower corner; neighbours descend the same
    /// paths). Freed ids are reused from here on.
    pub(super) fn commit(&mut self) {
        let mut pending = std::mem::take(&mut self.pending);
        let mut created = std::mem::take(&mut pending.created);
        let mut order = std::mem::take(&mut pending.order);
        order.clear();
        // Live new cells, each once (an id freed and reused is listed twice).
        for &id in &created {
            if pending.take(id) {
                let bx = self.cell(id).bx;
                order.push((pack(bx.lo), id, bx));
            }
        }
        order.sort_unstable_by_key(|&(key, id, _)| (key, id));
        self.tree.remove_many(&pending.dead);
        for &(_, id, bx) in &order {
            self.tree.insert(id, bx);
        }
        self.free_cells.append(&mut pending.dead);
        pending.order = order;
        created.clear();
        pending.created = created;
        self.pending = pending;
    }
}
