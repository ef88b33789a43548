//! Rays in the map frame of a patch: what the sensor saw along a segment of known length.
//!
//! The decay-rate likelihood of a ray depends only on the part of the ray inside the map
//! (space outside is not modelled), so rays of a log are **clipped** to the patch: the ray
//! enters the patch at `t₀` and is followed from there, which conditions on the ray having
//! reached `t₀` (the factor `𝒩(t₀)` outside the patch is the same for every map).
//!
//! | reading (Eq. 7.14) | in the patch | map ray |
//! |---|---|---|
//! | return at `r ∈ [r_min, r_max)`, `t₀ ≤ r ≤ t₁` | reflected inside | [`Outcome::Hit`], length `r − t₀` |
//! | return beyond `t₁`, or no return | crossed without reflection | [`Outcome::Super`], length `min(t₁, r_max) − t₀` |
//! | return before `t₀` | never reached the patch | dropped |
//! | return below `r_min` (`sub`) | kept only if the segment `[0, r_min]` lies inside | [`Outcome::Sub`], length `r_min` |
//!
//! `Super` is the thesis's `super` (no return up to `r_max`, Eq. 9.12) with `r_max` replaced
//! by the length inside the patch; `Sub` is `sub` (Eq. 9.11). Frames: the map frame has
//! its origin at the patch's lower-left corner, axes parallel to the world's (REP-103),
//! metres.

use nalgebra::{Point2, Vector2};
use raypath_geometry::{Range, Ray2};
use serde::{Deserialize, Serialize};

use crate::moments::Segment;

/// What happened along a [`MapRay`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Outcome {
    /// Reflected at `length_m` (density `p(r) = λ(r) 𝒩(r)`, Eq. 9.5).
    Hit,
    /// Reflected somewhere before `length_m` (= `r_min`; `P(sub) = 1 − 𝒩(r_min)`, Eq. 9.11).
    Sub,
    /// Not reflected up to `length_m` (`P(super) = 𝒩(length)`, Eq. 9.12).
    Super,
}

/// A ray in the map frame: origin (m, relative to the map's lower-left corner), unit
/// direction, the length that matters and the [`Outcome`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MapRay {
    /// Start of the ray in the map frame (m).
    pub origin: [f64; 2],
    /// Unit direction.
    pub direction: [f64; 2],
    /// Hit distance, `r_min` (sub) or the length without reflection (super), in metres.
    pub length_m: f64,
    /// What happened.
    pub outcome: Outcome,
}

impl MapRay {
    /// A map ray from an origin, an angle (rad, counter-clockwise from x) and a length.
    pub fn from_angle(origin: [f64; 2], angle_rad: f64, length_m: f64, outcome: Outcome) -> Self {
        Self {
            origin,
            direction: [angle_rad.cos(), angle_rad.sin()],
            length_m,
            outcome,
        }
    }

    /// The point at `t_m` metres along the ray.
    #[inline]
    pub fn at(&self, t_m: f64) -> [f64; 2] {
        [
            self.origin[0] + self.direction[0] * t_m,
            self.origin[1] + self.direction[1] * t_m,
        ]
    }

    /// The end of the relevant segment (the hit point for a [`Outcome::Hit`]).
    #[inline]
    pub fn end(&self) -> [f64; 2] {
        self.at(self.length_m)
    }

    /// The segment `[0, length_m]`.
    #[inline]
    pub fn segment(&self) -> Segment {
        Segment {
            origin: self.origin,
            direction: self.direction,
            length_m: self.length_m,
        }
    }

    /// Whether origin, direction and length are finite, the direction unit and the length
    /// positive.
    pub fn is_valid(&self) -> bool {
        let n = self.direction[0].hypot(self.direction[1]);
        self.origin
            .iter()
            .chain(&self.direction)
            .all(|v| v.is_finite())
            && (n - 1.0).abs() < 1e-9
            && self.length_m.is_finite()
            && self.length_m > 0.0
    }
}

/// A rectangular map region in the world frame: lower-left corner and extent.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Patch {
    /// Lower-left corner in the world frame (m).
    pub min: [f64; 2],
    /// Extent `[X, Y]` in metres.
    pub extent_m: [f64; 2],
}

/// Sensor range limits used when clipping rays (Eq. 7.14). Default `r_min = 0` (no `sub`
/// readings; the CARMEN logs have none) and `r_max = +∞` (no-returns are followed through
/// the patch, since their code is already mapped to [`Range::NoReturn`] by the reader).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RangeLimits {
    /// `r_min` (m).
    pub min_range_m: f64,
    /// `r_max` (m).
    pub max_range_m: f64,
}

