//! Turning a [`World`] into triangles: a ray-castable [`Scene3`] whose surfaces carry
//! SemanticKITTI labels (with the pole id + 1 as instance on poles and their attachments) and
//! reflectivities.
//!
//! Round shafts are prisms whose cross-section has the area of the true circle (vertex radius
//! `r·√(2π / (n·sin(2π/n)))`), so a pole's mean apparent width equals its ground-truth width
//! within 3 %; `n` = 8 facets below 6 cm radius, 12 below 20 cm, 16 above. Canopies are
//! ellipsoid-like polyhedra (10 × 5 vertices, radii jittered ±12 % per vertex).

use std::f64::consts::{PI, TAU};

use nalgebra::{Point2, Point3, UnitQuaternion, Vector3};
use rand::Rng;
use raypath_geometry::Pose3;

use super::kinds::{PoleKind, label};
use super::world::{Building, Car, Footprint, Ground, PoleObject, SlabKind, World};
use crate::error::Result;
use crate::rng;
use crate::scene3::{Scene3, SceneBuilder3, Surface, SurfaceId};

/// Random-stream domain of canopy shapes.
const DOMAIN_CANOPY: u64 = 0x5552_4341_4e4f_5059;

/// Reflectivities of the facade materials (concrete, plaster, brick, stone, painted).
const FACADE_REFLECTIVITY: [f32; 8] = [0.15, 0.25, 0.35, 0.45, 0.55, 0.30, 0.20, 0.60];

/// Facets of a round shaft of radius `r`.
pub fn facets_for_radius(radius_m: f64) -> usize {
    if radius_m < 0.06 {
        8
    } else if radius_m < 0.2 {
        12
    } else {
        16
    }
}

/// Vertex radius of an `n`-gon with the area of the circle of radius `r`.
pub fn equal_area_radius(radius_m: f64, n: usize) -> f64 {
    let n = n as f64;
    radius_m * (TAU / (n * (TAU / n).sin())).sqrt()
}

/// Shared surfaces of a scene under construction.
struct Surfaces {
    road: SurfaceId,
    sidewalk: SurfaceId,
    curb: SurfaceId,
    terrain: SurfaceId,
    facades: Vec<SurfaceId>,
    glass: SurfaceId,
    fence: SurfaceId,
    barrel: SurfaceId,
}

impl Surfaces {
    fn new(b: &mut SceneBuilder3) -> Self {
        let mut s = |label, reflectivity| {
            b.add_surface(Surface {
                label,
                reflectivity,
            })
        };
        Self {
            road: s(label::ROAD, 0.12),
            sidewalk: s(label::SIDEWALK, 0.35),
            curb: s(label::SIDEWALK, 0.45),
            terrain: s(label::TERRAIN, 0.3),
            facades: FACADE_REFLECTIVITY
                .iter()
                .map(|&r| s(label::BUILDING, r))
                .collect(),
            glass: s(label::BUILDING, 0.08),
            fence: s(label::FENCE, 0.3),
            barrel: s(label::OTHER_OBJECT, 0.8),
        }
    }
}

impl World {
    /// Builds the ray-castable scene of this world.
    pub fn build_scene(&self) -> Result<Scene3> {
        let mut b = SceneBuilder3::new();
        let s = Surfaces::new(&mut b);
        add_ground(&mut b, &self.ground, s.road);
        for slab in &self.slabs {
            let (top, side) = match slab.kind {
                SlabKind::Sidewalk => (s.sidewalk, s.curb),
                SlabKind::Terrain => (s.terrain, s.curb),
            };
            add_prism(
                &mut b,
                &slab.footprint,
                slab.base_z,
                slab.height_m,
                [side; 4],
                top,
            );
        }
        for building in &self.buildings {
            add_building(&mut b, building, &s);
        }
        for pole in &self.poles {
            add_pole(&mut b, pole, self.foliage, self.mesh_seed);
        }
        for car in &self.cars {
            add_car(&mut b, car);
        }
        for fence in &self.fences {
            let d = fence.to - fence.from;
            let len = d.norm();
            if len > 1e-6 {
                let fp = Footprint {
                    center: nalgebra::center(&fence.from, &fence.to),
                    yaw_rad: d.y.atan2(d.x),
                    half_length_m: len / 2.0,
                    half_width_m: 0.025,
                };
                add_prism(
                    &mut b,
                    &fp,
                    fence.base_z,
                    fence.height_m,
                    [s.fence; 4],
                    s.fence,
                );
            }
        }
        for barrel in &self.barrels {
            let base = Point3::new(barrel.center.x, barrel.center.y, barrel.base_z);
            add_shaft(&mut b, base, barrel.radius_m, barrel.height_m, 12, s.barrel);
        }
        b.build()
    }
}

