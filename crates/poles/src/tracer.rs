//! A voxel walk specialised for hit/miss counting: the exact traversal of
//! `raypath-geometry`'s [`Grid3::traverse`] (Amanatides & Woo 1987, with its clipping, tie and
//! face rules), reduced to what the counts need.
//!
//! The walk visits the same voxels as `Grid3::traverse` because it performs the same floating
//! point operations in the same order: the segment is clipped to the grid box by the slab
//! method, the first and last voxel per axis come from the clipped start and end points (which
//! fixes how many steps each axis takes), and the boundary parameters
//! `t = (grid origin − ray origin + boundary · cell) / direction`, clamped to the clipped end,
//! only order the steps (ties step the higher axis first). What it drops is everything the
//! counts do not use: the crossing intervals, the per-axis cell coordinates, the iterator
//! protocol. The grid geometry (box, strides) is computed once per grid, not once per ray, and
//! the state of the walk lives in registers: one linear index stepped by `±1`, `±nx` or
//! `±nx·ny`, three boundary parameters and three step counters.
//!
//! The module's tests compare the counts with a reference built on `Grid3::traverse` for
//! random rays, including rays from outside the grid, axis-parallel rays and rays ending on
//! voxel faces and edges.

use nalgebra::Point3;
use raypath_geometry::Grid3;

/// The grid geometry the walk needs, precomputed once.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tracer {
    /// Lower corner of the grid box, metres.
    min: [f64; 3],
    /// Upper corner of the grid box, metres (as `Grid3::bounds`).
    max: [f64; 3],
    /// Voxel edge, metres.
    cell: f64,
    /// Voxels per axis.
    dims: [usize; 3],
    /// Linear index strides per axis (`1`, `nx`, `nx · ny`).
    strides: [usize; 3],
}

/// Per-axis set-up of one walk.
#[derive(Clone, Copy)]
struct Axis {
    /// Index of the first voxel along the axis.
    start: usize,
    /// Steps along the axis.
    steps: usize,
    /// `t` of the first boundary crossed (`+∞` without steps).
    t_next: f64,
    /// Index of that boundary (an exact small integer).
    boundary: f64,
    /// `±1`.
    boundary_step: f64,
    /// `±stride` as a wrapping `usize`.
    index_step: usize,
    /// Grid origin minus ray origin, metres.
    offset: f64,
    /// `1 / direction` (0 when the axis does not move).
    inv: f64,
}

/// `floor(value)` as an integer, saturating (NaN gives 0): `value.floor() as i64` without
/// a libm call.
#[inline(always)]
fn floor_i64(value: f64) -> i64 {
    let truncated = value as i64;
    if (truncated as f64) > value {
        truncated.saturating_sub(1)
    } else {
        truncated
    }
}

/// `floor(value)` clamped to a voxel index `0..dim` (as `Traversal::new`'s
/// `clamp_cell(value.floor(), dim)`).
#[inline(always)]
fn floor_cell(value: f64, dim: usize) -> usize {
    floor_i64(value).clamp(0, dim.saturating_sub(1) as i64) as usize
}

/// `ceil(value) − 1` clamped to `0..dim` (as `clamp_cell(value.ceil() − 1, dim)`).
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

impl Tracer {
    /// The walk geometry of `grid`.
    pub(crate) fn new(grid: &Grid3) -> Self {
        let bounds = grid.bounds();
        let dims = grid.dims();
        Self {
            min: [bounds.min.x, bounds.min.y, bounds.min.z],
            max: [bounds.max.x, bounds.max.y, bounds.max.z],
            cell: grid.cell_size(),
            dims,
            strides: [1, dims[0], dims[0] * dims[1]],
        }
    }

