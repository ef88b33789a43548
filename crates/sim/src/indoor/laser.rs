//! The simulated 2-D laser: a fan of beams cast exactly against the world, Gaussian range
//! noise, no-returns beyond the maximum range and through glass, optional intensities.
//!
//! Each beam is cast from the laser pose. A beam that meets glass passes through with the
//! surface's transmission probability (and goes on to whatever lies behind) or reflects. The
//! measured range is the true range plus N(0, σ²); a beam that meets nothing, or whose
//! measured range is at or beyond the maximum range, is a no-return and is written as the
//! no-return code (81.91 m by default, the SICK LMS code of the Radish logs). The scan is
//! instantaneous at the laser pose (no motion distortion).

use std::f64::consts::PI;

use nalgebra::{Point2, Unit, Vector2};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use raypath_geometry::Pose2;
use serde::Serialize;

use super::floorplan::World;
use super::intensity::IntensityModel;
use crate::error::{Result, SimError};

/// A 2-D laser scanner.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Laser2Config {
    /// Number of beams.
    pub beams: usize,
    /// Angle of beam 0 in the laser frame, radians (counter-clockwise from forward).
    pub angle_min_rad: f64,
    /// Angle between beams, radians.
    pub angle_increment_rad: f64,
    /// Maximum range in metres: measured ranges at or beyond it are no-returns.
    pub max_range_m: f64,
    /// The reading written for a no-return, metres (above the maximum range).
    pub no_return_code_m: f64,
    /// Standard deviation of the range noise in metres.
    pub range_sigma_m: f64,
    /// Scan rate in Hz.
    pub rate_hz: f64,
    /// The laser's pose on the robot `[x, y, θ]` (metres, radians).
    pub mount: [f64; 3],
    /// Intensities (remissions) when `Some`.
    pub intensity: Option<IntensityModel>,
    /// CARMEN laser type code written in `ROBOTLASER1` lines (0 = SICK LMS).
    pub laser_type: i64,
}

impl Laser2Config {
    /// A SICK-LMS-like laser: 181 beams over 180° at 1° (a closed fan, −90° … +90°), 30 m,
    /// σ = 1 cm, 5 Hz, no-return code 81.91 m.
    pub fn sick_180() -> Self {
        Self {
            beams: 181,
            angle_min_rad: -PI / 2.0,
            angle_increment_rad: PI / 180.0,
            max_range_m: 30.0,
            no_return_code_m: 81.91,
            range_sigma_m: 0.01,
            rate_hz: 5.0,
            mount: [0.0; 3],
            intensity: None,
            laser_type: 0,
        }
    }

    /// A full-circle laser: 720 beams at 0.5° over [−180°, 180°), 30 m, σ = 1 cm, 5 Hz.
    pub fn full_360() -> Self {
        Self {
            beams: 720,
            angle_min_rad: -PI,
            angle_increment_rad: PI / 360.0,
            ..Self::sick_180()
        }
    }

    /// The same laser with the default intensity model.
    pub fn with_intensities(mut self) -> Self {
        self.intensity = Some(IntensityModel::default());
        self
    }

    /// The laser's pose on the robot.
    pub fn robot_from_laser(&self) -> Pose2 {
        Pose2::new(self.mount[0], self.mount[1], self.mount[2])
    }

    /// The field of view `(n − 1)·increment` in radians (CARMEN's convention).
    pub fn fov_rad(&self) -> f64 {
        self.beams.saturating_sub(1) as f64 * self.angle_increment_rad
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        let bad =
            |name: &'static str, reason: String| Err(SimError::InvalidParameter { name, reason });
        if self.beams == 0 {
            return bad("beams", "at least one beam".into());
        }
        if !(self.angle_min_rad.is_finite()
            && self.angle_increment_rad.is_finite()
            && self.angle_increment_rad > 0.0)
        {
            return bad(
                "angle_increment_rad",
                "angles must be finite, increment > 0".into(),
            );
        }
        if !(self.max_range_m.is_finite() && self.max_range_m > 0.0) {
            return bad(
                "max_range_m",
                format!("must be positive, got {}", self.max_range_m),
            );
        }
        if !(self.no_return_code_m.is_finite() && self.no_return_code_m > self.max_range_m + 0.2) {
            return bad(
                "no_return_code_m",
                format!(
                    "must lie above the maximum range by more than 20 cm, got {} for {}",
                    self.no_return_code_m, self.max_range_m
                ),
            );
        }
        if !(self.range_sigma_m.is_finite() && self.range_sigma_m >= 0.0) {
            return bad(
                "range_sigma_m",
                format!("must be ≥ 0, got {}", self.range_sigma_m),
            );
        }
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0) {
            return bad("rate_hz", format!("must be positive, got {}", self.rate_hz));
        }
        if self.mount.iter().any(|v| !v.is_finite()) {
            return bad("mount", "must be finite".into());
        }
        Ok(())
    }
}