fn add_ground(b: &mut SceneBuilder3, ground: &Ground, road: SurfaceId) {
    match ground {
        Ground::Flat { min, max, z } => {
            let c = |x: f64, y: f64| Point3::new(x, y, *z);
            b.add_polygon(
                &[
                    c(min.x, min.y),
                    c(max.x, min.y),
                    c(max.x, max.y),
                    c(min.x, max.y),
                ],
                road,
            );
        }
        Ground::HeightField {
            origin,
            cell_m,
            nx,
            ny,
            heights,
            cells,
        } => {
            let vertex = |ix: usize, iy: usize| {
                let z = heights.get(iy * nx + ix).copied().unwrap_or(0.0);
                Point3::new(
                    origin.x + ix as f64 * cell_m,
                    origin.y + iy as f64 * cell_m,
                    z,
                )
            };
            for iy in 0..ny.saturating_sub(1) {
                for ix in 0..nx.saturating_sub(1) {
                    if cells.get(iy * (nx - 1) + ix).copied().unwrap_or(false) {
                        let quad = [
                            vertex(ix, iy),
                            vertex(ix + 1, iy),
                            vertex(ix + 1, iy + 1),
                            vertex(ix, iy + 1),
                        ];
                        b.add_triangle([quad[0], quad[1], quad[2]], road);
                        b.add_triangle([quad[0], quad[2], quad[3]], road);
                    }
                }
            }
        }
    }
}

/// A vertical prism over a footprint: four sides (−width side first, then +length, +width,
/// −length) and a top; no bottom (it rests on the ground).
fn add_prism(
    b: &mut SceneBuilder3,
    fp: &Footprint,
    base_z: f64,
    height_m: f64,
    sides: [SurfaceId; 4],
    top: SurfaceId,
) {
    let c = fp.corners();
    let at = |p: Point2<f64>, z: f64| Point3::new(p.x, p.y, z);
    let z1 = base_z + height_m;
    for (i, side) in sides.iter().enumerate() {
        let (p, q) = (c[i], c[(i + 1) % 4]);
        b.add_polygon(&[at(p, base_z), at(q, base_z), at(q, z1), at(p, z1)], *side);
    }
    b.add_polygon(&c.map(|p| at(p, z1)), top);
}

fn add_building(b: &mut SceneBuilder3, building: &Building, s: &Surfaces) {
    let facade = s.facades[building.material as usize % s.facades.len()];
    let fp = building.footprint;
    let recess = building.ground_floor_recess_m.clamp(0.0, fp.half_width_m);
    if recess > 0.0 {
        // Ground floor set back from the front (the −width side), glass front.
        let shift = nalgebra::Vector2::new(-fp.yaw_rad.sin(), fp.yaw_rad.cos()) * (recess / 2.0);
        let ground_floor = Footprint {
            center: fp.center + shift,
            half_width_m: fp.half_width_m - recess / 2.0,
            ..fp
        };
        let gf = building.ground_floor_height_m;
        add_prism(
            b,
            &ground_floor,
            building.base_z,
            gf,
            [s.glass, facade, facade, facade],
            facade,
        );
        // The upper floors overhang: their underside is visible from the street.
        let c = fp.corners();
        let z = building.base_z + gf;
        b.add_polygon(&c.map(|p| Point3::new(p.x, p.y, z)), facade);
        add_prism(b, &fp, z, building.height_m - gf, [facade; 4], facade);
    } else {
        add_prism(
            b,
            &fp,
            building.base_z,
            building.height_m,
            [facade; 4],
            facade,
        );
    }
    if building.top_floor_height_m > 0.0 {
        let top = Footprint {
            half_length_m: fp.half_length_m * 0.7,
            half_width_m: fp.half_width_m * 0.6,
            ..fp
        };
        let z = building.base_z + building.height_m;
        add_prism(b, &top, z, building.top_floor_height_m, [facade; 4], facade);
    }
}

