//! Cell fusion, `Fuse(g_i)` of Khan 2017, Fig. 2.7, with coverage and non-overlap checks that
//! the fusion conditions (Eqs. 2.9–2.11, §2.5.2) omit: as printed, a fused cuboid could
//! swallow unknown space or overlap a neighbouring cell.

use super::{RtreeGrid, SensorModel};
use crate::config::FusionRule;
use crate::key::{Key, KeyBox};

/// One search direction: an axis and a sign.
type Direction = (usize, bool);

/// The search-direction order S̄_i (Eq. 2.8): cubes try +x, +y, +z, −x, −y, −z; other
/// cuboids try ± of their longest axis first, then the second longest, then the shortest
/// (ties: x before y before z, + before −).
fn search_order(widths: [u32; 3]) -> [Direction; 6] {
    if widths[0] == widths[1] && widths[1] == widths[2] {
        return [
            (0, true),
            (1, true),
            (2, true),
            (0, false),
            (1, false),
            (2, false),
        ];
    }
    let mut axes = [0usize, 1, 2];
    axes.sort_by_key(|&a| std::cmp::Reverse(widths[a]));
    [
        (axes[0], true),
        (axes[0], false),
        (axes[1], true),
        (axes[1], false),
        (axes[2], true),
        (axes[2], false),
    ]
}

/// The slab `R̄_i \ R_i` of expanding `bx` by its own width along `direction`
/// (`R̄_i = R_i +^j S̄_i`), or `None` past the lattice edge.
fn slab(bx: &KeyBox, (axis, positive): Direction) -> Option<KeyBox> {
    let w = i32::from(bx.hi[axis]) - i32::from(bx.lo[axis]) + 1;
    let (lo, hi) = if positive {
        (i32::from(bx.hi[axis]) + 1, i32::from(bx.hi[axis]) + w)
    } else {
        (i32::from(bx.lo[axis]) - w, i32::from(bx.lo[axis]) - 1)
    };
    let mut s = *bx;
    s.lo[axis] = u16::try_from(lo).ok()?;
    s.hi[axis] = u16::try_from(hi).ok()?;
    Some(s)
}

impl RtreeGrid {
    /// Runs `Fuse(g_i)` on cell `id` (repeating on the fused cell, the thesis' recursive
    /// call); returns the number of fusion steps.
    pub(super) fn fuse(&mut self, mut id: u32) -> usize {
        let mut steps = 0;
        let mut members: Vec<u32> = Vec::new();
        loop {
            let cell = self.cell(id);
            if cell.log_odds.is_nan() {
                return steps; // removed earlier in this pass
            }
            if !self.may_fuse(cell.log_odds) {
                return steps;
            }
            if self.config.model == SensorModel::BeamEndPoint && cell.log_odds <= self.l_threshold {
                return steps; // §2.5.2, beam-end-point model: only occupied fusion
            }
            let mut fused = None;
            for direction in search_order(cell.bx.widths()) {
                let Some(slab) = slab(&cell.bx, direction) else {
                    continue;
                };
                if self.slab_fuses(&slab, cell.log_odds, &mut members) {
                    fused = Some(slab);
                    break;
                }
            }
            let Some(slab) = fused else {
                return steps;
            };
            // The fused cell's probability is the mean of its cells' (equal weight per
            // cell, g_i included); all are clamped to the same bound. Under the equal-value
            // rule all are bit-equal and the value is kept as it is.
            let value = match self.config.fusion_rule {
                FusionRule::EqualValue => cell.log_odds,
                FusionRule::Clamped => {
                    let mut sum = f64::from(cell.log_odds);
                    for &m in &members {
                        sum += f64::from(self.log_odds[m as usize]);
                    }
                    (sum / (members.len() + 1) as f64) as f32
                }
            };
            self.delete_cell(id);
            for &m in &members {
                self.delete_cell(m);
            }
            id = self.create_cell(cell.bx.union(&slab), value);
            steps += 1;
        }
    }

    /// Whether log-odds `other` may fuse with a seed of log-odds `seed`: clamped at the same
    /// bound (thesis), or bit-equal ([`FusionRule::EqualValue`]).
    #[inline]
    fn fuses_with(&self, seed: f32, other: f32) -> bool {
        match self.config.fusion_rule {
            FusionRule::EqualValue => seed.to_bits() == other.to_bits(),
            FusionRule::Clamped => {
                let c = self.is_clamped(seed);
                c.is_some() && self.is_clamped(other) == c
            }
        }
    }

