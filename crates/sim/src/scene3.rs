//! 3-D scenes: a triangle soup in one BVH, every triangle tagged with the surface it belongs
//! to, for exact first-hit ray casting (f64; an SAH bounding volume hierarchy of our own,
//! cross-checked against parry3d's `TriMesh`).
//!
//! Solids: polygons, boxes, cylinders (plain or with separate caps), prisms, wedges, stairs and
//! spheres ([`SceneBuilder3::add_prism`] and friends).

use nalgebra::{Point3, Unit, Vector3};
use raypath_geometry::{Aabb3, Pose3};

use crate::error::{Result, SimError};

mod bvh;
mod primitives;

use bvh::Bvh;

pub(crate) use primitives::is_convex_ccw;

/// Index of a [`Surface`] in a scene.
pub type SurfaceId = u32;

/// What a surface is: its ground-truth label and how it reflects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// Label written with every point that hits the surface. Plane-extraction sets use the
    /// SynPEB convention: labels ≥ 10 are planar segments, smaller labels are not planes.
    pub label: u32,
    /// Diffuse reflectivity (Lambertian albedo) in `[0, 1]`, for simulated intensities.
    pub reflectivity: f32,
}

/// A hit of a ray on the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit3 {
    /// Distance from the ray origin in metres.
    pub range_m: f64,
    /// Unit surface normal at the hit, facing the ray origin.
    pub normal: Unit<Vector3<f64>>,
    /// The surface that was hit.
    pub surface: SurfaceId,
}

/// Collects triangles and surfaces, then builds a [`Scene3`].
#[derive(Clone, Debug, Default)]
pub struct SceneBuilder3 {
    vertices: Vec<Point3<f64>>,
    triangles: Vec<[u32; 3]>,
    triangle_surfaces: Vec<SurfaceId>,
    surfaces: Vec<Surface>,
}

impl SceneBuilder3 {
    /// An empty scene.
    pub fn new() -> Self {
        Self::default()
    }

    /// Registers a surface; its id tags the triangles added with it.
    pub fn add_surface(&mut self, surface: Surface) -> SurfaceId {
        self.surfaces.push(surface);
        (self.surfaces.len() - 1) as SurfaceId
    }

    /// Number of triangles so far.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// Adds one triangle of `surface`. Degenerate triangles (zero area) are skipped.
    pub fn add_triangle(&mut self, corners: [Point3<f64>; 3], surface: SurfaceId) {
        let area2 = (corners[1] - corners[0])
            .cross(&(corners[2] - corners[0]))
            .norm();
        if area2.is_nan() || area2 <= 1e-12 {
            return;
        }
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&corners);
        self.triangles.push([base, base + 1, base + 2]);
        self.triangle_surfaces.push(surface);
    }

    /// Adds a planar convex polygon (corners in order) as a triangle fan.
    pub fn add_polygon(&mut self, corners: &[Point3<f64>], surface: SurfaceId) {
        for i in 1..corners.len().saturating_sub(1) {
            self.add_triangle([corners[0], corners[i], corners[i + 1]], surface);
        }
    }

    /// Adds a box with half extents `half_extents_m` placed by `world_from_box`; `faces`
    /// gives the surface of each face in the order −x, +x, −y, +y, −z, +z (box frame).
    pub fn add_box(
        &mut self,
        world_from_box: &Pose3,
        half_extents_m: Vector3<f64>,
        faces: [SurfaceId; 6],
    ) {
        let h = half_extents_m;
        let corner = |sx: f64, sy: f64, sz: f64| {
            world_from_box.transform_point(&Point3::new(sx * h.x, sy * h.y, sz * h.z))
        };
        let quads: [[(f64, f64, f64); 4]; 6] = [
            [
                (-1., -1., -1.),
                (-1., -1., 1.),
                (-1., 1., 1.),
                (-1., 1., -1.),
            ],
            [(1., -1., -1.), (1., 1., -1.), (1., 1., 1.), (1., -1., 1.)],
            [
                (-1., -1., -1.),
                (1., -1., -1.),
                (1., -1., 1.),
                (-1., -1., 1.),
            ],
            [(-1., 1., -1.), (-1., 1., 1.), (1., 1., 1.), (1., 1., -1.)],
            [
                (-1., -1., -1.),
                (-1., 1., -1.),
                (1., 1., -1.),
                (1., -1., -1.),
            ],
            [(-1., -1., 1.), (1., -1., 1.), (1., 1., 1.), (-1., 1., 1.)],
        ];
        for (quad, surface) in quads.iter().zip(faces) {
            let corners = quad.map(|(x, y, z)| corner(x, y, z));
            self.add_polygon(&corners, surface);
        }
    }

    /// Adds a closed vertical-axis cylinder (side, top and bottom caps) approximated by
    /// `segments` facets; `base_center` is the centre of the bottom cap.
    pub fn add_cylinder(
        &mut self,
        base_center: Point3<f64>,
        radius_m: f64,
        height_m: f64,
        segments: usize,
        surface: SurfaceId,
    ) {
        self.add_capped_cylinder(base_center, radius_m, height_m, segments, [surface; 3]);
    }

    /// Builds the BVH. Fails for a scene without triangles or with non-finite coordinates.
    pub fn build(self) -> Result<Scene3> {
        if self.triangles.is_empty() {
            return Err(SimError::InvalidScene {
                reason: "the scene has no triangles".into(),
            });
        }
        if self
            .vertices
            .iter()
            .any(|v| !v.iter().all(|c| c.is_finite()))
        {
            return Err(SimError::InvalidScene {
                reason: "a vertex has non-finite coordinates".into(),
            });
        }
        let bounds = Aabb3::from_points(self.vertices.iter());
        let corners: Vec<[Point3<f64>; 3]> = self
            .triangles
            .iter()
            .map(|t| t.map(|i| self.vertices[i as usize]))
            .collect();
        Ok(Scene3 {
            bvh: Bvh::build(&corners),
            corners,
            triangle_surfaces: self.triangle_surfaces,
            surfaces: self.surfaces,
            bounds,
        })
    }
}

