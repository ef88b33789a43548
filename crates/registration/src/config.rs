//! Configuration of registration and odometry, with the source of every default.

use serde::{Deserialize, Serialize};

use crate::error::{RegistrationError, Result, require_positive};

/// The robust kernel ρ applied to the point-to-plane residuals `e` (iteratively reweighted
/// least squares: each correspondence weighs `w(e) = ρ'(e) / e`), with scale κ.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Kernel {
    /// Plain least squares, `w(e) = 1`.
    None,
    /// Huber: `w(e) = 1` for `|e| ≤ κ`, `κ / |e|` beyond.
    Huber,
    /// Geman–McClure, `ρ(e) = κ² e² / (2 (κ² + e²))`, `w(e) = κ⁴ / (κ² + e²)²`: residuals well
    /// beyond κ barely count (the kernel of KISS-ICP, Vizzo et al. 2023).
    GemanMcClure,
}

impl Kernel {
    /// The IRLS weight of residual `e` at scale `kappa` (both metres), in `(0, 1]`.
    pub fn weight(self, e: f64, kappa: f64) -> f64 {
        match self {
            Self::None => 1.0,
            Self::Huber => {
                let a = e.abs();
                if a <= kappa { 1.0 } else { kappa / a }
            }
            Self::GemanMcClure => {
                let k2 = kappa * kappa;
                let d = k2 + e * e;
                k2 * k2 / (d * d)
            }
        }
    }
}

/// How [`register`](crate::register) preprocesses, matches and stops.
///
/// Defaults follow KISS-ICP (Vizzo et al., "KISS-ICP: In Defense of Point-to-Point ICP",
/// RA-L 2023, and its `config.py`), which was tuned for automotive lidars at 10 Hz, except
/// where a field says "ours".
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegistrationConfig {
    /// Returns closer than this to the sensor (the cloud's origin) are dropped, metres.
    /// Default 0 (KISS-ICP `min_range`): only returns exactly at the origin go.
    pub min_range_m: f64,
    /// Returns farther than this are dropped, metres. Default 100 (KISS-ICP `max_range`).
    pub max_range_m: f64,
    /// The voxel size v, metres. Default 1.0 = `max_range_m / 100` (KISS-ICP's rule).
    pub voxel_size_m: f64,
    /// The target (and, in odometry, the map's input) is down-sampled at this multiple of v.
    /// Default 0.5 (KISS-ICP `frame_downsample`).
    pub target_voxel_scale: f64,
    /// The source is down-sampled at this multiple of v. Default 1.5 (KISS-ICP `source`).
    pub source_voxel_scale: f64,
    /// Neighbours of a target point whose covariance gives its normal (local PCA; Low 2004
    /// assumes given normals). Default 10 (ours).
    pub normal_neighbours: usize,
    /// Neighbours farther than this do not count toward a normal, metres. Default 2.0 (ours:
    /// four target voxels).
    pub normal_radius_m: f64,
    /// Largest surface variation `λ₀ / (λ₀ + λ₁ + λ₂)` (eigenvalues ascending; Pauly et al.
    /// 2002) of a neighbourhood that still gives a normal; rougher points are left out of the
    /// target. Default 0.1 (ours; 1/3 is an isotropic blob).
    pub max_surface_variation: f64,
    /// Smallest `λ₁ / λ₂` of a neighbourhood that still gives a normal: below it the
    /// neighbours lie on a line (one ring of a far scan) whose normal is undetermined.
    /// Default 0.05 (ours).
    pub min_planarity: f64,
    /// Correspondences farther apart (point to point) are rejected, metres. Default 6.0 =
    /// 3 σ₀ with KISS-ICP's initial threshold σ₀ = 2 m.
    pub max_correspondence_distance_m: f64,
    /// The robust kernel. Default Geman–McClure (KISS-ICP).
    pub kernel: Kernel,
    /// The kernel scale κ, metres. Default 2/3 = σ₀ / 3 (the KISS-ICP paper scales its kernel
    /// by σ / 3; our κ is a residual in metres).
    pub kernel_scale_m: f64,
    /// After convergence the kernel scale is halved and the estimate refined, down to this
    /// scale, metres (graduated robustness: the wide kernel's basin, the narrow kernel's
    /// precision). Default 0.1 (ours: a few times the range noise of automotive lidars); set it
    /// to `kernel_scale_m` or more for a single stage.
    pub final_kernel_scale_m: f64,
    /// Most Gauss–Newton iterations, over all stages. Default 100 (ours; KISS-ICP allows 500 point-to-point
    /// steps, point-to-plane converges in tens).
    pub max_iterations: usize,
    /// Converged when an update translates less than this, metres, … Default 1e-4
    /// (KISS-ICP's `convergence_criterion` on the update's norm).
    pub convergence_translation_m: f64,
    /// … and rotates less than this, radians. Default 1e-4 (same source).
    pub convergence_rotation_rad: f64,
    /// Fewer correspondences than this is an error (the clouds do not overlap). Default 30
    /// (ours: five per degree of freedom).
    pub min_correspondences: usize,
}