    /// Traces the segment from `origin` to `endpoint` (world frame): one miss for every voxel
    /// it crosses inside the grid, and when the endpoint's voxel is the last one crossed, that
    /// miss becomes a hit (saturating counts). Returns whether any voxel was crossed.
    #[inline]
    pub(crate) fn trace(
        &self,
        hits: &mut [u16],
        misses: &mut [u16],
        origin: &Point3<f64>,
        endpoint: &Point3<f64>,
    ) -> bool {
        let delta = endpoint - origin;
        let length = delta.norm();
        if !(length > 0.0 && length.is_finite()) {
            return false;
        }
        let direction = delta / length;
        let o = [origin.x, origin.y, origin.z];
        let d = [direction.x, direction.y, direction.z];
        if !(o.iter().all(|v| v.is_finite()) && d.iter().all(|v| v.is_finite())) {
            return false;
        }
        // Slab clipping, as `Aabb3::clip_segment(origin, direction, 0, length)`.
        let (mut t_start, mut t_end) = (0.0f64, length);
        for axis in 0..3 {
            let (oa, da) = (o[axis], d[axis]);
            if da == 0.0 {
                if oa < self.min[axis] || oa > self.max[axis] {
                    return false;
                }
                continue;
            }
            let inv = 1.0 / da;
            let (mut near, mut far) = ((self.min[axis] - oa) * inv, (self.max[axis] - oa) * inv);
            if near > far {
                std::mem::swap(&mut near, &mut far);
            }
            t_start = t_start.max(near);
            t_end = t_end.min(far);
            if t_start > t_end {
                return false;
            }
        }
        if t_end <= t_start || !t_end.is_finite() {
            return false;
        }
        let clipped_at_end = t_end < length;
        let axes = [
            self.axis(0, o[0], d[0], t_start, t_end, clipped_at_end),
            self.axis(1, o[1], d[1], t_start, t_end, clipped_at_end),
            self.axis(2, o[2], d[2], t_start, t_end, clipped_at_end),
        ];
        let last = self.walk(misses, &axes, t_end);
        // The hit: the endpoint's voxel (`Grid3::cell_of`) is the last one crossed.
        if let Some(end_index) = self.index_of(endpoint)
            && end_index == last
        {
            if let Some(m) = misses.get_mut(last) {
                *m = m.saturating_sub(1);
            }
            if let Some(h) = hits.get_mut(last) {
                *h = h.saturating_add(1);
            }
        }
        true
    }

    /// The set-up of one axis (as `Traversal::new` of `raypath-geometry`).
    #[inline(always)]
    fn axis(&self, axis: usize, o: f64, d: f64, t_start: f64, t_end: f64, clipped: bool) -> Axis {
        let g = self.min[axis];
        let dim = self.dims[axis];
        let stride = self.strides[axis];
        let inv = 1.0 / d;
        let moving = d != 0.0 && inv.is_finite();
        let u_start = ((o + d * t_start) - g) / self.cell;
        let u_end = ((o + d * t_end) - g) / self.cell;
        let start = if moving && d < 0.0 {
            ceil_minus_one_cell(u_start, dim)
        } else {
            floor_cell(u_start, dim)
        };
        let end = if clipped && d > 0.0 {
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
        let (boundary, boundary_step, index_step) = if up {
            ((start + 1) as f64, 1.0, stride)
        } else {
            (start as f64, -1.0, stride.wrapping_neg())
        };
        let offset = g - o;
        let inv = if moving { inv } else { 0.0 };
        let t_next = if steps == 0 {
            f64::INFINITY
        } else {
            boundary_t(offset, boundary, self.cell, inv, t_end)
        };
        Axis {
            start,
            steps,
            t_next,
            boundary,
            boundary_step,
            index_step,
            offset,
            inv,
        }
    }

    /// Walks the voxels, counting a miss in each; returns the last voxel's index.
    #[inline(always)]
    fn walk(&self, misses: &mut [u16], axes: &[Axis; 3], t_end: f64) -> usize {
        let cell = self.cell;
        let [ax, ay, az] = *axes;
        let (mut tx, mut ty, mut tz) = (ax.t_next, ay.t_next, az.t_next);
        let (mut bx, mut by, mut bz) = (ax.boundary, ay.boundary, az.boundary);
        let (mut rx, mut ry, mut rz) = (ax.steps, ay.steps, az.steps);
        let mut i =
            ax.start * self.strides[0] + ay.start * self.strides[1] + az.start * self.strides[2];
        for _ in 0..ax.steps + ay.steps + az.steps {
            if let Some(m) = misses.get_mut(i) {
                *m = m.saturating_add(1);
            }
            // The axis whose boundary comes first; ties step the higher axis.
            if tx < ty && tx < tz {
                i = i.wrapping_add(ax.index_step);
                rx -= 1;
                bx += ax.boundary_step;
                tx = if rx == 0 {
                    f64::INFINITY
                } else {
                    boundary_t(ax.offset, bx, cell, ax.inv, t_end)
                };
            } else if ty < tz {
                i = i.wrapping_add(ay.index_step);
                ry -= 1;
                by += ay.boundary_step;
                ty = if ry == 0 {
                    f64::INFINITY
                } else {
                    boundary_t(ay.offset, by, cell, ay.inv, t_end)
                };
            } else {
                i = i.wrapping_add(az.index_step);
                rz -= 1;
                bz += az.boundary_step;
                tz = if rz == 0 {
                    f64::INFINITY
                } else {
                    boundary_t(az.offset, bz, cell, az.inv, t_end)
                };
            }
        }
        if let Some(m) = misses.get_mut(i) {
            *m = m.saturating_add(1);
        }
        i
    }

    /// The linear index of the voxel containing `point` (as `Grid3::cell_of`), `None` outside.
    #[inline(always)]
    fn index_of(&self, point: &Point3<f64>) -> Option<usize> {
        let mut index = 0;
        for (((&p, &min), &dim), &stride) in point
            .coords
            .iter()
            .zip(&self.min)
            .zip(&self.dims)
            .zip(&self.strides)
        {
            let lattice = floor_i64((p - min) / self.cell);
            if lattice < 0 || lattice as u64 >= dim as u64 {
                return None;
            }
            index += lattice as usize * stride;
        }
        Some(index)
    }
}

/// `t` of a boundary, clamped to the segment end (NaN from overflow becomes `t_end`).
#[inline(always)]
fn boundary_t(offset: f64, boundary: f64, cell: f64, inv: f64, t_end: f64) -> f64 {
    let t = (offset + boundary * cell) * inv;
    if t < t_end { t } else { t_end }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Point3, Unit};
    use proptest::prelude::*;
    use raypath_geometry::Grid3;