/// A built scene: first-hit ray casting against all triangles.
#[derive(Clone, Debug)]
pub struct Scene3 {
    bvh: Bvh,
    corners: Vec<[Point3<f64>; 3]>,
    triangle_surfaces: Vec<SurfaceId>,
    surfaces: Vec<Surface>,
    bounds: Aabb3,
}

impl Scene3 {
    /// The first hit of the ray `origin + t · direction` (`direction` a unit vector),
    /// `0 ≤ t < max_range_m`, if any; triangles are two-sided.
    pub fn cast(
        &self,
        origin: &Point3<f64>,
        direction: &Unit<Vector3<f64>>,
        max_range_m: f64,
    ) -> Option<Hit3> {
        let hit = self.bvh.cast(origin, direction, max_range_m)?;
        let normal = if hit.normal.dot(direction) > 0.0 {
            -hit.normal
        } else {
            hit.normal
        };
        Some(Hit3 {
            range_m: hit.t,
            normal: Unit::new_unchecked(normal),
            surface: *self.triangle_surfaces.get(hit.triangle as usize)?,
        })
    }

    /// The corners of triangle `index` (in the order they were added), if it exists.
    pub fn triangle(&self, index: usize) -> Option<[Point3<f64>; 3]> {
        self.corners.get(index).copied()
    }

    /// The surface of triangle `index`, if it exists.
    pub fn triangle_surface(&self, index: usize) -> Option<SurfaceId> {
        self.triangle_surfaces.get(index).copied()
    }

    /// The surface with this id.
    pub fn surface(&self, id: SurfaceId) -> Option<&Surface> {
        self.surfaces.get(id as usize)
    }

    /// All surfaces, indexed by [`SurfaceId`].
    pub fn surfaces(&self) -> &[Surface] {
        &self.surfaces
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.triangle_surfaces.len()
    }

    /// The bounding box of all geometry.
    pub fn bounds(&self) -> Aabb3 {
        self.bounds
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn surface(label: u32) -> Surface {
        Surface {
            label,
            reflectivity: 0.5,
        }
    }

    #[test]
    fn box_faces_are_hit_at_analytic_ranges_with_their_labels() {
        let mut builder = SceneBuilder3::new();
        let faces = [10, 11, 12, 13, 14, 15].map(|l| builder.add_surface(surface(l)));
        builder.add_box(&Pose3::identity(), Vector3::new(2.0, 3.0, 1.0), faces);
        let scene = builder.build().unwrap();
        // From inside the box (the simulator's rooms are seen from inside).
        let cases = [
            (Vector3::new(-1.0, 0.0, 0.0), 2.0, 10),
            (Vector3::new(1.0, 0.0, 0.0), 2.0, 11),
            (Vector3::new(0.0, -1.0, 0.0), 3.0, 12),
            (Vector3::new(0.0, 1.0, 0.0), 3.0, 13),
            (Vector3::new(0.0, 0.0, -1.0), 1.0, 14),
            (Vector3::new(0.0, 0.0, 1.0), 1.0, 15),
        ];
        for (dir, range, label) in cases {
            let dir = Unit::new_normalize(dir);
            let hit = scene.cast(&Point3::origin(), &dir, 100.0).unwrap();
            assert!((hit.range_m - range).abs() < 1e-9, "{dir:?}");
            assert_eq!(scene.surface(hit.surface).unwrap().label, label);
            assert!(hit.normal.dot(&dir) < 0.0);
        }
        // From outside: the near face.
        let hit = scene
            .cast(&Point3::new(-5.0, 0.5, 0.2), &Vector3::x_axis(), 100.0)
            .unwrap();
        assert!((hit.range_m - 3.0).abs() < 1e-9);
        assert_eq!(scene.surface(hit.surface).unwrap().label, 10);
        assert!(
            scene
                .cast(&Point3::new(-5.0, 0.5, 0.2), &Vector3::x_axis(), 2.9)
                .is_none()
        );
    }

    #[test]
    fn cylinder_hit_matches_the_inscribed_polygon() {
        let mut builder = SceneBuilder3::new();
        let s = builder.add_surface(surface(3));
        builder.add_cylinder(Point3::new(5.0, 0.0, 0.0), 0.2, 3.0, 64, s);
        let scene = builder.build().unwrap();
        let hit = scene
            .cast(&Point3::new(0.0, 0.0, 1.0), &Vector3::x_axis(), 100.0)
            .unwrap();
        // A vertex of the 64-gon lies on the x axis: exact radius there.
        assert!((hit.range_m - 4.8).abs() < 1e-9, "{}", hit.range_m);
    }

    #[test]
    fn empty_scene_is_an_error() {
        assert!(SceneBuilder3::new().build().is_err());
    }
}
