//! Exact updates of fused cells (split-on-update).
//!
//! With [`FusionRule::EqualValue`](crate::FusionRule::EqualValue), or the thesis' rule with
//! `split_on_unclamp`, a fused cell must keep the value an unfused lattice would give each
//! of its base cubes. The updates a scan makes inside fused cells are collected per cell;
//! when they change every base cube to one value the cell is updated whole, otherwise it is
//! replaced by the changed base cubes (new values) and cuboids covering the rest with the
//! old value. The rest is covered by halving the cuboid along its longest axis until a half
//! holds no changed cube: `O(k · log V)` pieces for `k` changed cubes in a cell of `V` base
//! cubes, instead of `V` base cubes.

use super::{RtreeGrid, ScanUpdate};
use crate::key::{Key, KeyBox, unpack};

impl RtreeGrid {
    /// Applies the queued exact updates of fused cells, splitting them where needed; the
    /// changed base cubes join `selected` (fusion seeds) when fusion is on.
    pub(super) fn apply_exact_updates(
        &mut self,
        selected: &mut super::fuse::Seeds,
        update: &mut ScanUpdate,
    ) {
        let mut touched = std::mem::take(&mut self.touched_exact);
        touched.sort_unstable_by_key(|&(id, key, _)| (id, key));
        let mut changed: Vec<(Key, f32)> = Vec::new();
        let mut start = 0;
        while start < touched.len() {
            let id = touched[start].0;
            let end = start + touched[start..].partition_point(|t| t.0 == id);
            let group = &touched[start..end];
            start = end;
            let cell = self.cell(id);
            if cell.log_odds.is_nan() {
                continue;
            }
            changed.clear();
            changed.extend(
                group
                    .iter()
                    .map(|&(_, key, hit)| (unpack(key), self.updated(cell.log_odds, hit))),
            );
            let Some(&(_, first)) = changed.first() else {
                continue;
            };
            if group.len() as u64 == cell.bx.volume()
                && changed.iter().all(|c| c.1.to_bits() == first.to_bits())
            {
                self.set_lo(id, first);
                continue;
            }
            self.delete_cell(id);
            update.splits += 1;
            self.create_pieces(cell.bx, cell.log_odds, &mut changed, selected);
        }
        touched.clear();
        self.touched_exact = touched;
    }

    /// Covers `bx` with cells: the base cubes in `changed` with their new values, the rest
    /// with halving cuboids of value `old`.
    fn create_pieces(
        &mut self,
        bx: KeyBox,
        old: f32,
        changed: &mut [(Key, f32)],
        selected: &mut super::fuse::Seeds,
    ) {
        if changed.is_empty() {
            self.create_cell(bx, old);
            return;
        }
        if bx.volume() == 1 {
            self.create_cell(bx, changed[0].1);
            if self.config.fusion && self.may_fuse(changed[0].1) {
                selected.push(&bx);
            }
            return;
        }
        let widths = bx.widths();
        let axis = (0..3).max_by_key(|&a| (widths[a], 3 - a)).unwrap_or(0);
        // Low half lo..=mid, high half mid+1..=hi (widths[axis] ≥ 2 here).
        let mid = bx.lo[axis] + ((widths[axis] - 1) / 2) as u16;
        let mut low_len = 0;
        for i in 0..changed.len() {
            if changed[i].0[axis] <= mid {
                changed.swap(i, low_len);
                low_len += 1;
            }
        }
        let (low, high) = changed.split_at_mut(low_len);
        let mut low_box = bx;
        low_box.hi[axis] = mid;
        let mut high_box = bx;
        high_box.lo[axis] = mid + 1;
        self.create_pieces(low_box, old, low, selected);
        self.create_pieces(high_box, old, high, selected);
    }
}
