//! More solids for [`SceneBuilder3`]: prisms, wedges, stairs, capped cylinders and spheres.
//!
//! Every solid is closed and built from planar faces (curved ones approximated by facets);
//! each planar face takes its own [`SurfaceId`] where the caller asks for it, so that plane
//! ground truth can label faces separately. Sizes are in metres, poses place the solid's own
//! frame in the world.

use std::f64::consts::{PI, TAU};

use nalgebra::{Point2, Point3, Vector3};
use raypath_geometry::Pose3;

use super::{SceneBuilder3, SurfaceId};
use crate::error::{Result, SimError};

fn invalid(name: &'static str, reason: String) -> SimError {
    SimError::InvalidParameter { name, reason }
}

fn positive(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(invalid(
            name,
            format!("{value} (expected a finite value > 0)"),
        ))
    }
}

/// True when `polygon` (at least 3 finite vertices) is strictly convex and counter-clockwise.
pub(crate) fn is_convex_ccw(polygon: &[Point2<f64>]) -> bool {
    let n = polygon.len();
    n >= 3
        && polygon.iter().all(|p| p.x.is_finite() && p.y.is_finite())
        && (0..n).all(|i| {
            let (a, b, c) = (polygon[i], polygon[(i + 1) % n], polygon[(i + 2) % n]);
            (b - a).perp(&(c - b)) > 1e-12
        })
}

impl SceneBuilder3 {
    /// Adds a right prism: the convex, counter-clockwise polygon `base_ccw` in the xy-plane of
    /// the prism frame, extruded from z = 0 to z = `height_m`, placed by `world_from_prism`.
    /// `faces` gives the surfaces of the bottom, the top, then side `i` (from vertex `i` to
    /// `i + 1`) for every vertex: `base_ccw.len() + 2` entries.
    pub fn add_prism(
        &mut self,
        world_from_prism: &Pose3,
        base_ccw: &[Point2<f64>],
        height_m: f64,
        faces: &[SurfaceId],
    ) -> Result<()> {
        positive("height_m", height_m)?;
        if !is_convex_ccw(base_ccw) {
            return Err(invalid(
                "base_ccw",
                format!(
                    "the {} vertices do not form a convex counter-clockwise polygon",
                    base_ccw.len()
                ),
            ));
        }
        let n = base_ccw.len();
        if faces.len() != n + 2 {
            return Err(invalid(
                "faces",
                format!("{} surfaces for a prism with {} faces", faces.len(), n + 2),
            ));
        }
        let at =
            |p: &Point2<f64>, z: f64| world_from_prism.transform_point(&Point3::new(p.x, p.y, z));
        let bottom: Vec<Point3<f64>> = base_ccw.iter().rev().map(|p| at(p, 0.0)).collect();
        let top: Vec<Point3<f64>> = base_ccw.iter().map(|p| at(p, height_m)).collect();
        self.add_polygon(&bottom, faces[0]);
        self.add_polygon(&top, faces[1]);
        for i in 0..n {
            let (a, b) = (&base_ccw[i], &base_ccw[(i + 1) % n]);
            self.add_polygon(
                &[at(a, 0.0), at(b, 0.0), at(b, height_m), at(a, height_m)],
                faces[i + 2],
            );
        }
        Ok(())
    }

    /// Adds a wedge (a ramp): the bottom rectangle `[−l/2, l/2] × [−w/2, w/2]` at z = 0 of
    /// the wedge frame (`size_m = (l, w, h)`), a vertical back face at x = l/2 of height `h`
    /// and the slope rising from the front edge (x = −l/2, z = 0) to the top of the back face.
    /// `faces`: bottom, back, slope, the −y side and the +y side (triangles).
    pub fn add_wedge(
        &mut self,
        world_from_wedge: &Pose3,
        size_m: Vector3<f64>,
        faces: [SurfaceId; 5],
    ) -> Result<()> {
        for (name, v) in [
            ("size_m.x", size_m.x),
            ("size_m.y", size_m.y),
            ("size_m.z", size_m.z),
        ] {
            positive(name, v)?;
        }
        let (hl, hw, h) = (size_m.x / 2.0, size_m.y / 2.0, size_m.z);
        let p = |x: f64, y: f64, z: f64| world_from_wedge.transform_point(&Point3::new(x, y, z));
        let (front_l, front_r) = (p(-hl, -hw, 0.0), p(-hl, hw, 0.0));
        let (back_l, back_r) = (p(hl, -hw, 0.0), p(hl, hw, 0.0));
        let (top_l, top_r) = (p(hl, -hw, h), p(hl, hw, h));
        self.add_polygon(&[front_l, front_r, back_r, back_l], faces[0]);
        self.add_polygon(&[back_l, back_r, top_r, top_l], faces[1]);
        self.add_polygon(&[front_l, top_l, top_r, front_r], faces[2]);
        self.add_polygon(&[front_l, back_l, top_l], faces[3]);
        self.add_polygon(&[front_r, top_r, back_r], faces[4]);
        Ok(())
    }

