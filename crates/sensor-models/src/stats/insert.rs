//! Inserting one ray into any statistics store (the inner loop of MAP-DECAY).

use crate::Reading;
use crate::dimension::{Crossing, Dimension};
use crate::stats::{CellStats, MappingConfig, MappingSummary};

/// A store of per-cell statistics that a ray can be written into.
pub(crate) trait StatsSink<D: Dimension> {
    /// The grid the store covers.
    fn sink_grid(&self) -> &D::Grid;
    /// The statistics of the crossed cell (created on demand by sparse stores).
    fn cell_mut(&mut self, crossing: &D::Crossing) -> &mut CellStats;
    /// The running summary.
    fn summary_mut(&mut self) -> &mut MappingSummary;
}

/// Algorithm MAP-DECAY step 2 (Schaefer 2020, Sec. 7.4.2) for one ray in the map frame:
/// every entered cell gets its in-cell length added to `R_i`; cells other than the
/// endpoint cell get `M_i += 1`; the endpoint cell gets `H_i += 1`.
///
/// Edge cases (recorded in the crate docs):
/// * endpoint outside the grid: the in-grid cells are all misses, no hit;
/// * endpoint exactly on a cell face: the hit goes to the cell that `Grid::cell_of` gives
///   (the larger index), which the traversal reports last with zero length;
/// * zero-length crossings (through an edge or corner) are not misses;
/// * zero-length rays record nothing;
/// * no-returns are traced to `r_max` as misses when `include_no_returns` is set;
/// * `sub` readings are ignored.
#[inline]
pub(crate) fn insert_ray<D: Dimension, S: StatsSink<D>>(
    sink: &mut S,
    ray: &D::Ray,
    config: &MappingConfig,
) {
    sink.summary_mut().rays += 1;
    let (length_m, is_hit) = match config.range.classify(D::range(ray)) {
        Reading::Hit(r) => (r, true),
        Reading::Sup if config.include_no_returns => (config.range.max_range_m, false),
        Reading::Sup => {
            sink.summary_mut().no_returns_skipped += 1;
            return;
        }
        Reading::Sub => {
            sink.summary_mut().sub_ignored += 1;
            return;
        }
    };
    let grid = *sink.sink_grid();
    let endpoint_inside = is_hit && D::cell_index_at(&grid, ray, length_m).is_some();
    let mut traversal = D::traverse(&grid, ray, length_m);
    let Some(first) = traversal.next() else {
        sink.summary_mut().empty += 1;
        return;
    };
    let mut crossings = 1u64;
    // One step behind: a crossing is a miss once we know it is not the last.
    let last = traversal.fold(first, |previous, crossing| {
        sink.cell_mut(&previous).add_miss(previous.length());
        crossings += 1;
        crossing
    });
    let cell = sink.cell_mut(&last);
    if endpoint_inside {
        cell.add_hit(last.length());
    } else {
        cell.add_miss(last.length());
    }
    let summary = sink.summary_mut();
    summary.crossings += crossings;
    if endpoint_inside {
        summary.hits += 1;
    } else if is_hit {
        summary.endpoints_outside += 1;
    } else {
        summary.no_returns_traced += 1;
    }
}
