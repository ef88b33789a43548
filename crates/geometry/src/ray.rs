//! Rays: an origin, a unit direction and what the sensor saw along it.

use nalgebra::{Point2, Point3, Unit, Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// What a beam returned.
///
/// Lidars report either a range to the surface that reflected the beam, or nothing (the beam
/// left the sensor's range, hit a non-reflective or glass surface, or the return was too weak).
/// No-returns carry information too — the beam travelled at least up to the maximum range
/// through free space — so they are kept rather than dropped.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Range {
    /// A reflection at this distance from the origin, in metres.
    Hit(f64),
    /// No reflection within the sensor's maximum range.
    NoReturn,
}

impl Range {
    /// The range in metres for a hit, `None` for a no-return.
    pub fn hit(&self) -> Option<f64> {
        match *self {
            Range::Hit(r) => Some(r),
            Range::NoReturn => None,
        }
    }

    /// The length along the ray that a traversal covers: the hit distance, or `max_range_m`
    /// for a no-return (a no-return is cut at the sensor's maximum range). Hits beyond the
    /// maximum range are cut too.
    pub fn traced_length(&self, max_range_m: f64) -> f64 {
        match *self {
            Range::Hit(r) => r.min(max_range_m),
            Range::NoReturn => max_range_m,
        }
    }
}

/// A ray in the plane.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ray2 {
    /// Where the beam starts (the sensor position), in the frame the ray is expressed in.
    pub origin: Point2<f64>,
    /// Unit direction of the beam.
    pub direction: Unit<Vector2<f64>>,
    /// What the beam returned.
    pub range: Range,
}

impl Ray2 {
    /// A ray from `origin` along `direction` (normalized here; a zero vector gives `None`).
    pub fn new(origin: Point2<f64>, direction: Vector2<f64>, range: Range) -> Option<Self> {
        let direction = Unit::try_new(direction, 0.0)?;
        Some(Self {
            origin,
            direction,
            range,
        })
    }

    /// A ray from `origin` at angle `angle_rad` (counter-clockwise from x).
    pub fn from_angle(origin: Point2<f64>, angle_rad: f64, range: Range) -> Self {
        Self {
            origin,
            direction: Unit::new_unchecked(Vector2::new(angle_rad.cos(), angle_rad.sin())),
            range,
        }
    }

    /// The point at distance `t_m` along the ray.
    pub fn at(&self, t_m: f64) -> Point2<f64> {
        self.origin + self.direction.into_inner() * t_m
    }

    /// The reflection point, `None` for a no-return.
    pub fn endpoint(&self) -> Option<Point2<f64>> {
        self.range.hit().map(|r| self.at(r))
    }
}

/// A ray in space.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ray3 {
    /// Where the beam starts (the sensor position), in the frame the ray is expressed in.
    pub origin: Point3<f64>,
    /// Unit direction of the beam.
    pub direction: Unit<Vector3<f64>>,
    /// What the beam returned.
    pub range: Range,
}

impl Ray3 {
    /// A ray from `origin` along `direction` (normalized here; a zero vector gives `None`).
    pub fn new(origin: Point3<f64>, direction: Vector3<f64>, range: Range) -> Option<Self> {
        let direction = Unit::try_new(direction, 0.0)?;
        Some(Self {
            origin,
            direction,
            range,
        })
    }

    /// The ray from `origin` to the reflection point `endpoint`. `None` when the two coincide
    /// (the direction is undefined).
    pub fn between(origin: Point3<f64>, endpoint: Point3<f64>) -> Option<Self> {
        let delta = endpoint - origin;
        let length = delta.norm();
        Self::new(origin, delta, Range::Hit(length))
    }

    /// The point at distance `t_m` along the ray.
    pub fn at(&self, t_m: f64) -> Point3<f64> {
        self.origin + self.direction.into_inner() * t_m
    }

    /// The reflection point, `None` for a no-return.
    pub fn endpoint(&self) -> Option<Point3<f64>> {
        self.range.hit().map(|r| self.at(r))
    }
}