impl Default for RegistrationConfig {
    fn default() -> Self {
        Self {
            min_range_m: 0.0,
            max_range_m: 100.0,
            voxel_size_m: 1.0,
            target_voxel_scale: 0.5,
            source_voxel_scale: 1.5,
            normal_neighbours: 10,
            normal_radius_m: 2.0,
            max_surface_variation: 0.1,
            min_planarity: 0.05,
            max_correspondence_distance_m: 6.0,
            kernel: Kernel::GemanMcClure,
            kernel_scale_m: 2.0 / 3.0,
            final_kernel_scale_m: 0.1,
            max_iterations: 100,
            convergence_translation_m: 1e-4,
            convergence_rotation_rad: 1e-4,
            min_correspondences: 30,
        }
    }
}

impl RegistrationConfig {
    /// The target's voxel size, metres.
    pub fn target_voxel_m(&self) -> f64 {
        self.voxel_size_m * self.target_voxel_scale
    }

    /// The source's voxel size, metres.
    pub fn source_voxel_m(&self) -> f64 {
        self.voxel_size_m * self.source_voxel_scale
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        if !(self.min_range_m.is_finite() && self.min_range_m >= 0.0) {
            return Err(invalid(
                "min_range_m",
                "must be finite and ≥ 0",
                self.min_range_m,
            ));
        }
        if self.max_range_m.is_nan() || self.max_range_m <= self.min_range_m {
            return Err(invalid(
                "max_range_m",
                "must exceed min_range_m",
                self.max_range_m,
            ));
        }
        require_positive("voxel_size_m", self.voxel_size_m)?;
        require_positive("target_voxel_scale", self.target_voxel_scale)?;
        require_positive("source_voxel_scale", self.source_voxel_scale)?;
        require_positive("normal_radius_m", self.normal_radius_m)?;
        require_positive(
            "max_correspondence_distance_m",
            self.max_correspondence_distance_m,
        )?;
        require_positive("kernel_scale_m", self.kernel_scale_m)?;
        require_positive("final_kernel_scale_m", self.final_kernel_scale_m)?;
        require_positive("convergence_translation_m", self.convergence_translation_m)?;
        require_positive("convergence_rotation_rad", self.convergence_rotation_rad)?;
        if self.normal_neighbours < 3 {
            return Err(invalid(
                "normal_neighbours",
                "must be at least 3",
                self.normal_neighbours as f64,
            ));
        }
        if !(self.max_surface_variation > 0.0 && self.max_surface_variation <= 1.0 / 3.0) {
            return Err(invalid(
                "max_surface_variation",
                "must be in (0, 1/3]",
                self.max_surface_variation,
            ));
        }
        if !(self.min_planarity >= 0.0 && self.min_planarity <= 1.0) {
            return Err(invalid(
                "min_planarity",
                "must be in [0, 1]",
                self.min_planarity,
            ));
        }
        if self.max_iterations == 0 {
            return Err(invalid("max_iterations", "must be at least 1", 0.0));
        }
        if self.min_correspondences < 6 {
            return Err(invalid(
                "min_correspondences",
                "must be at least 6 (six unknowns)",
                self.min_correspondences as f64,
            ));
        }
        Ok(())
    }
}

/// How [`Odometry`](crate::Odometry) tracks a sequence: registration settings plus KISS-ICP's
/// adaptive threshold and local map.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OdometryConfig {
    /// Preprocessing, normals and Gauss–Newton settings. Its `max_correspondence_distance_m`
    /// and `kernel_scale_m` are replaced per frame by 3 σ and σ / 3 of the adaptive threshold
    /// (unless `fixed_threshold_m` is set).
    pub registration: RegistrationConfig,
    /// σ₀, the threshold before any motion has been seen, metres. Default 2.0 (KISS-ICP
    /// `initial_threshold`).
    pub initial_threshold_m: f64,
    /// Model deviations smaller than this do not update σ, metres. Default 0.1 (KISS-ICP
    /// `min_motion_th`).
    pub min_motion_m: f64,
    /// A fixed σ instead of the adaptive one, metres. Default `None` (KISS-ICP
    /// `fixed_threshold`).
    pub fixed_threshold_m: Option<f64>,
    /// Most points per map voxel (voxel size `registration.voxel_size_m`). Default 20
    /// (KISS-ICP `max_points_per_voxel`).
    pub max_points_per_voxel: usize,
}

impl Default for OdometryConfig {
    fn default() -> Self {
        Self {
            registration: RegistrationConfig::default(),
            initial_threshold_m: 2.0,
            min_motion_m: 0.1,
            fixed_threshold_m: None,
            max_points_per_voxel: 20,
        }
    }
}

impl OdometryConfig {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        self.registration.validate()?;
        require_positive("initial_threshold_m", self.initial_threshold_m)?;
        if !(self.min_motion_m.is_finite() && self.min_motion_m >= 0.0) {
            return Err(invalid(
                "min_motion_m",
                "must be finite and ≥ 0",
                self.min_motion_m,
            ));
        }
        if let Some(sigma) = self.fixed_threshold_m {
            require_positive("fixed_threshold_m", sigma)?;
        }
        if self.max_points_per_voxel == 0 {
            return Err(invalid("max_points_per_voxel", "must be at least 1", 0.0));
        }
        if !self.registration.max_range_m.is_finite() {
            return Err(invalid(
                "registration.max_range_m",
                "must be finite in odometry (it is the local map's radius)",
                self.registration.max_range_m,
            ));
        }
        Ok(())
    }
}

fn invalid(name: &'static str, rule: &str, value: f64) -> RegistrationError {
    RegistrationError::InvalidParameter {
        name,
        reason: format!("{rule}, got {value}"),
    }
}