/// A round vertical shaft with a top cap (no bottom).
pub(crate) fn add_shaft(
    b: &mut SceneBuilder3,
    base: Point3<f64>,
    radius_m: f64,
    height_m: f64,
    n: usize,
    surface: SurfaceId,
) {
    let rv = equal_area_radius(radius_m, n);
    let ring = |z: f64, i: usize| {
        let a = TAU * i as f64 / n as f64;
        base + Vector3::new(rv * a.cos(), rv * a.sin(), z)
    };
    for i in 0..n {
        let j = (i + 1) % n;
        b.add_polygon(
            &[
                ring(0.0, i),
                ring(0.0, j),
                ring(height_m, j),
                ring(height_m, i),
            ],
            surface,
        );
    }
    let top: Vec<Point3<f64>> = (0..n).map(|i| ring(height_m, i)).collect();
    b.add_polygon(&top, surface);
}

/// An axis box given by its centre, yaw and half extents.
fn add_yawed_box(
    b: &mut SceneBuilder3,
    center: Point3<f64>,
    yaw: f64,
    half: Vector3<f64>,
    s: SurfaceId,
) {
    let pose = Pose3::from_parts(
        center.coords,
        UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
    );
    b.add_box(&pose, half, [s; 6]);
}

fn add_pole(b: &mut SceneBuilder3, object: &PoleObject, foliage: f64, mesh_seed: u64) {
    let pole = &object.pole;
    let instance = pole.id + 1;
    let reflectivity = match pole.kind {
        PoleKind::StreetLight => 0.45,
        PoleKind::SignPost => 0.5,
        PoleKind::TreeTrunk => 0.3,
        PoleKind::Bollard => 0.6,
    };
    let shaft = b.add_surface(Surface {
        label: label::with_instance(pole.kind.class(), instance),
        reflectivity,
    });
    let base = Point3::new(pole.x, pole.y, pole.base_z);
    let n = facets_for_radius(pole.radius_m);
    let (dir_c, dir_s) = (object.yaw_rad.cos(), object.yaw_rad.sin());
    let top = pole.base_z + pole.height_m;
    match pole.kind {
        PoleKind::StreetLight => {
            add_shaft(b, base, pole.radius_m, pole.height_m, n, shaft);
            // Arm towards the road, lamp head at its end.
            let arm = object.attachment_m;
            let mid = Point3::new(
                pole.x + dir_c * arm / 2.0,
                pole.y + dir_s * arm / 2.0,
                top - 0.15,
            );
            add_yawed_box(
                b,
                mid,
                object.yaw_rad,
                Vector3::new(arm / 2.0, 0.04, 0.04),
                shaft,
            );
            let head = Point3::new(pole.x + dir_c * arm, pole.y + dir_s * arm, top - 0.25);
            add_yawed_box(
                b,
                head,
                object.yaw_rad,
                Vector3::new(0.3, 0.15, 0.08),
                shaft,
            );
        }
        PoleKind::SignPost => {
            add_shaft(b, base, pole.radius_m, pole.height_m, n, shaft);
            let plate = b.add_surface(Surface {
                label: label::with_instance(label::TRAFFIC_SIGN, instance),
                reflectivity: 0.9,
            });
            // The plate faces along `yaw` (towards oncoming traffic), just above the post.
            let w = object.attachment_m;
            let center = Point3::new(pole.x, pole.y, top + w / 2.0 - 0.05);
            add_yawed_box(
                b,
                center,
                object.yaw_rad,
                Vector3::new(0.015, w / 2.0, w / 2.0),
                plate,
            );
        }
        PoleKind::Bollard => add_shaft(b, base, pole.radius_m, pole.height_m, n, shaft),
        PoleKind::TreeTrunk => {
            let Some(canopy) = object.canopy else {
                add_shaft(b, base, pole.radius_m, pole.height_m, n, shaft);
                return;
            };
            let rx = canopy.radius_m * foliage;
            let rz = canopy.half_height_m * foliage.sqrt();
            let center_z = top + rz * 0.9;
            // The trunk continues into the crown.
            add_shaft(b, base, pole.radius_m, center_z - pole.base_z, n, shaft);
            let crown = b.add_surface(Surface {
                label: label::with_instance(label::VEGETATION, instance),
                reflectivity: 0.45,
            });
            let mut rng = rng::stream(mesh_seed, DOMAIN_CANOPY, u64::from(pole.id));
            add_canopy(
                b,
                Point3::new(pole.x, pole.y, center_z),
                rx,
                rz,
                &mut rng,
                crown,
            );
        }
    }
}