    use super::Tracer;

    /// The reference: `Grid3::traverse`, a miss per voxel, the last voxel a hit when it is
    /// `cell_of(endpoint)` (the extraction's counting before the specialised walk).
    fn trace_reference(
        grid: &Grid3,
        hits: &mut [u16],
        misses: &mut [u16],
        origin: &Point3<f64>,
        endpoint: &Point3<f64>,
    ) {
        let delta = endpoint - origin;
        let length = delta.norm();
        if !(length > 0.0 && length.is_finite()) {
            return;
        }
        let direction = Unit::new_unchecked(delta / length);
        let mut last = None;
        grid.traverse(origin, &direction, length).for_each(|c| {
            misses[c.index] = misses[c.index].saturating_add(1);
            last = Some(c.index);
        });
        if let (Some(index), Some(cell)) = (last, grid.cell_of(endpoint))
            && grid.linear_index(cell) == index
        {
            misses[index] = misses[index].saturating_sub(1);
            hits[index] = hits[index].saturating_add(1);
        }
    }

    /// A coordinate: anywhere around the grid, or exactly on a voxel face (`k` cells from the
    /// grid origin, `k` from −2 past the far end), or the grid origin's coordinate.
    fn coordinate(origin: f64, cell: f64, dim: usize) -> impl Strategy<Value = f64> {
        let span = dim as f64 * cell;
        prop_oneof![
            (-0.5f64..1.5).prop_map(move |u| origin + u * span),
            (-2i64..dim as i64 + 3).prop_map(move |k| origin + k as f64 * cell),
            (-2i64..dim as i64 + 3, 0.0f64..1.0)
                .prop_map(move |(k, f)| origin + (k as f64 + f) * cell),
        ]
    }

    fn point(grid: Grid3) -> impl Strategy<Value = Point3<f64>> {
        let (o, c, d) = (grid.origin(), grid.cell_size(), grid.dims());
        (
            coordinate(o.x, c, d[0]),
            coordinate(o.y, c, d[1]),
            coordinate(o.z, c, d[2]),
        )
            .prop_map(|(x, y, z)| Point3::new(x, y, z))
    }

