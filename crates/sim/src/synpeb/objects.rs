//! The polyhedral furniture of a SynPEB-style room: random shapes in their own frame and how
//! they are added to a scene, every planar face with its own plane label.
//!
//! An object's frame has its origin on the floor at the centre of its footprint, z up; for
//! objects placed against a wall, +x points at the wall (the back of shelves, stairs and
//! wedges is at +x).

use std::f64::consts::TAU;

use nalgebra::{Point2, Point3, Quaternion, UnitQuaternion, Vector2, Vector3};
use rand::Rng;
use rand_distr::StandardNormal;
use raypath_geometry::Pose3;

use crate::error::Result;
use crate::rng::SimRng;
use crate::scene3::is_convex_ccw;
use crate::scene3::{SceneBuilder3, Surface, SurfaceId};

/// Label of curved surfaces (cylinder sides) — not planes.
pub const LABEL_CYLINDER: u32 = 1;
/// Label of spheres — not planes.
pub const LABEL_SPHERE: u32 = 2;
/// The first plane label (SynPEB: labels ≥ 10 are planes).
pub const FIRST_PLANE_LABEL: u32 = 10;

/// Facets of cylinders around the axis.
const CYLINDER_SEGMENTS: usize = 48;

/// Hands out surfaces: a new plane label for every planar face.
pub(crate) struct Labeler {
    pub builder: SceneBuilder3,
    next_label: u32,
}

impl Labeler {
    pub fn new() -> Self {
        Self {
            builder: SceneBuilder3::new(),
            next_label: FIRST_PLANE_LABEL,
        }
    }

    /// Number of plane labels handed out.
    pub fn planes_created(&self) -> usize {
        (self.next_label - FIRST_PLANE_LABEL) as usize
    }

    /// A new planar face with its own label.
    pub fn plane(&mut self) -> SurfaceId {
        let label = self.next_label;
        self.next_label += 1;
        self.builder.add_surface(Surface {
            label,
            reflectivity: 0.5,
        })
    }

    pub fn planes<const N: usize>(&mut self) -> [SurfaceId; N] {
        std::array::from_fn(|_| self.plane())
    }

    pub fn plane_vec(&mut self, n: usize) -> Vec<SurfaceId> {
        (0..n).map(|_| self.plane()).collect()
    }

    /// A curved surface with a fixed label below 10.
    pub fn curved(&mut self, label: u32) -> SurfaceId {
        self.builder.add_surface(Surface {
            label,
            reflectivity: 0.5,
        })
    }
}

/// A shape and its dimensions (metres).
#[derive(Clone, Debug)]
pub(crate) enum Shape {
    Cuboid(Vector3<f64>),
    Wedge(Vector3<f64>),
    Prism {
        base: Vec<Point2<f64>>,
        height: f64,
    },
    Stairs {
        steps: usize,
        depth: f64,
        rise: f64,
        width: f64,
    },
    Table {
        size: Vector2<f64>,
        height: f64,
        top: f64,
        leg: f64,
    },
    Shelf {
        depth: f64,
        width: f64,
        height: f64,
        board: f64,
        shelves: usize,
    },
    /// A cuboid or prism (`body` vertices around its centroid) in a random orientation,
    /// resting on its lowest vertex.
    Tumbled {
        inner: Box<Shape>,
        rotation: UnitQuaternion<f64>,
    },
    Cylinder {
        radius: f64,
        height: f64,
    },
    Sphere {
        radius: f64,
    },
    /// A cuboid cabinet mounted on a wall with its bottom at `mount`.
    Cabinet {
        size: Vector3<f64>,
        mount: f64,
    },
}

/// Which shape to draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    Cuboid,
    Wedge,
    Prism,
    Stairs,
    Table,
    Shelf,
    TumbledCuboid,
    TumbledPrism,
    Cylinder,
    Sphere,
    Cabinet,
}

/// Relative frequencies of the kinds of standing objects.
pub(super) const KIND_WEIGHTS: [(Kind, f64); 11] = [
    (Kind::Cuboid, 0.20),
    (Kind::Wedge, 0.12),
    (Kind::Prism, 0.12),
    (Kind::Stairs, 0.06),
    (Kind::Table, 0.08),
    (Kind::Shelf, 0.07),
    (Kind::TumbledCuboid, 0.10),
    (Kind::TumbledPrism, 0.08),
    (Kind::Cylinder, 0.08),
    (Kind::Sphere, 0.07),
    (Kind::Cabinet, 0.07),
];

