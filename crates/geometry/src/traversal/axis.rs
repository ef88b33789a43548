//! The per-axis set-up of a grid walk (Amanatides & Woo 1987), shared by [`Traversal`] and
//! [`SlabWalk`]: from a segment already clipped to the grid box, the first voxel along the
//! axis, the number of steps, the direction of the steps, and the `t` of the first boundary.
//! Both walks take it from here so that they start, end and step in the same voxels.
//!
//! [`Traversal`]: super::Traversal
//! [`SlabWalk`]: super::SlabWalk

/// The set-up of one axis of a walk, from [`axis_setup`].
#[derive(Clone, Copy, Debug)]
pub(super) struct AxisSetup {
    /// Index of the first cell along the axis.
    pub start: usize,
    /// Steps along the axis.
    pub steps: usize,
    /// Whether the steps go towards higher indices (also for an axis without steps).
    pub up: bool,
    /// Index of the first boundary crossed (`start + 1` up, `start` down).
    pub boundary: f64,
    /// Grid origin minus segment origin along the axis, metres.
    pub offset: f64,
    /// `1 / direction`, or 0 when the axis does not move (zero or subnormal component).
    pub inv: f64,
    /// `t` of the first boundary crossed, clamped to the segment end (`+∞` without steps).
    pub t_next: f64,
}

/// The set-up of one axis for the segment `o + t · d`, `t ∈ [t_start, t_end]` (already
/// clipped to the grid box; `clipped_at_end` when the box, not the segment, bounds
/// `t_end`), on a grid axis starting at `g` with `dim` cells of edge `cell`.
///
/// The first cell is the one occupied just after the start; the last is `cell_of` the
/// endpoint (ties to the larger index) or, when the box cuts the segment, the one occupied
/// just before it leaves. The two rules disagree only when the coordinate does not change
/// at all (start and end on the same face, up to rounding): then the axis does not move
/// and, like a zero component, uses the `cell_of` tie-break at both ends. Rounding can
/// never reverse the direction of travel.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn axis_setup(
    o: f64,
    d: f64,
    g: f64,
    cell: f64,
    dim: usize,
    t_start: f64,
    t_end: f64,
    clipped_at_end: bool,
) -> AxisSetup {
    let inv = 1.0 / d;
    // Tiny (subnormal) components whose reciprocal overflows count as zero.
    let moving = d != 0.0 && inv.is_finite();
    let u_start = ((o + d * t_start) - g) / cell;
    let u_end = ((o + d * t_end) - g) / cell;
    let start = if moving && d < 0.0 {
        ceil_minus_one_cell(u_start, dim)
    } else {
        floor_cell(u_start, dim)
    };
    let end = if clipped_at_end && d > 0.0 {
        ceil_minus_one_cell(u_end, dim)
    } else {
        floor_cell(u_end, dim)
    };
    let (start, steps, up) = if !moving {
        (start, 0, true)
    } else if d > 0.0 {
        (start, end.saturating_sub(start), true)
    } else {
        let start = start.max(end);
        (start, start - end, false)
    };
    let boundary = if up { (start + 1) as f64 } else { start as f64 };
    let offset = g - o;
    let inv = if moving { inv } else { 0.0 };
    let t_next = if steps == 0 {
        f64::INFINITY
    } else {
        boundary_t(offset, boundary, cell, inv, t_end)
    };
    AxisSetup {
        start,
        steps,
        up,
        boundary,
        offset,
        inv,
        t_next,
    }
}

/// `t` of a boundary, `(offset + boundary · cell) · inv`, clamped to the segment end (a NaN
/// from overflow also becomes `t_end`: the comparison is false).
#[inline(always)]
pub(super) fn boundary_t(offset: f64, boundary: f64, cell: f64, inv: f64, t_end: f64) -> f64 {
    let t = (offset + boundary * cell) * inv;
    if t < t_end { t } else { t_end }
}

/// `floor(value)` as an integer, saturating (NaN gives 0): `value.floor() as i64` without
/// a libm call.
#[inline(always)]
pub(super) fn floor_i64(value: f64) -> i64 {
    let truncated = value as i64;
    if (truncated as f64) > value {
        truncated.saturating_sub(1)
    } else {
        truncated
    }
}

/// `floor(value)` clamped to a cell index `0..dim` (the same index as
/// `(value.floor() as i64).clamp(0, dim − 1)`).
#[inline(always)]
fn floor_cell(value: f64, dim: usize) -> usize {
    floor_i64(value).clamp(0, dim.saturating_sub(1) as i64) as usize
}

/// `ceil(value) − 1` clamped to `0..dim` (the same index as
/// `((value.ceil() − 1.0) as i64).clamp(0, dim − 1)`).
#[inline(always)]
fn ceil_minus_one_cell(value: f64, dim: usize) -> usize {
    let truncated = value as i64;
    let ceil = if (truncated as f64) < value {
        truncated.saturating_add(1)
    } else {
        truncated
    };
    ceil.saturating_sub(1)
        .clamp(0, dim.saturating_sub(1) as i64) as usize
}

#[cfg(test)]
mod tests {
    use super::{ceil_minus_one_cell, floor_cell};

    /// The libm-free cell helpers give the indices of the float `floor`/`ceil` forms.
    #[test]
    fn cell_helpers_match_float_rounding() {
        let values = [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.999_999,
            3.0,
            3.000_001,
            7.0,
            7.5,
            8.0,
            1e300,
            -1e300,
            9.3e18,
            -9.3e18,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE,
        ];
        for dim in [1usize, 2, 8, 1000] {
            let max = dim as i64 - 1;
            for &v in &values {
                assert_eq!(
                    floor_cell(v, dim),
                    (v.floor() as i64).clamp(0, max) as usize,
                    "{v}"
                );
                assert_eq!(
                    ceil_minus_one_cell(v, dim),
                    ((v.ceil() - 1.0) as i64).clamp(0, max) as usize,
                    "{v}"
                );
            }
        }
    }
}