impl Default for RangeLimits {
    fn default() -> Self {
        Self {
            min_range_m: 0.0,
            max_range_m: f64::INFINITY,
        }
    }
}

impl Patch {
    /// A `size_m × size_m` patch with its lower-left corner at `min`.
    pub fn square(min: [f64; 2], size_m: f64) -> Self {
        Self {
            min,
            extent_m: [size_m, size_m],
        }
    }

    /// The parameter interval `[t₀, t₁] ⊂ [0, t_max]` of `origin + t · dir` inside the patch.
    pub fn clip(&self, origin: [f64; 2], dir: [f64; 2], t_max: f64) -> Option<(f64, f64)> {
        let (mut t0, mut t1) = (0.0f64, t_max);
        for k in 0..2 {
            let lo = self.min[k];
            let hi = self.min[k] + self.extent_m[k];
            if dir[k] == 0.0 {
                if origin[k] < lo || origin[k] > hi {
                    return None;
                }
            } else {
                let a = (lo - origin[k]) / dir[k];
                let b = (hi - origin[k]) / dir[k];
                t0 = t0.max(a.min(b));
                t1 = t1.min(a.max(b));
            }
        }
        (t0 < t1 && t0.is_finite()).then_some((t0, t1))
    }

    /// Whether a world point lies inside the patch (closed box).
    pub fn contains(&self, p: [f64; 2]) -> bool {
        (0..2).all(|k| p[k] >= self.min[k] && p[k] <= self.min[k] + self.extent_m[k])
    }

    /// Clips a world-frame sensor ray to the patch (table in the module docs); `None` when the
    /// ray does not reach the patch or its segment inside is shorter than 1 µm.
    pub fn clip_ray(&self, ray: &Ray2, limits: &RangeLimits) -> Option<MapRay> {
        let o = [ray.origin.x, ray.origin.y];
        let d = [ray.direction.x, ray.direction.y];
        if !o.iter().chain(&d).all(|v| v.is_finite()) {
            return None;
        }
        let to_map = |t0: f64| {
            [
                o[0] + d[0] * t0 - self.min[0],
                o[1] + d[1] * t0 - self.min[1],
            ]
        };
        match ray.range {
            Range::Hit(r) if r.is_finite() && r < limits.min_range_m => {
                // `sub`: keep only when [0, r_min] lies inside the patch.
                let (t0, t1) = self.clip(o, d, limits.min_range_m)?;
                (t0 == 0.0 && t1 >= limits.min_range_m).then(|| MapRay {
                    origin: to_map(0.0),
                    direction: d,
                    length_m: limits.min_range_m,
                    outcome: Outcome::Sub,
                })
            }
            Range::Hit(r) if r.is_finite() && r >= 0.0 && r < limits.max_range_m => {
                let (t0, t1) = self.clip(o, d, f64::INFINITY)?;
                if r < t0 {
                    return None;
                }
                let (length_m, outcome) = if r <= t1 {
                    (r - t0, Outcome::Hit)
                } else {
                    (t1 - t0, Outcome::Super)
                };
                (length_m > 1e-6).then(|| MapRay {
                    origin: to_map(t0),
                    direction: d,
                    length_m,
                    outcome,
                })
            }
            Range::Hit(r) if r.is_nan() || r < 0.0 => None,
            _ => {
                let (t0, t1) = self.clip(o, d, limits.max_range_m)?;
                (t1 - t0 > 1e-6).then(|| MapRay {
                    origin: to_map(t0),
                    direction: d,
                    length_m: t1 - t0,
                    outcome: Outcome::Super,
                })
            }
        }
    }

    /// A world-frame point in the map frame.
    pub fn to_map(&self, p: Point2<f64>) -> [f64; 2] {
        [p.x - self.min[0], p.y - self.min[1]]
    }

    /// A map-frame ray as a world-frame [`Ray2`] whose range is its length (for traversal).
    pub fn to_world(&self, ray: &MapRay) -> Option<Ray2> {
        Ray2::new(
            Point2::new(ray.origin[0] + self.min[0], ray.origin[1] + self.min[1]),
            Vector2::new(ray.direction[0], ray.direction[1]),
            Range::Hit(ray.length_m),
        )
    }
}