/// Why a beam has no return.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum NoReturn {
    /// Nothing within the maximum range (or the noisy range reached it).
    BeyondRange,
    /// The beam went through glass and met nothing behind it.
    ThroughGlass,
}

/// One simulated scan.
#[derive(Clone, Debug, PartialEq)]
pub struct SimulatedScan {
    /// Measured ranges in metres (the no-return code for no-returns).
    pub ranges: Vec<f64>,
    /// Intensities (0 for no-returns) when the laser has an intensity model.
    pub intensities: Option<Vec<f64>>,
    /// True range of each return (`NaN` for no-returns), metres.
    pub true_ranges: Vec<f64>,
    /// Label of the surface hit (0 for no-returns).
    pub labels: Vec<u32>,
    /// Why each no-return has none (`None` for returns).
    pub no_returns: Vec<Option<NoReturn>>,
}

/// Scans `world` from `world_from_laser`.
pub fn scan<R: Rng + ?Sized>(
    world: &World,
    world_from_laser: &Pose2,
    laser: &Laser2Config,
    rng: &mut R,
) -> SimulatedScan {
    let n = laser.beams;
    let mut out = SimulatedScan {
        ranges: Vec::with_capacity(n),
        intensities: laser.intensity.map(|_| Vec::with_capacity(n)),
        true_ranges: Vec::with_capacity(n),
        labels: Vec::with_capacity(n),
        no_returns: Vec::with_capacity(n),
    };
    let origin = Point2::new(world_from_laser.x(), world_from_laser.y());
    for i in 0..n {
        let angle =
            world_from_laser.theta() + laser.angle_min_rad + i as f64 * laser.angle_increment_rad;
        let dir = Unit::new_unchecked(Vector2::new(angle.cos(), angle.sin()));
        let mut travelled = 0.0;
        let mut through_glass = false;
        let mut result = None;
        // A few panes at most: stop after 8 transmissions.
        for _ in 0..8 {
            let from = origin + dir.into_inner() * travelled;
            let remaining = laser.max_range_m + 1.0 - travelled;
            let Some(hit) = world.scene.cast(&from, &dir, remaining) else {
                break;
            };
            let material = world.materials.get(hit.surface as usize);
            let transmission = material.map_or(0.0, |m| m.transmission);
            if transmission > 0.0 && rng.random::<f64>() < transmission {
                travelled += hit.range_m + 1e-6;
                through_glass = true;
                continue;
            }
            result = Some((travelled + hit.range_m, hit, material));
            break;
        }
        let noise: f64 = StandardNormal.sample(rng);
        let measured = result.map(|(r, _, _)| r + laser.range_sigma_m * noise);
        match (result, measured) {
            (Some((r, hit, material)), Some(m)) if m < laser.max_range_m && m > 0.0 => {
                out.ranges.push(m);
                out.true_ranges.push(r);
                out.labels.push(material.map_or(0, |m| m.label));
                out.no_returns.push(None);
                if let (Some(model), Some(values)) = (laser.intensity, out.intensities.as_mut()) {
                    let cos = -hit.normal.dot(&dir);
                    let incidence = cos.clamp(-1.0, 1.0).acos();
                    let rho = material.map_or(0.0, |m| m.reflectivity);
                    values.push(model.sample(rho, r, incidence, rng));
                }
            }
            _ => {
                out.ranges.push(laser.no_return_code_m);
                out.true_ranges.push(f64::NAN);
                out.labels.push(0);
                out.no_returns
                    .push(Some(if through_glass && result.is_none() {
                        NoReturn::ThroughGlass
                    } else {
                        NoReturn::BeyondRange
                    }));
                if let Some(values) = out.intensities.as_mut() {
                    values.push(0.0);
                }
            }
        }
    }
    out
}