/// The kinds of `n` standing objects: each kind in proportion to its weight (largest
/// remainders round), in random order — so that rooms of one size have the same mix.
pub(super) fn kind_mix(n: usize, rng: &mut SimRng) -> Vec<Kind> {
    let total: f64 = KIND_WEIGHTS.iter().map(|(_, w)| w).sum();
    let quotas: Vec<f64> = KIND_WEIGHTS
        .iter()
        .map(|(_, w)| w / total * n as f64)
        .collect();
    let mut counts: Vec<usize> = quotas.iter().map(|q| q.floor() as usize).collect();
    let mut by_remainder: Vec<usize> = (0..quotas.len()).collect();
    by_remainder.sort_by(|&a, &b| {
        (quotas[b] - quotas[b].floor()).total_cmp(&(quotas[a] - quotas[a].floor()))
    });
    let missing = n.saturating_sub(counts.iter().sum());
    for &k in by_remainder.iter().cycle().take(missing) {
        counts[k] += 1;
    }
    let mut kinds: Vec<Kind> = KIND_WEIGHTS
        .iter()
        .zip(&counts)
        .flat_map(|((kind, _), &c)| std::iter::repeat_n(*kind, c))
        .collect();
    // Fisher–Yates with the room's stream.
    for i in (1..kinds.len()).rev() {
        kinds.swap(i, rng.random_range(0..=i));
    }
    kinds
}

/// A convex polygon of `n` vertices around the origin with radii jittered by ±15 % (the
/// regular polygon when the jitter breaks convexity).
pub(crate) fn random_polygon(rng: &mut SimRng, n: usize, radius: f64) -> Vec<Point2<f64>> {
    let phase = rng.random_range(0.0..TAU);
    let jittered: Vec<Point2<f64>> = (0..n)
        .map(|i| {
            let a = phase + TAU * i as f64 / n as f64;
            let r = radius * rng.random_range(0.85..1.15);
            Point2::new(r * a.cos(), r * a.sin())
        })
        .collect();
    if is_convex_ccw(&jittered) {
        jittered
    } else {
        (0..n)
            .map(|i| {
                let a = phase + TAU * i as f64 / n as f64;
                Point2::new(radius * a.cos(), radius * a.sin())
            })
            .collect()
    }
}

/// A uniformly random rotation.
fn random_rotation(rng: &mut SimRng) -> UnitQuaternion<f64> {
    loop {
        let q = Quaternion::new(
            rng.sample::<f64, _>(StandardNormal),
            rng.sample(StandardNormal),
            rng.sample(StandardNormal),
            rng.sample(StandardNormal),
        );
        if q.norm() > 1e-6 {
            return UnitQuaternion::from_quaternion(q);
        }
    }
}