/// An ellipsoid-like polyhedron: 10 meridians × 3 inner rings plus two apexes.
fn add_canopy(
    b: &mut SceneBuilder3,
    center: Point3<f64>,
    rx: f64,
    rz: f64,
    rng: &mut rng::SimRng,
    s: SurfaceId,
) {
    const LON: usize = 10;
    const RINGS: usize = 3;
    let mut jitter = || 1.0 + rng.random_range(-0.12..0.12);
    let mut rings = [[Point3::origin(); LON]; RINGS];
    for (k, ring) in rings.iter_mut().enumerate() {
        let lat = -PI / 2.0 + PI * (k + 1) as f64 / (RINGS + 1) as f64;
        for (i, v) in ring.iter_mut().enumerate() {
            let lon = TAU * (i as f64 + 0.5 * (k % 2) as f64) / LON as f64;
            let r = rx * lat.cos() * jitter();
            *v = center + Vector3::new(r * lon.cos(), r * lon.sin(), rz * lat.sin() * jitter());
        }
    }
    let bottom = center - Vector3::new(0.0, 0.0, rz * jitter());
    let apex = center + Vector3::new(0.0, 0.0, rz * jitter());
    for i in 0..LON {
        let j = (i + 1) % LON;
        b.add_triangle([bottom, rings[0][j], rings[0][i]], s);
        b.add_triangle([apex, rings[RINGS - 1][i], rings[RINGS - 1][j]], s);
        for k in 0..RINGS - 1 {
            let (lo, hi) = (&rings[k], &rings[k + 1]);
            b.add_triangle([lo[i], lo[j], hi[i]], s);
            b.add_triangle([lo[j], hi[j], hi[i]], s);
        }
    }
}

fn add_car(b: &mut SceneBuilder3, car: &Car) {
    let s = b.add_surface(Surface {
        label: label::CAR,
        reflectivity: car.reflectivity,
    });
    let fp = car.footprint;
    let (l, w) = (fp.half_length_m, fp.half_width_m);
    let yaw = fp.yaw_rad;
    let to_world = |x: f64, y: f64, z: f64| {
        let (sn, cs) = yaw.sin_cos();
        Point3::new(
            fp.center.x + x * cs - y * sn,
            fp.center.y + x * sn + y * cs,
            car.base_z + z,
        )
    };
    // Body between the wheels' tops and the belt line.
    let belt = (car.height_m * 0.6).max(0.8);
    let body = to_world(0.0, 0.0, (0.3 + belt) / 2.0);
    add_yawed_box(b, body, yaw, Vector3::new(l, w, (belt - 0.3) / 2.0), s);
    // Cabin: a frustum with sloped windscreens, set back a little.
    let (lb, lt, wt) = (l * 0.62, l * 0.38, w * 0.88);
    let x0 = -0.1 * l;
    let bottom = [
        to_world(x0 - lb, -w, belt),
        to_world(x0 + lb, -w, belt),
        to_world(x0 + lb, w, belt),
        to_world(x0 - lb, w, belt),
    ];
    let top = [
        to_world(x0 - lt, -wt, car.height_m),
        to_world(x0 + lt, -wt, car.height_m),
        to_world(x0 + lt, wt, car.height_m),
        to_world(x0 - lt, wt, car.height_m),
    ];
    for i in 0..4 {
        let j = (i + 1) % 4;
        b.add_polygon(&[bottom[i], bottom[j], top[j], top[i]], s);
    }
    b.add_polygon(&top, s);
    // Wheels.
    for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        let c = to_world(sx * l * 0.68, sy * (w - 0.12), 0.3);
        add_yawed_box(b, c, yaw, Vector3::new(0.3, 0.1, 0.3), s);
    }
}
