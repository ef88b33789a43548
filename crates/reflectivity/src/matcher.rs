//! Gauss–Newton scan matching on the multi-resolution map (Kohlbrecher et al. 2011;
//! Khan 2017 §3.4.2, eqs. (3.6)–(3.9), with `H` summed over the beams: the thesis writes `H`
//! for one beam and the sum outside `H⁻¹`).
//!
//! For the pose `ζ = (t_x, t_y, θ)` and end points `s_i` (sensor frame):
//!
//! * occupancy residual (plain Hector): `r_i = 1 − M(S_i(ζ))`, `J_i = ∇M · ∂S_i/∂ζ`;
//! * reflectivity residual (the thesis): `r_i = ϱ̄_i − R(S_i(ζ))`, `J_i = ∇R · ∂S_i/∂ζ`;
//! * combined (the thesis' future work): both, the reflectivity terms weighted by
//!   [`MatcherConfig::reflectivity_weight`];
//! * an optional odometry prior `‖ζ − ζ_odo‖²_Λ`.
//!
//! `H = Σ J_iᵀ J_i (+ Λ)`, `Δζ = H⁻¹ Σ J_iᵀ r_i (+ Λ (ζ_odo − ζ))`, coarse level to fine. The
//! rotation step is clamped to ±0.2 rad per iteration (as Hector does). The covariance is
//! `K = σ² H⁻¹` at the result on the finest level.

use nalgebra::{Matrix3, Vector3};
use raypath_geometry::Pose2;
use raypath_geometry::wrap_angle;
use serde::{Deserialize, Serialize};

use crate::error::{ReflectivityError, Result, require_positive};
use crate::grid::GridLevel;
use crate::map::{MapConfig, MultiResMap};
use crate::points::ScanPoints;

/// Which residual the matcher minimises.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ResidualMode {
    /// Occupancy only: plain Hector SLAM.
    Occupancy,
    /// Relative reflectivity only: Khan's intensity-based Hector (eq. 3.6).
    Reflectivity,
    /// Both residuals.
    Combined,
}

impl ResidualMode {
    /// Parses `occupancy`, `reflectivity` or `combined`.
    pub fn parse(name: &str) -> Option<Self> {
        match name {
            "occupancy" => Some(Self::Occupancy),
            "reflectivity" => Some(Self::Reflectivity),
            "combined" => Some(Self::Combined),
            _ => None,
        }
    }

    /// The name [`Self::parse`] accepts.
    pub fn name(self) -> &'static str {
        match self {
            Self::Occupancy => "occupancy",
            Self::Reflectivity => "reflectivity",
            Self::Combined => "combined",
        }
    }

    fn occupancy(self) -> bool {
        matches!(self, Self::Occupancy | Self::Combined)
    }

    fn reflectivity(self) -> bool {
        matches!(self, Self::Reflectivity | Self::Combined)
    }
}

/// Matcher parameters. Defaults follow hector_mapping (the thesis gives no levels or
/// iterations): 3 Gauss–Newton iterations on the coarser levels, 5 on the finest, map updates
/// after 0.4 m or 0.9 rad of motion.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MatcherConfig {
    /// The map.
    pub map: MapConfig,
    /// The residual.
    pub mode: ResidualMode,
    /// Gauss–Newton iterations on each coarser level.
    pub iterations_coarse: usize,
    /// Gauss–Newton iterations on the finest level.
    pub iterations_finest: usize,
    /// Map update after this much translation since the last update, metres.
    pub update_distance_m: f64,
    /// Map update after this much rotation since the last update, radians.
    pub update_angle_rad: f64,
    /// Largest rotation step per iteration, radians (Hector: 0.2).
    pub max_rotation_step_rad: f64,
    /// Weight of the reflectivity residuals in [`ResidualMode::Combined`].
    pub reflectivity_weight: f64,
    /// Reflectivity assumed for unobserved cells (`None`: skip such beams; the thesis leaves it
    /// open). Default 0: empty space reflects nothing, so the map's reflectivity also has edges
    /// across surfaces.
    pub unobserved_reflectivity: Option<f64>,
    /// σ of the covariance `K = σ² H⁻¹` (sensor dependent; not given in the thesis).
    pub covariance_sigma: f64,
    /// Standard deviations `(σ_x m, σ_y m, σ_θ rad)` of the odometry increment when used as a
    /// prior; `None`: odometry only gives the initial guess.
    pub odometry_sigma: Option<[f64; 3]>,
}