impl Shape {
    /// A random shape of `kind`; `small` asks for an object to put on a table or box.
    pub fn random(kind: Kind, rng: &mut SimRng, small: bool) -> Self {
        let scale = if small { 0.4 } else { 0.8 };
        let mut u = |lo: f64, hi: f64| scale * rng.random_range(lo..hi);
        match kind {
            Kind::Cuboid => Shape::Cuboid(Vector3::new(u(0.3, 1.2), u(0.3, 1.0), u(0.2, 1.4))),
            Kind::Wedge => Shape::Wedge(Vector3::new(u(0.5, 1.5), u(0.4, 1.2), u(0.3, 1.0))),
            Kind::Prism => {
                let (radius, height) = (u(0.2, 0.6), u(0.3, 1.5));
                let n = [3, 5, 6][rng.random_range(0..3)];
                Shape::Prism {
                    base: random_polygon(rng, n, radius),
                    height,
                }
            }
            Kind::Stairs => Shape::Stairs {
                steps: rng.random_range(3..=6),
                depth: rng.random_range(0.25..0.35),
                rise: rng.random_range(0.15..0.2),
                width: rng.random_range(0.6..1.4),
            },
            Kind::Table => Shape::Table {
                size: Vector2::new(rng.random_range(0.8..1.6), rng.random_range(0.6..1.0)),
                height: rng.random_range(0.7..0.8),
                top: rng.random_range(0.03..0.06),
                leg: rng.random_range(0.04..0.08),
            },
            Kind::Shelf => Shape::Shelf {
                depth: rng.random_range(0.3..0.45),
                width: rng.random_range(0.6..1.2),
                height: rng.random_range(1.2..2.0),
                board: rng.random_range(0.02..0.03),
                shelves: rng.random_range(2..=4),
            },
            Kind::TumbledCuboid => {
                let size = Vector3::new(u(0.3, 0.8), u(0.3, 0.8), u(0.3, 0.8));
                Shape::Tumbled {
                    inner: Box::new(Shape::Cuboid(size)),
                    rotation: random_rotation(rng),
                }
            }
            Kind::TumbledPrism => {
                let (radius, height) = (u(0.2, 0.5), u(0.3, 0.8));
                let n = rng.random_range(3..=6);
                Shape::Tumbled {
                    inner: Box::new(Shape::Prism {
                        base: random_polygon(rng, n, radius),
                        height,
                    }),
                    rotation: random_rotation(rng),
                }
            }
            Kind::Cylinder => Shape::Cylinder {
                radius: u(0.1, 0.35),
                height: u(0.3, 1.5),
            },
            Kind::Sphere => Shape::Sphere {
                radius: u(0.15, 0.4),
            },
            Kind::Cabinet => Shape::Cabinet {
                size: Vector3::new(u(0.3, 0.45), u(0.5, 1.2), u(0.4, 0.8)),
                mount: rng.random_range(1.2..1.8),
            },
        }
    }

    /// The same shape with every length multiplied by `factor` (angles, step and shelf
    /// counts kept): room furniture shrunk to table-top blocks.
    pub fn scaled(&self, factor: f64) -> Self {
        let k = factor;
        match self {
            Shape::Cuboid(s) => Shape::Cuboid(s * k),
            Shape::Wedge(s) => Shape::Wedge(s * k),
            Shape::Prism { base, height } => Shape::Prism {
                base: base.iter().map(|p| Point2::from(p.coords * k)).collect(),
                height: height * k,
            },
            Shape::Stairs {
                steps,
                depth,
                rise,
                width,
            } => Shape::Stairs {
                steps: *steps,
                depth: depth * k,
                rise: rise * k,
                width: width * k,
            },
            Shape::Table {
                size,
                height,
                top,
                leg,
            } => Shape::Table {
                size: size * k,
                height: height * k,
                top: top * k,
                leg: leg * k,
            },
            Shape::Shelf {
                depth,
                width,
                height,
                board,
                shelves,
            } => Shape::Shelf {
                depth: depth * k,
                width: width * k,
                height: height * k,
                board: board * k,
                shelves: *shelves,
            },
            Shape::Tumbled { inner, rotation } => Shape::Tumbled {
                inner: Box::new(inner.scaled(k)),
                rotation: *rotation,
            },
            Shape::Cylinder { radius, height } => Shape::Cylinder {
                radius: radius * k,
                height: height * k,
            },
            Shape::Sphere { radius } => Shape::Sphere { radius: radius * k },
            Shape::Cabinet { size, mount } => Shape::Cabinet {
                size: size * k,
                mount: mount * k,
            },
        }
    }

    /// Vertices of a cuboid or prism body centred on its centroid (for tumbling).
    fn body_vertices(&self) -> Vec<Point3<f64>> {
        match self {
            Shape::Cuboid(s) => (0..8)
                .map(|i| {
                    let sign = |bit: usize| if i & bit == 0 { -0.5 } else { 0.5 };
                    Point3::new(sign(1) * s.x, sign(2) * s.y, sign(4) * s.z)
                })
                .collect(),
            Shape::Prism { base, height } => base
                .iter()
                .flat_map(|p| {
                    [
                        Point3::new(p.x, p.y, -height / 2.0),
                        Point3::new(p.x, p.y, height / 2.0),
                    ]
                })
                .collect(),
            _ => Vec::new(),
        }
    }

