//! Building blocks of the floor plans: segments with surfaces, solid rectangles, walls with
//! door and window gaps, and the boxes used for placement tests.

use nalgebra::{Point2, Vector2};
use rand::Rng;
use raypath_geometry::Pose2;

use super::floorplan::{Material, SurfaceClass, WorldSegment};
use crate::scene2::SurfaceId;

/// Collects the materials, segments and planning footprints of a world.
pub(super) struct Builder {
    pub(super) materials: Vec<Material>,
    pub(super) segments: Vec<WorldSegment>,
    pub(super) footprints: Vec<Vec<[f64; 2]>>,
}

impl Builder {
    pub(super) fn material(
        &mut self,
        class: SurfaceClass,
        reflectivity: f64,
        transmission: f64,
    ) -> SurfaceId {
        self.materials.push(Material {
            class,
            label: class.label(),
            reflectivity,
            transmission,
        });
        (self.materials.len() - 1) as SurfaceId
    }

    pub(super) fn segment(&mut self, a: Point2<f64>, b: Point2<f64>, surface: SurfaceId) {
        if (b - a).norm() > 1e-6 {
            self.segments.push(WorldSegment {
                a: [a.x, a.y],
                b: [b.x, b.y],
                surface,
            });
        }
    }

    /// An axis-aligned solid rectangle; `sides` are the surfaces of the −x, +x, −y, +y faces.
    pub(super) fn rect(&mut self, min: [f64; 2], max: [f64; 2], sides: [SurfaceId; 4]) {
        let p = |x: f64, y: f64| Point2::new(x, y);
        let [x0, y0] = min;
        let [x1, y1] = max;
        self.segment(p(x0, y1), p(x0, y0), sides[0]);
        self.segment(p(x1, y0), p(x1, y1), sides[1]);
        self.segment(p(x0, y0), p(x1, y0), sides[2]);
        self.segment(p(x1, y1), p(x0, y1), sides[3]);
    }

    /// A rotated solid rectangle of one surface.
    pub(super) fn oriented_rect(&mut self, pose: &Pose2, half: Vector2<f64>, surface: SurfaceId) {
        let corners = rect_corners(pose, half);
        for i in 0..4 {
            self.segment(corners[i], corners[(i + 1) % 4], surface);
        }
    }

    /// A wall along `horizontal` (x) or vertical (y): thickness interval `[c0, c1]`, span
    /// `[s0, s1]` minus `gaps` (glass panes fill a gap when it carries a surface); `low` and
    /// `high` are the surfaces of the faces towards −y/−x and +y/+x, `jamb` of the ends.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn wall(
        &mut self,
        horizontal: bool,
        thickness: [f64; 2],
        span: [f64; 2],
        gaps: &[(f64, f64, Option<SurfaceId>)],
        low: SurfaceId,
        high: SurfaceId,
        jamb: SurfaceId,
        glass: Option<SurfaceId>,
    ) {
        let mut gaps: Vec<_> = gaps.to_vec();
        gaps.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut pieces = Vec::new();
        let mut start = span[0];
        for &(g0, g1, _) in &gaps {
            if g0 > start {
                pieces.push((start, g0));
            }
            start = start.max(g1);
        }
        if span[1] > start {
            pieces.push((start, span[1]));
        }
        let mid = 0.5 * (thickness[0] + thickness[1]);
        let point = |s: f64, c: f64| {
            if horizontal {
                Point2::new(s, c)
            } else {
                Point2::new(c, s)
            }
        };
        for (s0, s1) in pieces {
            match glass {
                Some(g) => self.segment(point(s0, mid), point(s1, mid), g),
                None if horizontal => self.rect(
                    [s0, thickness[0]],
                    [s1, thickness[1]],
                    [jamb, jamb, low, high],
                ),
                None => self.rect(
                    [thickness[0], s0],
                    [thickness[1], s1],
                    [low, high, jamb, jamb],
                ),
            }
        }
        for &(g0, g1, pane) in &gaps {
            if let Some(pane) = pane {
                self.segment(point(g0, mid), point(g1, mid), pane);
            }
        }
    }
}

pub(super) fn rect_corners(pose: &Pose2, half: Vector2<f64>) -> [Point2<f64>; 4] {
    [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .map(|(sx, sy)| pose.transform_point(&Point2::new(sx * half.x, sy * half.y)))
}

pub(super) fn uniform<R: Rng + ?Sized>(rng: &mut R, range: [f64; 2]) -> f64 {
    if range[1] > range[0] {
        rng.random_range(range[0]..range[1])
    } else {
        range[0]
    }
}

/// Axis-aligned boxes `[min, max]` for overlap tests.
pub(super) type Aabb = ([f64; 2], [f64; 2]);

pub(super) fn overlaps(a: &Aabb, b: &Aabb, margin: f64) -> bool {
    a.0[0] < b.1[0] + margin
        && b.0[0] < a.1[0] + margin
        && a.0[1] < b.1[1] + margin
        && b.0[1] < a.1[1] + margin
}

pub(super) fn inside(inner: &Aabb, outer: &Aabb) -> bool {
    inner.0[0] >= outer.0[0]
        && inner.0[1] >= outer.0[1]
        && inner.1[0] <= outer.1[0]
        && inner.1[1] <= outer.1[1]
}

/// Splits `[a, b]` into widths drawn from `range` (the last one absorbs the rest).
pub(super) fn split<R: Rng + ?Sized>(rng: &mut R, a: f64, b: f64, range: [f64; 2]) -> Vec<f64> {
    let mut cuts = vec![a];
    let mut x = a;
    while b - x > range[1] {
        let mut w = uniform(rng, range);
        if b - (x + w) < range[0] {
            w = (b - x - range[0]).max(range[0]);
        }
        x += w;
        cuts.push(x);
    }
    cuts.push(b);
    cuts
}