impl Default for MatcherConfig {
    fn default() -> Self {
        Self {
            map: MapConfig::default(),
            mode: ResidualMode::Occupancy,
            iterations_coarse: 3,
            iterations_finest: 5,
            update_distance_m: 0.4,
            update_angle_rad: 0.9,
            max_rotation_step_rad: 0.2,
            reflectivity_weight: 1.0,
            unobserved_reflectivity: Some(0.0),
            covariance_sigma: 1.0,
            odometry_sigma: None,
        }
    }
}

impl MatcherConfig {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        self.map.validate()?;
        require_positive("update_distance_m", self.update_distance_m)?;
        require_positive("update_angle_rad", self.update_angle_rad)?;
        require_positive("max_rotation_step_rad", self.max_rotation_step_rad)?;
        require_positive("reflectivity_weight", self.reflectivity_weight)?;
        require_positive("covariance_sigma", self.covariance_sigma)?;
        if self.iterations_finest == 0 {
            return Err(ReflectivityError::InvalidParameter {
                name: "iterations_finest",
                reason: "at least one iteration".into(),
            });
        }
        if let Some(s) = self.odometry_sigma {
            for v in s {
                require_positive("odometry_sigma", v)?;
            }
        }
        Ok(())
    }
}

/// The result of matching one scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatchResult {
    /// The estimated sensor pose in the map frame.
    pub world_from_sensor: Pose2,
    /// `σ² H⁻¹` over `(x, y, θ)` (infinite diagonal when `H` is singular).
    pub covariance: Matrix3<f64>,
    /// Whether the scan was integrated into the map.
    pub map_updated: bool,
}

/// An odometry prior for one match: the predicted pose and its information matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prior {
    /// The predicted pose.
    pub pose: Pose2,
    /// Information (inverse covariance) over `(x, y, θ)`.
    pub information: Matrix3<f64>,
}

/// The Hector-style front-end: matches each scan against the map built so far and updates the
/// map after enough motion.
#[derive(Clone, Debug)]
pub struct ScanMatcher {
    config: MatcherConfig,
    map: MultiResMap,
    pose: Pose2,
    last_update: Option<Pose2>,
}