    /// For a tumbled shape: the rotated body's lowest z (≤ 0) and its xy half extents.
    fn tumbled_extents(inner: &Shape, rotation: &UnitQuaternion<f64>) -> (f64, f64, Vector2<f64>) {
        let (mut lo, mut hi, mut half) = (0.0_f64, 0.0_f64, Vector2::zeros());
        for v in inner.body_vertices() {
            let r = rotation * v;
            lo = lo.min(r.z);
            hi = hi.max(r.z);
            half.x = f64::max(half.x, r.x.abs());
            half.y = f64::max(half.y, r.y.abs());
        }
        (lo, hi, half)
    }

    /// Half extents of the footprint in the object frame (x, y).
    pub fn half_footprint(&self) -> Vector2<f64> {
        match self {
            Shape::Cuboid(s) | Shape::Wedge(s) => Vector2::new(s.x / 2.0, s.y / 2.0),
            Shape::Prism { base, .. } => base.iter().fold(Vector2::zeros(), |h, p| {
                Vector2::new(h.x.max(p.x.abs()), h.y.max(p.y.abs()))
            }),
            Shape::Stairs {
                steps,
                depth,
                width,
                ..
            } => Vector2::new(*steps as f64 * depth / 2.0, width / 2.0),
            Shape::Table { size, .. } => size / 2.0,
            Shape::Shelf { depth, width, .. } => Vector2::new(depth / 2.0, width / 2.0),
            Shape::Tumbled { inner, rotation } => Self::tumbled_extents(inner, rotation).2,
            Shape::Cylinder { radius, .. } => Vector2::new(*radius, *radius),
            Shape::Sphere { radius } => Vector2::new(*radius, *radius),
            Shape::Cabinet { size, .. } => Vector2::new(size.x / 2.0, size.y / 2.0),
        }
    }

    /// Height of the top above the floor.
    pub fn height(&self) -> f64 {
        match self {
            Shape::Cuboid(s) | Shape::Wedge(s) => s.z,
            Shape::Prism { height, .. } | Shape::Table { height, .. } => *height,
            Shape::Shelf { height, .. } | Shape::Cylinder { height, .. } => *height,
            Shape::Stairs { steps, rise, .. } => *steps as f64 * rise,
            Shape::Tumbled { inner, rotation } => {
                let (lo, hi, _) = Self::tumbled_extents(inner, rotation);
                hi - lo
            }
            Shape::Sphere { radius } => 2.0 * radius,
            Shape::Cabinet { size, mount } => mount + size.z,
        }
    }

    /// How often the shape is placed against a wall (its back at +x) rather than anywhere.
    pub fn wall_probability(&self) -> f64 {
        match self {
            Shape::Cabinet { .. } => 1.0,
            Shape::Stairs { .. } | Shape::Shelf { .. } | Shape::Wedge(_) => 0.85,
            _ => 0.35,
        }
    }

    /// The top a small object can stand on: half extents of the usable area, or `None`.
    pub fn support_top(&self) -> Option<Vector2<f64>> {
        match self {
            Shape::Cuboid(s) if s.z < 1.5 && s.x > 0.3 && s.y > 0.3 => {
                Some(Vector2::new(s.x, s.y) / 2.0)
            }
            Shape::Table { size, .. } => Some(size / 2.0),
            _ => None,
        }
    }

