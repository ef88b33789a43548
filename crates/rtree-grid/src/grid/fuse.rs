//! Cell fusion, `Fuse(g_i)` of Khan 2017, Fig. 2.7, with coverage and non-overlap checks that
//! the fusion conditions (Eqs. 2.9–2.11, §2.5.2) omit: as printed, a fused cuboid could
//! swallow unknown space or overlap a neighbouring cell.

use super::id_bits::IdBits;
use super::{RtreeGrid, SensorModel};
use crate::config::FusionRule;
use crate::key::{Key, KeyBox, from_morton, morton};

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

/// Fusion seeds: the Morton codes of the lower and upper corners of the cells selected since
/// the last fusion pass (16 bytes a seed). A fusion interval of several scans selects the same
/// cells again and again, so the list is sorted and de-duplicated whenever it has doubled.
#[derive(Clone, Debug, Default)]
pub(super) struct Seeds {
    codes: Vec<(u64, u64)>,
    unique: usize,
}

impl Seeds {
    #[inline]
    pub(super) fn push(&mut self, bx: &KeyBox) {
        self.codes.push((morton(bx.lo), morton(bx.hi)));
    }

    /// Sorts and de-duplicates once the list has doubled since the last time.
    pub(super) fn tidy(&mut self) {
        if self.codes.len() > 2 * self.unique + 4096 {
            self.sort();
        }
    }

    fn sort(&mut self) {
        self.codes.sort_unstable();
        self.codes.dedup();
        self.unique = self.codes.len();
    }

    /// The lower corners of the seeds in Morton order of the lower, then of the upper
    /// corners, each box once; empties the list (keeping its buffer).
    fn drain_sorted(&mut self) -> impl Iterator<Item = Key> + '_ {
        self.sort();
        self.unique = 0;
        self.codes.drain(..).map(|(lo, _)| from_morton(lo))
    }

    /// Bytes held (kept between passes).
    pub(super) fn memory_bytes(&self) -> usize {
        self.codes.capacity() * size_of::<(u64, u64)>()
    }

    /// Releases spare capacity.
    pub(super) fn shrink_to_fit(&mut self) {
        self.codes.shrink_to_fit();
    }
}

/// The cells of one fusion pass that no slab can join: within a pass a slab that failed
/// keeps failing (unknown cubes stay unknown, values stay, and fusion only makes the cells
/// reaching into it larger), so a later seed in such a cell would repeat the same six failed
/// slab walks. A bit per cell id; an id freed and reused within the pass loses its bit.
#[derive(Clone, Debug, Default)]
pub(super) struct Settled {
    bits: IdBits,
    ids: Vec<u32>,
}

impl Settled {
    fn mark(&mut self, id: u32) {
        self.bits.insert(id);
        self.ids.push(id);
    }

    fn contains(&self, id: u32) -> bool {
        self.bits.contains(id)
    }

    /// Forgets `id` (a new cell took it).
    #[inline]
    pub(super) fn unmark(&mut self, id: u32) {
        self.bits.remove(id);
    }

    /// Forgets every cell (the end of a pass).
    pub(super) fn clear(&mut self) {
        for &id in &self.ids {
            self.bits.remove(id);
        }
        self.ids.clear();
    }
}

impl RtreeGrid {
    /// Fuses from the selected cells in Morton order of their lower corners (then of their
    /// upper corners); a seed fused into a larger cell or split since it was selected starts
    /// from the cell now holding its lower corner. The leaves depend on the scans only, not
    /// on cell ids or the tree's shape.
    pub(super) fn fuse_seeds(&mut self) -> usize {
        let mut seeds = std::mem::take(&mut self.selected);
        let mut steps = 0;
        for lo in seeds.drain_sorted() {
            if let Some(id) = self.cell_id_of_key(lo) {
                steps += self.fuse(id);
            }
        }
        self.selected = seeds;
        self.settled.clear();
        steps
    }

    /// Runs `Fuse(g_i)` on cell `id` (repeating on the fused cell, the thesis' recursive
    /// call); returns the number of fusion steps. A cell settled earlier in the pass is
    /// skipped (the result is the same).
    pub(super) fn fuse(&mut self, mut id: u32) -> usize {
        if self.settled.contains(id) {
            return 0;
        }
        let mut steps = 0;
        let mut members = std::mem::take(&mut self.members);
        while let Some(next) = self.fuse_step(id, &mut members) {
            id = next;
            steps += 1;
        }
        self.settled.mark(id);
        self.members = members;
        steps
    }