impl ScanMatcher {
    /// A matcher with an empty map, starting at the map origin.
    pub fn new(config: MatcherConfig) -> Result<Self> {
        config.validate()?;
        Ok(Self {
            map: MultiResMap::new(&config.map)?,
            config,
            pose: Pose2::identity(),
            last_update: None,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &MatcherConfig {
        &self.config
    }

    /// The map.
    pub fn map(&self) -> &MultiResMap {
        &self.map
    }

    /// The current pose estimate.
    pub fn pose(&self) -> Pose2 {
        self.pose
    }

    /// Processes one scan. `odometry_delta` is the odometry motion since the previous scan
    /// (`prev⁻¹ · current` in the robot's odometry frame); it gives the initial guess and,
    /// with [`MatcherConfig::odometry_sigma`], a prior. The first scan only builds the map.
    pub fn process(&mut self, scan: &ScanPoints, odometry_delta: Option<Pose2>) -> MatchResult {
        let guess = odometry_delta.map_or(self.pose, |d| self.pose * d);
        let prior = match (odometry_delta, self.config.odometry_sigma) {
            (Some(_), Some(s)) => Some(Prior {
                pose: guess,
                information: Matrix3::from_diagonal(&Vector3::new(
                    1.0 / (s[0] * s[0]),
                    1.0 / (s[1] * s[1]),
                    1.0 / (s[2] * s[2]),
                )),
            }),
            _ => None,
        };
        let (pose, covariance) = if self.last_update.is_none() {
            (guess, Matrix3::from_diagonal_element(f64::INFINITY))
        } else {
            self.match_scan(scan, guess, prior.as_ref())
        };
        self.pose = pose;
        let map_updated = match self.last_update {
            None => true,
            Some(last) => {
                let d = last.inverse() * pose;
                d.translation().norm() > self.config.update_distance_m
                    || d.theta().abs() > self.config.update_angle_rad
            }
        };
        if map_updated {
            self.map.update(&pose, scan);
            self.last_update = Some(pose);
        }
        MatchResult {
            world_from_sensor: pose,
            covariance,
            map_updated,
        }
    }

    /// Matches `scan` against the current map from `initial` (coarse to fine) without changing
    /// the matcher; returns the pose and `σ² H⁻¹`.
    pub fn match_scan(
        &self,
        scan: &ScanPoints,
        initial: Pose2,
        prior: Option<&Prior>,
    ) -> (Pose2, Matrix3<f64>) {
        match_levels(self.map.levels(), &self.config, scan, initial, prior)
    }
}

/// Matches `scan` (sensor frame) against the grid `levels` (finest first, as
/// [`MultiResMap::levels`]) from `initial`, coarse to fine, with the iterations, residual and
/// step limit of `config` (its map settings are not used): returns the pose in the levels'
/// frame and `σ² H⁻¹`. This is [`ScanMatcher::match_scan`] for maps the matcher does not own
/// (submaps, cropped frozen grids).
pub fn match_levels(
    levels: &[GridLevel],
    config: &MatcherConfig,
    scan: &ScanPoints,
    initial: Pose2,
    prior: Option<&Prior>,
) -> (Pose2, Matrix3<f64>) {
    let mut zeta = Vector3::new(initial.x(), initial.y(), initial.theta());
    for level in (0..levels.len()).rev() {
        let iterations = if level == 0 {
            config.iterations_finest
        } else {
            config.iterations_coarse
        };
        for _ in 0..iterations {
            let (h, g) = normal_equations(&levels[level], config, scan, &zeta, prior);
            let Some(inv) = h.try_inverse() else {
                break;
            };
            let mut step = inv * g;
            if !step.iter().all(|v| v.is_finite()) {
                break;
            }
            let m = config.max_rotation_step_rad;
            step[2] = step[2].clamp(-m, m);
            zeta += step; // Eq. (3.9): ζ ← ζ + H⁻¹ Σ Jᵀ r
            zeta[2] = wrap_angle(zeta[2]);
        }
    }
    let covariance = match levels.first() {
        Some(finest) => {
            let (h, _) = normal_equations(finest, config, scan, &zeta, prior);
            let sigma2 = config.covariance_sigma * config.covariance_sigma;
            h.try_inverse()
                .map_or(Matrix3::from_diagonal_element(f64::INFINITY), |inv| {
                    inv * sigma2
                }) // K = σ² H⁻¹
        }
        None => Matrix3::from_diagonal_element(f64::INFINITY),
    };
    (Pose2::new(zeta[0], zeta[1], zeta[2]), covariance)
}

/// `H = Σ JᵢᵀJᵢ` and `g = Σ Jᵢᵀ rᵢ` on one level at pose `zeta`.
fn normal_equations(
    grid: &GridLevel,
    config: &MatcherConfig,
    scan: &ScanPoints,
    zeta: &Vector3<f64>,
    prior: Option<&Prior>,
) -> (Matrix3<f64>, Vector3<f64>) {
    let mut h = Matrix3::zeros();
    let mut g = Vector3::zeros();
    let mode = config.mode;
    let weight = config.reflectivity_weight;
    let unobserved = config.unobserved_reflectivity;
    let (c, s) = (zeta[2].cos(), zeta[2].sin());
    let mut add = |grad: [f64; 2], ds_dtheta: [f64; 2], residual: f64, w: f64| {
        // J_i = ∇M(S_i) ∂S_i/∂ζ  (eq. 3.9)
        let j = Vector3::new(
            grad[0],
            grad[1],
            grad[0] * ds_dtheta[0] + grad[1] * ds_dtheta[1],
        );
        h += j * j.transpose() * w; // H = Σ JᵢᵀJᵢ (summed; the thesis prints one term)
        g += j * (residual * w);
    };
    for (p, &refl) in scan.points().iter().zip(scan.reflectivity()) {
        // Eq. (3.7): S_i(ζ) = R(θ) s_i + t
        let x = c * p[0] - s * p[1] + zeta[0];
        let y = s * p[0] + c * p[1] + zeta[1];
        // ∂S_i/∂θ = (−sinθ s_x − cosθ s_y, cosθ s_x − sinθ s_y)
        let ds = [-s * p[0] - c * p[1], c * p[0] - s * p[1]];
        if mode.occupancy() {
            if let Some(m) = grid.occupancy(x, y) {
                add(m.gradient, ds, 1.0 - m.value, 1.0);
            }
        }
        if mode.reflectivity() && refl.is_finite() {
            if let Some(r) = grid.reflectivity(x, y, unobserved) {
                let w = if mode.occupancy() { weight } else { 1.0 };
                add(r.gradient, ds, refl - r.value, w); // Eq. (3.6) residual ϱ̄ − R(S_i)
            }
        }
    }
    if let Some(prior) = prior {
        let d = Vector3::new(
            prior.pose.x() - zeta[0],
            prior.pose.y() - zeta[1],
            wrap_angle(prior.pose.theta() - zeta[2]),
        );
        h += prior.information;
        g += prior.information * d;
    }
    (h, g)
}