    /// Adds the shape standing on the floor point of `world_from_object` (z of that pose is
    /// the height of the surface it stands on).
    pub fn add_to(&self, labels: &mut Labeler, world_from_object: &Pose3) -> Result<()> {
        let at = |x: f64, y: f64, z: f64| {
            *world_from_object * Pose3::from_xyz_rpy(x, y, z, 0.0, 0.0, 0.0)
        };
        match self {
            Shape::Cuboid(s) => {
                let faces = labels.planes::<6>();
                labels
                    .builder
                    .add_box(&at(0.0, 0.0, s.z / 2.0), s / 2.0, faces);
            }
            Shape::Wedge(s) => {
                let faces = labels.planes::<5>();
                labels.builder.add_wedge(world_from_object, *s, faces)?;
            }
            Shape::Prism { base, height } => {
                let faces = labels.plane_vec(base.len() + 2);
                labels
                    .builder
                    .add_prism(world_from_object, base, *height, &faces)?;
            }
            Shape::Stairs {
                steps,
                depth,
                rise,
                width,
            } => {
                let faces = labels.plane_vec(2 * steps + 4);
                let start = at(-(*steps as f64) * depth / 2.0, 0.0, 0.0);
                labels
                    .builder
                    .add_stairs(&start, *steps, *depth, *rise, *width, &faces)?;
            }
            Shape::Table {
                size,
                height,
                top,
                leg,
            } => {
                let faces = labels.planes::<6>();
                let half_top = Vector3::new(size.x / 2.0, size.y / 2.0, top / 2.0);
                labels
                    .builder
                    .add_box(&at(0.0, 0.0, height - top / 2.0), half_top, faces);
                let inset = 0.03 + leg / 2.0;
                let leg_half = Vector3::new(leg / 2.0, leg / 2.0, (height - top) / 2.0);
                for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                    let faces = labels.planes::<6>();
                    let pose = at(
                        sx * (size.x / 2.0 - inset),
                        sy * (size.y / 2.0 - inset),
                        leg_half.z,
                    );
                    labels.builder.add_box(&pose, leg_half, faces);
                }
            }
            Shape::Shelf {
                depth,
                width,
                height,
                board,
                shelves,
            } => {
                let (d, w, h, t) = (*depth, *width, *height, *board);
                for side in [-1.0, 1.0] {
                    let faces = labels.planes::<6>();
                    let pose = at(0.0, side * (w - t) / 2.0, h / 2.0);
                    labels
                        .builder
                        .add_box(&pose, Vector3::new(d / 2.0, t / 2.0, h / 2.0), faces);
                }
                // The back panel between the sides, then the boards in front of it.
                let faces = labels.planes::<6>();
                let back = Vector3::new(t / 4.0, w / 2.0 - t, h / 2.0);
                labels
                    .builder
                    .add_box(&at(d / 2.0 - t / 4.0, 0.0, h / 2.0), back, faces);
                let board_half = Vector3::new(d / 2.0 - t / 4.0, w / 2.0 - t, t / 2.0);
                let (bottom, top) = (0.08 + t / 2.0, h - t / 2.0);
                let levels = shelves + 2;
                for k in 0..levels {
                    let z = bottom + (top - bottom) * k as f64 / (levels - 1) as f64;
                    let faces = labels.planes::<6>();
                    labels
                        .builder
                        .add_box(&at(-t / 4.0, 0.0, z), board_half, faces);
                }
            }
            Shape::Tumbled { inner, rotation } => {
                let (lo, _, _) = Self::tumbled_extents(inner, rotation);
                let body =
                    *world_from_object * Pose3::from_parts(Vector3::new(0.0, 0.0, -lo), *rotation);
                match inner.as_ref() {
                    Shape::Cuboid(s) => {
                        let faces = labels.planes::<6>();
                        labels.builder.add_box(&body, s / 2.0, faces);
                    }
                    Shape::Prism { base, height } => {
                        let faces = labels.plane_vec(base.len() + 2);
                        let bottom =
                            body * Pose3::from_xyz_rpy(0.0, 0.0, -height / 2.0, 0.0, 0.0, 0.0);
                        labels.builder.add_prism(&bottom, base, *height, &faces)?;
                    }
                    _ => {}
                }
            }
            Shape::Cylinder { radius, height } => {
                let side = labels.curved(LABEL_CYLINDER);
                let caps = labels.planes::<2>();
                let base = Point3::from(world_from_object.translation());
                labels.builder.add_capped_cylinder(
                    base,
                    *radius,
                    *height,
                    CYLINDER_SEGMENTS,
                    [side, caps[0], caps[1]],
                );
            }
            Shape::Cabinet { size, mount } => {
                let faces = labels.planes::<6>();
                labels
                    .builder
                    .add_box(&at(0.0, 0.0, mount + size.z / 2.0), size / 2.0, faces);
            }
            Shape::Sphere { radius } => {
                let surface = labels.curved(LABEL_SPHERE);
                let center = world_from_object.transform_point(&Point3::new(0.0, 0.0, *radius));
                labels.builder.add_sphere(center, *radius, 16, 32, surface);
            }
        }
        Ok(())
    }
}
