//! The objects of an urban world, as data: ground, sidewalk slabs, buildings, poles (with
//! arms, signs and canopies), parked cars, fences and construction barrels. World frame:
//! REP-103 (x, y horizontal, z up), metres, yaw in radians counter-clockwise from x.
//! [`World::build_scene`](super::mesh) turns a world into a ray-castable [`Scene3`](crate::scene3::Scene3).

use nalgebra::Point2;

use super::kinds::{Canopy, Pole, PoleKind};

/// An oriented rectangle on the ground plane.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Footprint {
    /// Centre, metres.
    pub center: Point2<f64>,
    /// Direction of the length axis, radians.
    pub yaw_rad: f64,
    /// Half of the extent along the length axis, metres.
    pub half_length_m: f64,
    /// Half of the extent across, metres.
    pub half_width_m: f64,
}

impl Footprint {
    /// The unit vector of the length axis.
    pub fn axis(&self) -> nalgebra::Vector2<f64> {
        nalgebra::Vector2::new(self.yaw_rad.cos(), self.yaw_rad.sin())
    }

    /// Corners, counter-clockwise.
    pub fn corners(&self) -> [Point2<f64>; 4] {
        let u = self.axis() * self.half_length_m;
        let v = nalgebra::Vector2::new(-self.yaw_rad.sin(), self.yaw_rad.cos()) * self.half_width_m;
        let c = self.center;
        [c - u - v, c + u - v, c + u + v, c - u + v]
    }

    /// Distance from `p` to the rectangle (0 inside).
    pub fn distance(&self, p: &Point2<f64>) -> f64 {
        let d = p - self.center;
        let (s, c) = self.yaw_rad.sin_cos();
        let along = (d.x * c + d.y * s).abs() - self.half_length_m;
        let across = (-d.x * s + d.y * c).abs() - self.half_width_m;
        along.max(0.0).hypot(across.max(0.0))
    }
}

/// What a raised slab is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum SlabKind {
    /// Sidewalk (top) with curbs (sides).
    Sidewalk,
    /// Lawn or open ground.
    Terrain,
}

/// A raised slab (sidewalk with curbs, lawn).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Slab {
    /// Where it is.
    pub footprint: Footprint,
    /// Bottom height, metres.
    pub base_z: f64,
    /// Height of the top above the base (the curb height), metres.
    pub height_m: f64,
    /// What it is.
    pub kind: SlabKind,
}

/// A building: a box with an optional recessed ground floor (shop fronts, arcades) and an
/// optional set-back top floor. The front is the `−width` side of the footprint.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Building {
    /// Footprint of the upper floors.
    pub footprint: Footprint,
    /// Ground height, metres.
    pub base_z: f64,
    /// Height of the main volume, metres.
    pub height_m: f64,
    /// Recess of the ground floor behind the front, metres (0: none).
    pub ground_floor_recess_m: f64,
    /// Height of the ground floor, metres.
    pub ground_floor_height_m: f64,
    /// Height of a set-back top floor above the main volume, metres (0: none).
    pub top_floor_height_m: f64,
    /// Index of the facade material (reflectivity class).
    pub material: u32,
}

/// A pole-like object and what it carries.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PoleObject {
    /// The ground-truth pole.
    pub pole: Pole,
    /// Direction the arm (street lights) or sign plate faces, radians.
    pub yaw_rad: f64,
    /// Arm length (street lights) or sign-plate width (sign posts), metres.
    pub attachment_m: f64,
    /// The canopy of a tree.
    pub canopy: Option<Canopy>,
}

/// A parked car: body, cabin and wheels.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Car {
    /// Footprint (length along the yaw).
    pub footprint: Footprint,
    /// Ground height, metres.
    pub base_z: f64,
    /// Roof height, metres.
    pub height_m: f64,
    /// Paint reflectivity.
    pub reflectivity: f32,
}

/// A fence panel between two points.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Fence {
    /// Start, metres.
    pub from: Point2<f64>,
    /// End, metres.
    pub to: Point2<f64>,
    /// Ground height, metres.
    pub base_z: f64,
    /// Height, metres.
    pub height_m: f64,
}

/// A construction barrel (a short, wide cylinder).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Barrel {
    /// Centre, metres.
    pub center: Point2<f64>,
    /// Ground height, metres.
    pub base_z: f64,
    /// Radius, metres.
    pub radius_m: f64,
    /// Height, metres.
    pub height_m: f64,
}

/// The ground under everything.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub enum Ground {
    /// A flat road surface at height `z` over a rectangle.
    Flat {
        /// Lower corner, metres.
        min: Point2<f64>,
        /// Upper corner, metres.
        max: Point2<f64>,
        /// Height, metres.
        z: f64,
    },
    /// A height field on a regular grid; cells with `false` in `cells` are left out.
    HeightField {
        /// Lower corner, metres.
        origin: Point2<f64>,
        /// Cell edge, metres.
        cell_m: f64,
        /// Vertices along x.
        nx: usize,
        /// Vertices along y.
        ny: usize,
        /// Vertex heights, row by row (`iy * nx + ix`), metres.
        heights: Vec<f64>,
        /// Cells present (`(ny − 1) × (nx − 1)`, row by row).
        cells: Vec<bool>,
    },
}

/// Everything in one session of a world.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct World {
    /// The ground.
    pub ground: Ground,
    /// Sidewalks and lawns.
    pub slabs: Vec<Slab>,
    /// Buildings.
    pub buildings: Vec<Building>,
    /// Poles, trees and their attachments.
    pub poles: Vec<PoleObject>,
    /// Parked cars.
    pub cars: Vec<Car>,
    /// Fences.
    pub fences: Vec<Fence>,
    /// Construction barrels.
    pub barrels: Vec<Barrel>,
    /// Leaf factor of the canopies: 1 in full leaf, about 0.6 in winter (scales the crowns).
    pub foliage: f64,
    /// Seed of the small random details of the meshes (canopy shapes).
    pub mesh_seed: u64,
}

impl World {
    /// The ground-truth poles.
    pub fn pole_list(&self) -> Vec<Pole> {
        self.poles.iter().map(|p| p.pole).collect()
    }

    /// Number of poles of each kind, in [`PoleKind::ALL`] order.
    pub fn pole_counts(&self) -> [usize; 4] {
        let mut counts = [0; 4];
        for p in &self.poles {
            if let Some(i) = PoleKind::ALL.iter().position(|k| *k == p.pole.kind) {
                counts[i] += 1;
            }
        }
        counts
    }
}
