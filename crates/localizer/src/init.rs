//! Initial particle distributions.
//!
//! * [`GaussianInit`]: a Gaussian around a pose. Defaults from Schaefer (2020), ch. 7 (Sec. 7.6.1,
//!   6-DOF MCL): σ = 1 m in the horizontal plane, 0.2 m vertically, 0.1 rad about every rotation
//!   axis. The thesis calls these values "variance"; we read them as standard deviations (their
//!   units, m and rad, are those of a standard deviation) and expose them as parameters.
//! * [`UniformDisc`]: uniform in a disc around a pose with a heading interval, for global or coarse
//!   initialization (Schaefer 2020, ch. 12: radius 2.5 m, ±5°). By default uniform in **area**
//!   (r = R√u); [`RadialSampling::UniformRadius`] reproduces the polex reference implementation,
//!   uniform in the radius (denser near the centre; the thesis says "uniformly in a circle").
//! * [`UniformBox`]: uniform over an axis-aligned box of positions and a heading interval
//!   (global localization in a known map, SE(2)).
//!
//! Translation offsets are in the world frame; rotation offsets are applied in the pose's
//! own (body) frame for SE(3) Gaussians, and about the world z axis for heading offsets.

use std::f64::consts::PI;

use nalgebra::{UnitQuaternion, Vector3};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use raypath_geometry::{Pose2, Pose3, wrap_angle};
use serde::{Deserialize, Serialize};

use crate::error::{LocalizerError, require_non_negative};

/// A distribution initial particles are drawn from.
pub trait Initializer<S>: Sync {
    /// Checks the parameters (called once before sampling).
    fn validate(&self) -> Result<(), LocalizerError> {
        Ok(())
    }

    /// Draws one state.
    fn sample(&self, rng: &mut impl Rng) -> S;
}

fn normal(rng: &mut impl Rng) -> f64 {
    StandardNormal.sample(rng)
}

/// A Gaussian around a pose (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GaussianInit<S> {
    /// The mean pose.
    pub mean: S,
    /// Standard deviation of x and y (world frame) in metres. Default 1 m (thesis ch. 7).
    pub sigma_xy_m: f64,
    /// Standard deviation of z in metres (SE(3) only). Default 0.2 m (thesis ch. 7).
    pub sigma_z_m: f64,
    /// Standard deviation of each rotation component in radians (heading for SE(2); roll,
    /// pitch and yaw as a body-frame rotation vector for SE(3)). Default 0.1 rad (thesis ch. 7).
    pub sigma_rotation_rad: f64,
}

impl<S> GaussianInit<S> {
    /// The Gaussian around `mean` with the thesis's ch. 7 spreads (1 m, 0.2 m, 0.1 rad).
    pub fn new(mean: S) -> Self {
        Self {
            mean,
            sigma_xy_m: 1.0,
            sigma_z_m: 0.2,
            sigma_rotation_rad: 0.1,
        }
    }

    fn check(&self) -> Result<(), LocalizerError> {
        require_non_negative("sigma_xy_m", self.sigma_xy_m)?;
        require_non_negative("sigma_z_m", self.sigma_z_m)?;
        require_non_negative("sigma_rotation_rad", self.sigma_rotation_rad)
    }
}

impl Initializer<Pose2> for GaussianInit<Pose2> {
    fn validate(&self) -> Result<(), LocalizerError> {
        self.check()?;
        finite_pose(self.mean.is_finite())
    }

    fn sample(&self, rng: &mut impl Rng) -> Pose2 {
        let dx = self.sigma_xy_m * normal(rng);
        let dy = self.sigma_xy_m * normal(rng);
        let dtheta = self.sigma_rotation_rad * normal(rng);
        Pose2::new(
            self.mean.x() + dx,
            self.mean.y() + dy,
            wrap_angle(self.mean.theta() + dtheta),
        )
    }
}

impl Initializer<Pose3> for GaussianInit<Pose3> {
    fn validate(&self) -> Result<(), LocalizerError> {
        self.check()?;
        finite_pose(self.mean.is_finite())
    }

    fn sample(&self, rng: &mut impl Rng) -> Pose3 {
        let offset = Vector3::new(
            self.sigma_xy_m * normal(rng),
            self.sigma_xy_m * normal(rng),
            self.sigma_z_m * normal(rng),
        );
        let rotation_vector = Vector3::new(
            self.sigma_rotation_rad * normal(rng),
            self.sigma_rotation_rad * normal(rng),
            self.sigma_rotation_rad * normal(rng),
        );
        Pose3::from_parts(
            self.mean.translation() + offset,
            self.mean.rotation() * UnitQuaternion::from_scaled_axis(rotation_vector),
        )
    }
}

fn finite_pose(finite: bool) -> Result<(), LocalizerError> {
    if finite {
        Ok(())
    } else {
        Err(LocalizerError::NonFinite {
            what: "initial pose",
            index: 0,
        })
    }
}

