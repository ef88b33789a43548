//! 2-D scenes: line segments in one BVH, every segment tagged with the surface it belongs to,
//! for exact first-hit ray casting with parry2d (f64).
//!
//! The segments form a parry [`Polyline`] with explicit segment indices, so unconnected walls,
//! closed room outlines and polygonal obstacles live in one bounding-volume hierarchy. Frames
//! follow REP-103 (x forward, y left, angles counter-clockwise), units are metres.

use nalgebra::{Point2, Unit, Vector2};
use parry2d_f64::query::{PointQuery, Ray};
use parry2d_f64::shape::{CompositeShapeRef, Polyline};
use raypath_geometry::{Aabb2, Pose2};

use crate::error::{Result, SimError};
pub use crate::scene3::{Surface, SurfaceId};

/// A hit of a ray on a 2-D scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit2 {
    /// Distance from the ray origin in metres.
    pub range_m: f64,
    /// Unit normal of the segment hit, facing the ray origin.
    pub normal: Unit<Vector2<f64>>,
    /// The surface that was hit.
    pub surface: SurfaceId,
    /// Index of the segment hit (in the order the segments were added).
    pub segment: u32,
}

/// Collects segments and surfaces, then builds a [`Scene2`].
#[derive(Clone, Debug, Default)]
pub struct SceneBuilder2 {
    vertices: Vec<Point2<f64>>,
    segments: Vec<[u32; 2]>,
    segment_surfaces: Vec<SurfaceId>,
    surfaces: Vec<Surface>,
}

impl SceneBuilder2 {
    /// An empty scene.
    pub fn new() -> Self {
        Self::default()
    }

    /// Registers a surface; its id tags the segments added with it.
    pub fn add_surface(&mut self, surface: Surface) -> SurfaceId {
        self.surfaces.push(surface);
        (self.surfaces.len() - 1) as SurfaceId
    }

    /// Number of segments so far.
    pub fn num_segments(&self) -> usize {
        self.segments.len()
    }

    /// Adds the segment `a`–`b` of `surface`. Degenerate (shorter than 1 µm) or non-finite
    /// segments are skipped.
    pub fn add_segment(&mut self, a: Point2<f64>, b: Point2<f64>, surface: SurfaceId) {
        let length = (b - a).norm();
        if !(length.is_finite() && length > 1e-6) {
            return;
        }
        let base = self.vertices.len() as u32;
        self.vertices.push(a);
        self.vertices.push(b);
        self.segments.push([base, base + 1]);
        self.segment_surfaces.push(surface);
    }

    /// Adds the open polyline through `points`.
    pub fn add_polyline(&mut self, points: &[Point2<f64>], surface: SurfaceId) {
        for pair in points.windows(2) {
            if let [a, b] = pair {
                self.add_segment(*a, *b, surface);
            }
        }
    }

    /// Adds the closed polygon through `corners` (the last corner connects to the first).
    pub fn add_polygon(&mut self, corners: &[Point2<f64>], surface: SurfaceId) {
        self.add_polyline(corners, surface);
        if let (Some(first), Some(last)) = (corners.first(), corners.last())
            && corners.len() > 2
        {
            self.add_segment(*last, *first, surface);
        }
    }

    /// Adds a rectangle with half extents `half_extents_m` placed by `world_from_box`;
    /// `sides` gives the surface of each side in the order −x, +x, −y, +y (box frame).
    pub fn add_rectangle(
        &mut self,
        world_from_box: &Pose2,
        half_extents_m: Vector2<f64>,
        sides: [SurfaceId; 4],
    ) {
        let h = half_extents_m;
        let corner =
            |sx: f64, sy: f64| world_from_box.transform_point(&Point2::new(sx * h.x, sy * h.y));
        let (mm, pm, pp, mp) = (
            corner(-1.0, -1.0),
            corner(1.0, -1.0),
            corner(1.0, 1.0),
            corner(-1.0, 1.0),
        );
        let [minus_x, plus_x, minus_y, plus_y] = sides;
        self.add_segment(mp, mm, minus_x);
        self.add_segment(pm, pp, plus_x);
        self.add_segment(mm, pm, minus_y);
        self.add_segment(pp, mp, plus_y);
    }