    /// One step of `Fuse(g_i)` on cell `id`: merges it with the slab of the first search
    /// direction that fuses (`members` is scratch); returns the fused cell.
    fn fuse_step(&mut self, id: u32, members: &mut Vec<u32>) -> Option<u32> {
        let cell = self.cell(id);
        if cell.log_odds.is_nan() || !self.may_fuse(cell.log_odds) {
            return None; // removed earlier in this pass, or cannot fuse
        }
        if self.config.model == SensorModel::BeamEndPoint && cell.log_odds <= self.l_threshold {
            return None; // §2.5.2, beam-end-point model: only occupied fusion
        }
        let slab = search_order(cell.bx.widths())
            .into_iter()
            .filter_map(|direction| slab(&cell.bx, direction))
            .find(|slab| self.slab_fuses(slab, cell.log_odds, members))?;
        let value = self.fused_value(cell.log_odds, members);
        self.delete_cell(id);
        for &m in members.iter() {
            self.delete_cell(m);
        }
        Some(self.create_cell(cell.bx.union(&slab), value))
    }

    /// The log-odds of a fused cell from the seed's and its `members'`: the mean (equal
    /// weight per cell, g_i included; all are clamped to the same bound), or under the
    /// equal-value rule the common value as it is.
    fn fused_value(&self, seed: f32, members: &[u32]) -> f32 {
        match self.config.fusion_rule {
            FusionRule::EqualValue => seed,
            FusionRule::Clamped => {
                let sum = members
                    .iter()
                    .fold(f64::from(seed), |sum, &m| sum + f64::from(self.lo(m)));
                (sum / (members.len() + 1) as f64) as f32
            }
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
    /// checks); fills `members` with them in lattice order (z, y, x of their lower corners).
    ///
    /// Each row of the slab is walked with point look-ups (lattice index, fused-cell index),
    /// jumping over the cell found; the first cube in unknown space, in a cell reaching out
    /// of the slab or of another value ends the walk. Large slabs first test their corners.
    fn slab_fuses(&self, slab: &KeyBox, seed: f32, members: &mut Vec<u32>) -> bool {
        members.clear();
        let volume = slab.volume();
        if volume == 1 {
            // Only an unfused cube fits: one lattice-index probe.
            let id = self.index.get(slab.lo, Self::key_of_cell(&self.tree));
            return match id {
                Some(id) if self.fuses_with(seed, self.lo(id)) => {
                    members.push(id);
                    true
                }
                _ => false,
            };
        }
        if volume > CORNER_CHECK && !self.corners_join(slab, seed) {
            return false;
        }
        for z in slab.lo[2]..=slab.hi[2] {
            for y in slab.lo[1]..=slab.hi[1] {
                let mut x = u32::from(slab.lo[0]);
                while x <= u32::from(slab.hi[0]) {
                    let key = [x as u16, y, z];
                    let Some((id, bx)) = self.joining_cell(key, slab, seed) else {
                        return false;
                    };
                    if bx.lo == key {
                        members.push(id); // counted at its first cube
                    }
                    x = u32::from(bx.hi[0]) + 1;
                }
            }
        }
        true
    }

    /// The cell holding base cube `key` if it lies inside `slab` and fuses with `seed`.
    #[inline]
    fn joining_cell(&self, key: Key, slab: &KeyBox, seed: f32) -> Option<(u32, KeyBox)> {
        let (id, bx) = self.lookup(key)?;
        (slab.contains_box(&bx) && self.fuses_with(seed, self.lo(id))).then_some((id, bx))
    }

    /// Whether the cells at the slab's 8 corner cubes may join (a necessary condition).
    fn corners_join(&self, slab: &KeyBox, seed: f32) -> bool {
        (0..8u8).all(|corner| {
            let key = [0, 1, 2].map(|a| {
                if corner & (1 << a) != 0 {
                    slab.hi[a]
                } else {
                    slab.lo[a]
                }
            });
            self.joining_cell(key, slab, seed).is_some()
        })
    }
}

/// Slabs of more than this many base cubes test their corners before the row walk.
const CORNER_CHECK: u64 = 64;

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
