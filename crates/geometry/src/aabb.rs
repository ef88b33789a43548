//! Axis-aligned boxes in 2-D and 3-D.

use nalgebra::{Point2, Point3, Vector2, Vector3};
use serde::{Deserialize, Serialize};

macro_rules! aabb_impl {
    ($name:ident, $point:ident, $vector:ident, $dim:literal, $doc:literal) => {
        #[doc = $doc]
        ///
        /// The box is closed: `min <= p <= max` on every axis. An empty box (`min > max` on
        /// some axis) contains nothing and is what [`Self::empty`] returns.
        #[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
        pub struct $name {
            /// Lower corner.
            pub min: $point<f64>,
            /// Upper corner.
            pub max: $point<f64>,
        }

        impl $name {
            /// The box spanned by two corners (in any order).
            pub fn new(a: $point<f64>, b: $point<f64>) -> Self {
                Self {
                    min: a.inf(&b),
                    max: a.sup(&b),
                }
            }

            /// The empty box: `extend` by a point gives the box of that point.
            pub fn empty() -> Self {
                Self {
                    min: $point::from($vector::repeat(f64::INFINITY)),
                    max: $point::from($vector::repeat(f64::NEG_INFINITY)),
                }
            }

            /// True when the box contains no point.
            pub fn is_empty(&self) -> bool {
                (0..$dim).any(|i| self.min[i] > self.max[i])
            }

            /// Grows the box to contain `point`.
            pub fn extend(&mut self, point: &$point<f64>) {
                self.min = self.min.inf(point);
                self.max = self.max.sup(point);
            }

            /// The smallest box containing both.
            pub fn union(&self, other: &Self) -> Self {
                Self {
                    min: self.min.inf(&other.min),
                    max: self.max.sup(&other.max),
                }
            }

            /// The box of a set of points; empty for no points. Non-finite points are skipped.
            pub fn from_points<'a>(points: impl IntoIterator<Item = &'a $point<f64>>) -> Self {
                let mut aabb = Self::empty();
                for p in points {
                    if p.iter().all(|v| v.is_finite()) {
                        aabb.extend(p);
                    }
                }
                aabb
            }

            /// True when `point` lies inside or on the boundary.
            pub fn contains(&self, point: &$point<f64>) -> bool {
                (0..$dim).all(|i| self.min[i] <= point[i] && point[i] <= self.max[i])
            }

            /// Edge lengths (zero for an empty box).
            pub fn extents(&self) -> $vector<f64> {
                if self.is_empty() {
                    $vector::zeros()
                } else {
                    self.max - self.min
                }
            }

            /// The centre point.
            pub fn center(&self) -> $point<f64> {
                nalgebra::center(&self.min, &self.max)
            }

            /// Clips the segment `origin + t·direction`, `t ∈ [t_min, t_max]`, to the box
            /// (slab method). Returns the parameter interval inside the box, or `None` when the
            /// segment misses it. Axis-parallel directions (zero components) are handled: the
            /// segment is inside that slab for all `t` or for none.
            pub fn clip_segment(
                &self,
                origin: &$point<f64>,
                direction: &$vector<f64>,
                t_min: f64,
                t_max: f64,
            ) -> Option<(f64, f64)> {
                let mut t0 = t_min;
                let mut t1 = t_max;
                for i in 0..$dim {
                    let d = direction[i];
                    if d == 0.0 {
                        if origin[i] < self.min[i] || origin[i] > self.max[i] {
                            return None;
                        }
                        continue;
                    }
                    let inv = 1.0 / d;
                    let (mut near, mut far) = (
                        (self.min[i] - origin[i]) * inv,
                        (self.max[i] - origin[i]) * inv,
                    );
                    if near > far {
                        std::mem::swap(&mut near, &mut far);
                    }
                    t0 = t0.max(near);
                    t1 = t1.min(far);
                    if t0 > t1 {
                        return None;
                    }
                }
                Some((t0, t1))
            }
        }
    };
}

aabb_impl!(
    Aabb2,
    Point2,
    Vector2,
    2,
    "An axis-aligned rectangle in metres."
);
aabb_impl!(Aabb3, Point3, Vector3, 3, "An axis-aligned box in metres.");

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clip_through_box() {
        let aabb = Aabb3::new(Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 1.0, 1.0));
        let (t0, t1) = aabb
            .clip_segment(
                &Point3::new(-1.0, 0.5, 0.5),
                &Vector3::new(1.0, 0.0, 0.0),
                0.0,
                10.0,
            )
            .unwrap();
        assert_eq!((t0, t1), (1.0, 2.0));
        assert!(
            aabb.clip_segment(
                &Point3::new(-1.0, 2.0, 0.5),
                &Vector3::new(1.0, 0.0, 0.0),
                0.0,
                10.0
            )
            .is_none()
        );
    }

    #[test]
    fn empty_box() {
        let mut b = Aabb2::empty();
        assert!(b.is_empty());
        b.extend(&Point2::new(1.0, 2.0));
        assert!(!b.is_empty() && b.contains(&Point2::new(1.0, 2.0)));
        assert_eq!(b.extents(), Vector2::zeros());
    }
}