    /// Whether the slab is exactly tiled by leaves lying completely inside it, all fusing
    /// with the seed's log-odds `seed` (Eqs. 2.9–2.11 plus the coverage and containment
    /// checks); fills `members` with them.
    fn slab_fuses(&self, slab: &KeyBox, seed: f32, members: &mut Vec<u32>) -> bool {
        members.clear();
        let mut volume = 0u64;
        let target = slab.volume();
        if target == 1 {
            // A single base cube: one index look-up.
            return match self.index.get(slab.lo, Self::key_of_cell(&self.tree)) {
                Some(id) if self.fuses_with(seed, self.log_odds[id as usize]) => {
                    members.push(id);
                    true
                }
                _ => false,
            };
        }
        if target <= SMALL_SLAB {
            match self.small_slab_fuses(slab, seed, members) {
                Some(answer) => return answer,
                None => members.clear(),
            }
        }
        // Necessary conditions on the slab's 8 corner cubes, checked with cheap look-ups
        // (hash probe; near fused cells the last-found cell and the block cache) before the
        // slab query: each must lie in a known cell of a fusing value inside the slab.
        // Corners the caches cannot place are left to the slab query (a negative R-tree
        // point query costs as much as the slab query).
        for corner in 0..8u8 {
            let key = [0, 1, 2].map(|a| {
                if corner & (1 << a) != 0 {
                    slab.hi[a]
                } else {
                    slab.lo[a]
                }
            });
            if !self.probe_passes(key, slab, seed) {
                return false;
            }
        }
        // Larger slabs: up to 4 × 4 × 4 more probes spread over the slab catch unknown gaps
        // and other values before the tree query.
        if !self.probes_pass(slab, seed) {
            return false;
        }
        let ok = self.tree.for_each_intersecting_while(slab, &mut |id, bx| {
            if !slab.contains_box(bx) || !self.fuses_with(seed, self.log_odds[id as usize]) {
                return false;
            }
            volume += bx.volume();
            members.push(id);
            true
        });
        ok && volume == target
    }
}

impl RtreeGrid {
    /// [`Self::slab_fuses`] for a small slab by looking up each of its base cubes (hash
    /// probes; fused cells through the caches), stopping at the first cube that fails;
    /// `None` when a cube needs a tree search.
    fn small_slab_fuses(&self, slab: &KeyBox, seed: f32, members: &mut Vec<u32>) -> Option<bool> {
        for z in slab.lo[2]..=slab.hi[2] {
            for y in slab.lo[1]..=slab.hi[1] {
                for x in slab.lo[0]..=slab.hi[0] {
                    let key = [x, y, z];
                    let id = match self.index.get(key, Self::key_of_cell(&self.tree)) {
                        Some(id) => id,
                        None if !self.coverage.may_contain(key) => return Some(false),
                        None => {
                            let id = self.fused_hint(key)?;
                            let Some(bx) = self.tree.item_box(id) else {
                                return Some(false);
                            };
                            if !slab.contains_box(&bx) {
                                return Some(false);
                            }
                            if bx.lo != key {
                                continue; // counted at its first cube (z, y, x order)
                            }
                            id
                        }
                    };
                    if !self.fuses_with(seed, self.log_odds[id as usize]) {
                        return Some(false);
                    }
                    members.push(id);
                }
            }
        }
        Some(true)
    }
}

impl RtreeGrid {
    /// One necessary condition of a slab fusion, checked with cheap look-ups (hash probe;
    /// near fused cells the last-found cell and the block cache): the base cube `key` lies
    /// in a known cell of a fusing value inside `slab`. `false` in unknown space or in a
    /// cell that cannot join; a key the caches cannot place passes (the slab query decides).
    fn probe_passes(&self, key: Key, slab: &KeyBox, seed: f32) -> bool {
        let id = match self.index.get(key, Self::key_of_cell(&self.tree)) {
            Some(id) => id,
            None if !self.coverage.may_contain(key) => return false, // unknown space
            None => match self.fused_hint(key) {
                Some(id) => id,
                None => return true,
            },
        };
        self.fuses_with(seed, self.log_odds[id as usize])
            && self
                .tree
                .item_box(id)
                .is_some_and(|b| slab.contains_box(&b))
    }

    /// Probes a lattice of up to 4 per axis spread over `slab`: `false` when a probe lies
    /// in unknown space or in a cell that cannot join the fusion (probes the caches cannot
    /// place pass).
    fn probes_pass(&self, slab: &KeyBox, seed: f32) -> bool {
        let steps = slab.widths().map(|w| (w / 4).max(1));
        let w = slab.widths();
        for iz in 0..w[2].min(4) {
            for iy in 0..w[1].min(4) {
                for ix in 0..w[0].min(4) {
                    let off = [ix, iy, iz];
                    let key: [u16; 3] = [0, 1, 2].map(|a| {
                        let k = u32::from(slab.lo[a]) + off[a] * steps[a] + steps[a] / 2;
                        k.min(u32::from(slab.hi[a])) as u16
                    });
                    if !self.probe_passes(key, slab, seed) {
                        return false;
                    }
                }
            }
        }
        true
    }
}

/// Slabs of at most this many base cubes are checked cube by cube instead of by a tree
/// query.
const SMALL_SLAB: u64 = 64;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_prefers_the_long_axis() {
        assert_eq!(
            search_order([1, 1, 1])[..3],
            [(0, true), (1, true), (2, true)]
        );
        assert_eq!(
            search_order([1, 4, 2])[..3],
            [(1, true), (1, false), (2, true)]
        );
    }

    #[test]
    fn slab_doubles_along_the_direction() {
        let b = KeyBox {
            lo: [10, 10, 10],
            hi: [11, 10, 10],
        };
        assert_eq!(
            slab(&b, (0, true)),
            Some(KeyBox {
                lo: [12, 10, 10],
                hi: [13, 10, 10]
            })
        );
        assert_eq!(
            slab(&b, (1, false)),
            Some(KeyBox {
                lo: [10, 9, 10],
                hi: [11, 9, 10]
            })
        );
        let edge = KeyBox {
            lo: [0, 0, 0],
            hi: [0, 0, 0],
        };
        assert_eq!(slab(&edge, (0, false)), None);
    }
}