/// How the radius of a disc sample is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum RadialSampling {
    /// Uniform in area: r = R·√u (the default).
    #[default]
    UniformArea,
    /// Uniform in the radius: r = R·u (polex reference implementation; denser at the centre).
    UniformRadius,
}

/// Uniform in a disc around a pose with a uniform heading offset (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct UniformDisc<S> {
    /// The centre pose.
    pub center: S,
    /// Disc radius in metres.
    pub radius_m: f64,
    /// Heading offsets are uniform in `[−h, h]` radians (π: any heading).
    pub heading_half_width_rad: f64,
    /// Radius distribution.
    pub radial: RadialSampling,
}

impl<S> UniformDisc<S> {
    /// The disc of `radius_m` around `center`, headings within ±`heading_half_width_rad`,
    /// uniform in area.
    pub fn new(center: S, radius_m: f64, heading_half_width_rad: f64) -> Self {
        Self {
            center,
            radius_m,
            heading_half_width_rad,
            radial: RadialSampling::UniformArea,
        }
    }

    fn check(&self) -> Result<(), LocalizerError> {
        require_non_negative("radius_m", self.radius_m)?;
        require_non_negative("heading_half_width_rad", self.heading_half_width_rad)
    }

    /// A planar offset (dx, dy) in metres and a heading offset in radians.
    fn draw(&self, rng: &mut impl Rng) -> (f64, f64, f64) {
        let u: f64 = rng.random();
        let r = match self.radial {
            RadialSampling::UniformArea => self.radius_m * u.sqrt(),
            RadialSampling::UniformRadius => self.radius_m * u,
        };
        let bearing = rng.random_range(-PI..PI);
        let dtheta = if self.heading_half_width_rad > 0.0 {
            rng.random_range(-self.heading_half_width_rad..=self.heading_half_width_rad)
        } else {
            0.0
        };
        (r * bearing.cos(), r * bearing.sin(), dtheta)
    }
}

impl Initializer<Pose2> for UniformDisc<Pose2> {
    fn validate(&self) -> Result<(), LocalizerError> {
        self.check()?;
        finite_pose(self.center.is_finite())
    }

    fn sample(&self, rng: &mut impl Rng) -> Pose2 {
        let (dx, dy, dtheta) = self.draw(rng);
        Pose2::new(
            self.center.x() + dx,
            self.center.y() + dy,
            wrap_angle(self.center.theta() + dtheta),
        )
    }
}

impl Initializer<Pose3> for UniformDisc<Pose3> {
    fn validate(&self) -> Result<(), LocalizerError> {
        self.check()?;
        finite_pose(self.center.is_finite())
    }

    fn sample(&self, rng: &mut impl Rng) -> Pose3 {
        let (dx, dy, dtheta) = self.draw(rng);
        Pose3::from_parts(
            self.center.translation() + Vector3::new(dx, dy, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), dtheta) * self.center.rotation(),
        )
    }
}

/// Uniform over an axis-aligned box of planar positions and a heading interval (SE(2)).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct UniformBox {
    /// `[min, max]` of x in metres.
    pub x_range_m: [f64; 2],
    /// `[min, max]` of y in metres.
    pub y_range_m: [f64; 2],
    /// `[min, max]` of the heading in radians. Default `[−π, π]`.
    pub heading_range_rad: [f64; 2],
}

impl UniformBox {
    /// The box `[x0, x1] × [y0, y1]` with any heading.
    pub fn new(x_range_m: [f64; 2], y_range_m: [f64; 2]) -> Self {
        Self {
            x_range_m,
            y_range_m,
            heading_range_rad: [-PI, PI],
        }
    }
}

fn uniform_in(rng: &mut impl Rng, [lo, hi]: [f64; 2]) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

impl Initializer<Pose2> for UniformBox {
    fn validate(&self) -> Result<(), LocalizerError> {
        for (name, [lo, hi]) in [
            ("x_range_m", self.x_range_m),
            ("y_range_m", self.y_range_m),
            ("heading_range_rad", self.heading_range_rad),
        ] {
            if !(lo.is_finite() && hi.is_finite()) {
                return Err(LocalizerError::InvalidParameter {
                    name,
                    reason: format!("bounds must be finite, got [{lo}, {hi}]"),
                });
            }
            if lo > hi {
                return Err(LocalizerError::InvalidParameter {
                    name,
                    reason: format!("need min <= max, got [{lo}, {hi}]"),
                });
            }
        }
        Ok(())
    }

    fn sample(&self, rng: &mut impl Rng) -> Pose2 {
        Pose2::new(
            uniform_in(rng, self.x_range_m),
            uniform_in(rng, self.y_range_m),
            wrap_angle(uniform_in(rng, self.heading_range_rad)),
        )
    }
}