    fn grid() -> impl Strategy<Value = Grid3> {
        (
            (-3.0f64..3.0, -3.0f64..3.0, -3.0f64..3.0),
            prop_oneof![Just(0.1), Just(0.25), Just(1.0), 0.05f64..0.7],
            (1usize..9, 1usize..9, 1usize..6),
        )
            .prop_map(|((x, y, z), cell, (nx, ny, nz))| {
                Grid3::new(Point3::new(x, y, z), cell, [nx, ny, nz]).expect("valid grid")
            })
    }

    /// A grid and segments: random, axis-parallel (endpoint sharing one or two coordinates
    /// of the origin) and ending on faces, edges and corners.
    type Segments = Vec<(Point3<f64>, Point3<f64>)>;

    fn case() -> impl Strategy<Value = (Grid3, Segments)> {
        grid().prop_flat_map(|grid| {
            let segment = (point(grid), point(grid), 0u8..4).prop_map(|(a, mut b, parallel)| {
                match parallel {
                    1 => b.x = a.x,
                    2 => {
                        b.y = a.y;
                        b.z = a.z;
                    }
                    3 => b.z = a.z,
                    _ => {}
                }
                (a, b)
            });
            (Just(grid), proptest::collection::vec(segment, 1..40))
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        #[test]
        fn counts_equal_the_exact_traversal((grid, segments) in case()) {
            let n = grid.num_cells();
            let (mut hits, mut misses) = (vec![0u16; n], vec![0u16; n]);
            let (mut ref_hits, mut ref_misses) = (vec![0u16; n], vec![0u16; n]);
            let tracer = Tracer::new(&grid);
            for (a, b) in &segments {
                tracer.trace(&mut hits, &mut misses, a, b);
                trace_reference(&grid, &mut ref_hits, &mut ref_misses, a, b);
                prop_assert_eq!(&misses, &ref_misses, "segment {:?} -> {:?}", a, b);
                prop_assert_eq!(&hits, &ref_hits, "segment {:?} -> {:?}", a, b);
            }
        }
    }

    #[test]
    fn known_cases_equal_the_exact_traversal() {
        let grid = Grid3::new(Point3::new(-1.0, -1.0, -0.5), 0.25, [8, 8, 4]).expect("grid");
        let tracer = Tracer::new(&grid);
        let n = grid.num_cells();
        let segments = [
            // From outside along x, ending on a face; space diagonal through vertices.
            ([-3.0, 0.1, 0.1], [0.5, 0.1, 0.1]),
            ([-1.0, -1.0, -0.5], [1.0, 1.0, 0.5]),
            // Along a face, along an edge, on the grid's upper face, ending on a corner.
            ([-1.5, 0.0, 0.1], [2.0, 0.0, 0.1]),
            ([-1.5, 0.0, 0.0], [2.0, 0.0, 0.0]),
            ([0.1, 1.0, 0.1], [0.1, -2.0, 0.1]),
            ([0.3, 0.3, 0.3], [0.5, 0.5, 0.25]),
            // Degenerate: zero length, missing the grid, touching only a corner.
            ([0.1, 0.1, 0.1], [0.1, 0.1, 0.1]),
            ([5.0, 5.0, 5.0], [6.0, 5.0, 5.0]),
            ([-2.0, -2.0, -0.5], [-1.0, -1.0, -0.5]),
        ];
        let (mut hits, mut misses) = (vec![0u16; n], vec![0u16; n]);
        let (mut ref_hits, mut ref_misses) = (vec![0u16; n], vec![0u16; n]);
        for (a, b) in segments {
            let (a, b) = (Point3::from(a), Point3::from(b));
            tracer.trace(&mut hits, &mut misses, &a, &b);
            trace_reference(&grid, &mut ref_hits, &mut ref_misses, &a, &b);
            assert_eq!((&hits, &misses), (&ref_hits, &ref_misses), "{a:?} -> {b:?}");
        }
        assert!(misses.iter().any(|&m| m > 0) && hits.iter().any(|&h| h > 0));
    }
}