    /// Adds a flight of `steps` solid stairs rising along +x of the stairs frame: step `k`
    /// occupies `x ∈ [k·d, (k+1)·d]`, `z ∈ [0, (k+1)·h]`, `y ∈ [−w/2, w/2]` (`d` =
    /// `step_depth_m`, `h` = `step_height_m`, `w` = `width_m`). `faces`: the treads (top of
    /// step `k`), then the risers (front of step `k`), then the −y side, the +y side, the back
    /// (x = steps·d) and the bottom: `2·steps + 4` entries.
    pub fn add_stairs(
        &mut self,
        world_from_stairs: &Pose3,
        steps: usize,
        step_depth_m: f64,
        step_height_m: f64,
        width_m: f64,
        faces: &[SurfaceId],
    ) -> Result<()> {
        positive("step_depth_m", step_depth_m)?;
        positive("step_height_m", step_height_m)?;
        positive("width_m", width_m)?;
        if steps == 0 || faces.len() != 2 * steps + 4 {
            return Err(invalid(
                "faces",
                format!(
                    "{} surfaces for {steps} steps (expected 2·steps + 4)",
                    faces.len()
                ),
            ));
        }
        let (d, h, hw) = (step_depth_m, step_height_m, width_m / 2.0);
        let p = |x: f64, y: f64, z: f64| world_from_stairs.transform_point(&Point3::new(x, y, z));
        let (left, right, back, bottom) = (
            faces[2 * steps],
            faces[2 * steps + 1],
            faces[2 * steps + 2],
            faces[2 * steps + 3],
        );
        for k in 0..steps {
            let (x0, x1) = (k as f64 * d, (k + 1) as f64 * d);
            let (z0, z1) = (k as f64 * h, (k + 1) as f64 * h);
            // Tread and riser.
            self.add_polygon(
                &[p(x0, -hw, z1), p(x1, -hw, z1), p(x1, hw, z1), p(x0, hw, z1)],
                faces[k],
            );
            self.add_polygon(
                &[p(x0, -hw, z0), p(x0, hw, z0), p(x0, hw, z1), p(x0, -hw, z1)],
                faces[steps + k],
            );
            // The side profiles, one column per step.
            self.add_polygon(
                &[
                    p(x0, -hw, 0.0),
                    p(x1, -hw, 0.0),
                    p(x1, -hw, z1),
                    p(x0, -hw, z1),
                ],
                left,
            );
            self.add_polygon(
                &[p(x0, hw, 0.0), p(x0, hw, z1), p(x1, hw, z1), p(x1, hw, 0.0)],
                right,
            );
        }
        let (xe, ze) = (steps as f64 * d, steps as f64 * h);
        self.add_polygon(
            &[
                p(xe, -hw, 0.0),
                p(xe, hw, 0.0),
                p(xe, hw, ze),
                p(xe, -hw, ze),
            ],
            back,
        );
        self.add_polygon(
            &[
                p(0.0, -hw, 0.0),
                p(0.0, hw, 0.0),
                p(xe, hw, 0.0),
                p(xe, -hw, 0.0),
            ],
            bottom,
        );
        Ok(())
    }

    /// Adds a closed vertical-axis cylinder of `segments` facets whose side, bottom cap and
    /// top cap are separate surfaces (the caps are planes, the side is curved).
    pub fn add_capped_cylinder(
        &mut self,
        base_center: Point3<f64>,
        radius_m: f64,
        height_m: f64,
        segments: usize,
        [side, bottom, top]: [SurfaceId; 3],
    ) {
        let n = segments.max(3);
        let point = |i: usize, z: f64| {
            let a = TAU * i as f64 / n as f64;
            base_center + Vector3::new(radius_m * a.cos(), radius_m * a.sin(), z)
        };
        for i in 0..n {
            let j = (i + 1) % n;
            self.add_polygon(
                &[
                    point(i, 0.0),
                    point(j, 0.0),
                    point(j, height_m),
                    point(i, height_m),
                ],
                side,
            );
        }
        let bottom_ring: Vec<Point3<f64>> = (0..n).rev().map(|i| point(i, 0.0)).collect();
        let top_ring: Vec<Point3<f64>> = (0..n).map(|i| point(i, height_m)).collect();
        self.add_polygon(&bottom_ring, bottom);
        self.add_polygon(&top_ring, top);
    }

    /// Adds a sphere as a latitude/longitude mesh of `rings` bands and `segments` sectors
    /// (its vertices lie on the sphere).
    pub fn add_sphere(
        &mut self,
        center: Point3<f64>,
        radius_m: f64,
        rings: usize,
        segments: usize,
        surface: SurfaceId,
    ) {
        let (rings, segments) = (rings.max(2), segments.max(3));
        let point = |ring: usize, seg: usize| {
            let polar = PI * ring as f64 / rings as f64;
            let azimuth = TAU * seg as f64 / segments as f64;
            center
                + radius_m
                    * Vector3::new(
                        polar.sin() * azimuth.cos(),
                        polar.sin() * azimuth.sin(),
                        polar.cos(),
                    )
        };
        for ring in 0..rings {
            for seg in 0..segments {
                let next = (seg + 1) % segments;
                let (a, b) = (point(ring, seg), point(ring, next));
                let (c, d) = (point(ring + 1, next), point(ring + 1, seg));
                // The poles' quads degenerate into triangles; add_triangle skips the rest.
                self.add_triangle([a, d, c], surface);
                self.add_triangle([a, c, b], surface);
            }
        }
    }
}
