//! `traverse` and `traverse_ray` on [`Grid2`] and [`Grid3`].

use nalgebra::{Point2, Point3, Unit, Vector2, Vector3};

use super::{ClippedSegment, GridSpec, Traversal};
use crate::{Grid2, Grid3, Ray2, Ray3};

macro_rules! traverse_impl {
    ($grid:ident, $point:ident, $vector:ident, $ray:ident, $dim:literal, $alias:ident) => {
        impl $grid {
            /// The cells the segment `origin + t · direction`, `t ∈ [0, length_m]`, crosses
            /// inside the grid, in order, each with its entry and exit `t` in metres (see
            /// the contract of [`Traversal`](crate::Traversal)). The segment may start and end
            /// outside the grid; `length_m = +∞` traces until the ray leaves the grid.
            /// Zero-length segments, NaN or negative lengths and non-finite origins or
            /// directions yield nothing.
            #[inline]
            pub fn traverse(
                &self,
                origin: &$point<f64>,
                direction: &Unit<$vector<f64>>,
                length_m: f64,
            ) -> crate::$alias {
                let d = direction.as_ref();
                if length_m.is_nan()
                    || length_m <= 0.0
                    || !origin.iter().all(|v| v.is_finite())
                    || !d.iter().all(|v| v.is_finite())
                {
                    return Traversal::empty();
                }
                let Some((t_start, t_end)) = self.bounds().clip_segment(origin, d, 0.0, length_m)
                else {
                    return Traversal::empty();
                };
                if t_end <= t_start || !t_end.is_finite() {
                    return Traversal::empty();
                }
                let grid = GridSpec {
                    origin: self.origin().coords.into(),
                    cell_size: self.cell_size(),
                    dims: self.dims(),
                };
                let segment = ClippedSegment {
                    origin: origin.coords.into(),
                    direction: (*d).into(),
                    t_start,
                    t_end,
                    clipped_at_end: t_end < length_m,
                };
                Traversal::new(&grid, &segment)
            }

            /// The cells a sensor ray crosses: up to the hit for a return (cut at
            /// `max_range_m` when farther), up to `max_range_m` for a no-return
            /// ([`Range::traced_length`](crate::Range::traced_length)). For a hit inside the
            /// grid, the last cell is `self.cell_of(&ray.endpoint())`.
            #[inline]
            pub fn traverse_ray(&self, ray: &$ray, max_range_m: f64) -> crate::$alias {
                self.traverse(
                    &ray.origin,
                    &ray.direction,
                    ray.range.traced_length(max_range_m),
                )
            }
        }
    };
}

traverse_impl!(Grid2, Point2, Vector2, Ray2, 2, Traversal2);
traverse_impl!(Grid3, Point3, Vector3, Ray3, 3, Traversal3);
