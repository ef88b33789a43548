//! The per-cell ray statistics `H_i`, `M_i`, `R_i` (Schaefer 2020, Sec. 7.4.2 and Table 8.1).

/// Fixed-point scale of the path-length accumulator: `2^32` units per metre
/// (resolution 2.3·10⁻¹⁰ m; a cell saturates after 4.3·10⁹ m of accumulated path).
pub(crate) const LENGTH_UNITS_PER_M: f64 = 4_294_967_296.0;

/// The statistics of one cell: hits `H_i` (rays reflected in the cell), misses `M_i` (rays
/// that crossed the cell without being reflected there) and total path length
/// `R_i = Σ_j d_i(j)` (metres travelled inside the cell by all rays, including the partial
/// segment of rays that end in it).
///
/// **Storage.** 16 bytes: two `u32` counters and the path length as a `u64` fixed-point
/// number of `2^-32` m (the public accessors speak `f64` metres). Integer accumulation is
/// associative, so maps built in parallel with any number of threads and any split of the
/// rays are bit-identical; an `f64` sum would depend on the order of additions. Counters
/// saturate (at 4.29·10⁹ rays, resp. 4.3·10⁹ m) instead of wrapping; rounding each in-cell
/// length to 2^-32 m adds at most 1.2·10⁻¹⁰ m per crossing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct CellStats {
    hits: u32,
    misses: u32,
    length_units: u64,
}

impl CellStats {
    /// A cell no ray has entered.
    pub const EMPTY: CellStats = CellStats {
        hits: 0,
        misses: 0,
        length_units: 0,
    };

    /// Statistics from counts and a path length in metres. The length is rounded to the
    /// fixed-point resolution; negative or NaN lengths become 0, huge ones saturate.
    pub fn new(hits: u32, misses: u32, path_length_m: f64) -> Self {
        Self {
            hits,
            misses,
            length_units: to_units(path_length_m),
        }
    }

    /// Number of rays reflected in the cell, `H_i`.
    #[inline]
    pub fn hits(&self) -> u32 {
        self.hits
    }

    /// Number of rays that crossed the cell (with positive length) without a reflection,
    /// `M_i`.
    #[inline]
    pub fn misses(&self) -> u32 {
        self.misses
    }

    /// Total path length `R_i` in metres.
    #[inline]
    pub fn path_length_m(&self) -> f64 {
        self.length_units as f64 / LENGTH_UNITS_PER_M
    }

    /// `H_i` as `f64`.
    #[inline]
    pub fn h(&self) -> f64 {
        f64::from(self.hits)
    }

    /// `M_i` as `f64`.
    #[inline]
    pub fn m(&self) -> f64 {
        f64::from(self.misses)
    }

    /// True when no ray has touched the cell (`H = M = R = 0`).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.hits == 0 && self.misses == 0 && self.length_units == 0
    }

    /// Records a ray that crosses the cell for `length_m` metres without reflection. A
    /// zero-length crossing (through an edge or corner) adds nothing.
    #[inline(always)]
    pub(crate) fn add_miss(&mut self, length_m: f64) {
        let units = to_units(length_m);
        self.misses = self.misses.saturating_add(u32::from(units > 0));
        self.length_units = self.length_units.saturating_add(units);
    }

    /// Records a ray that travels `length_m` metres in the cell and is reflected there.
    #[inline(always)]
    pub(crate) fn add_hit(&mut self, length_m: f64) {
        self.hits = self.hits.saturating_add(1);
        self.length_units = self.length_units.saturating_add(to_units(length_m));
    }

    /// Adds another cell's statistics (saturating).
    #[inline]
    pub fn merge(&mut self, other: &CellStats) {
        self.hits = self.hits.saturating_add(other.hits);
        self.misses = self.misses.saturating_add(other.misses);
        self.length_units = self.length_units.saturating_add(other.length_units);
    }
}

/// Metres to fixed-point units, rounding to nearest; negative and NaN give 0.
#[inline(always)]
fn to_units(length_m: f64) -> u64 {
    // `max` maps NaN and negative values to 0; `as i64` (one instruction, unlike `as u64`)
    // saturates, so the result is at most 2^63 − 1 and never wraps.
    (length_m.max(0.0) * LENGTH_UNITS_PER_M + 0.5) as i64 as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accumulates_and_rounds() {
        let mut cell = CellStats::EMPTY;
        cell.add_miss(0.25);
        cell.add_miss(0.0);
        cell.add_hit(0.125);
        assert_eq!((cell.hits(), cell.misses()), (1, 1));
        assert_eq!(cell.path_length_m(), 0.375);
        let mut sum = CellStats::new(1, 2, 1.5);
        sum.merge(&cell);
        assert_eq!(sum, CellStats::new(2, 3, 1.875));
        assert!(CellStats::new(0, 0, -1.0).is_empty());
        assert!(CellStats::new(0, 0, f64::NAN).is_empty());
        let mut full = CellStats::new(u32::MAX, u32::MAX, 0.0);
        full.add_hit(1.0);
        full.add_miss(1.0);
        assert_eq!((full.hits(), full.misses()), (u32::MAX, u32::MAX));
    }
}