    /// Adds a circle of radius `radius_m` as the inscribed regular polygon with `segments`
    /// sides (at least 3); a vertex lies at angle 0 (on the +x side of the centre).
    pub fn add_circle(
        &mut self,
        center: Point2<f64>,
        radius_m: f64,
        segments: usize,
        surface: SurfaceId,
    ) {
        let n = segments.max(3);
        let corners: Vec<Point2<f64>> = (0..n)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                center + Vector2::new(radius_m * a.cos(), radius_m * a.sin())
            })
            .collect();
        self.add_polygon(&corners, surface);
    }

    /// Builds the BVH. Fails for a scene without segments or with a segment whose surface
    /// was not registered.
    pub fn build(self) -> Result<Scene2> {
        if self.segments.is_empty() {
            return Err(SimError::InvalidScene {
                reason: "the scene has no segments".into(),
            });
        }
        if let Some(&bad) = self
            .segment_surfaces
            .iter()
            .find(|&&s| s as usize >= self.surfaces.len())
        {
            return Err(SimError::InvalidScene {
                reason: format!(
                    "a segment uses surface {bad}, but only {} surfaces were added",
                    self.surfaces.len()
                ),
            });
        }
        let bounds = Aabb2::from_points(self.vertices.iter());
        let polyline = Polyline::new(self.vertices, Some(self.segments));
        Ok(Scene2 {
            polyline,
            segment_surfaces: self.segment_surfaces,
            surfaces: self.surfaces,
            bounds,
        })
    }
}

/// A built 2-D scene: first-hit ray casting against all segments.
#[derive(Clone)]
pub struct Scene2 {
    polyline: Polyline,
    segment_surfaces: Vec<SurfaceId>,
    surfaces: Vec<Surface>,
    bounds: Aabb2,
}

impl Scene2 {
    /// The first hit of the ray `origin + t · direction`, `0 ≤ t ≤ max_range_m`, if any.
    /// A ray that grazes a segment along its line hits it where it enters the segment.
    pub fn cast(
        &self,
        origin: &Point2<f64>,
        direction: &Unit<Vector2<f64>>,
        max_range_m: f64,
    ) -> Option<Hit2> {
        let ray = Ray::new(*origin, direction.into_inner());
        let (segment, hit) = CompositeShapeRef(&self.polyline).cast_local_ray_and_get_normal(
            &ray,
            max_range_m,
            false,
        )?;
        let mut normal = hit.normal;
        if normal.dot(direction) > 0.0 {
            normal = -normal;
        }
        let normal = Unit::try_new(normal, 0.0).unwrap_or_else(|| {
            // A collinear graze has no defined facing normal: use the segment's.
            let [a, b] = self.segment(segment).unwrap_or([Point2::origin(); 2]);
            let d = b - a;
            Unit::new_normalize(Vector2::new(-d.y, d.x))
        });
        Some(Hit2 {
            range_m: hit.time_of_impact,
            normal,
            surface: *self.segment_surfaces.get(segment as usize)?,
            segment,
        })
    }

    /// The first hit of a ray from `origin` at `angle_rad` (counter-clockwise from +x).
    pub fn cast_angle(
        &self,
        origin: &Point2<f64>,
        angle_rad: f64,
        max_range_m: f64,
    ) -> Option<Hit2> {
        let direction = Unit::new_unchecked(Vector2::new(angle_rad.cos(), angle_rad.sin()));
        self.cast(origin, &direction, max_range_m)
    }

    /// Whether the straight path from `a` to `b` crosses no segment.
    pub fn is_free(&self, a: &Point2<f64>, b: &Point2<f64>) -> bool {
        let d = b - a;
        let length = d.norm();
        if length <= 0.0 {
            return true;
        }
        let direction = Unit::new_unchecked(d / length);
        self.cast(a, &direction, length).is_none()
    }

    /// Distance in metres from `point` to the nearest segment.
    pub fn distance(&self, point: &Point2<f64>) -> f64 {
        let projection = self.polyline.project_local_point(point, false);
        (projection.point - point).norm()
    }

    /// The end points of segment `i`.
    pub fn segment(&self, i: u32) -> Option<[Point2<f64>; 2]> {
        let [a, b] = *self.polyline.indices().get(i as usize)?;
        let vertices = self.polyline.vertices();
        Some([*vertices.get(a as usize)?, *vertices.get(b as usize)?])
    }

    /// The surface of segment `i`.
    pub fn segment_surface(&self, i: u32) -> Option<SurfaceId> {
        self.segment_surfaces.get(i as usize).copied()
    }

    /// The surface with this id.
    pub fn surface(&self, id: SurfaceId) -> Option<&Surface> {
        self.surfaces.get(id as usize)
    }

    /// All surfaces, indexed by [`SurfaceId`].
    pub fn surfaces(&self) -> &[Surface] {
        &self.surfaces
    }

    /// Number of segments.
    pub fn num_segments(&self) -> usize {
        self.segment_surfaces.len()
    }

    /// The bounding box of all geometry.
    pub fn bounds(&self) -> Aabb2 {
        self.bounds
    }
}
