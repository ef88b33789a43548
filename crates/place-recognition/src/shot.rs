//! SHOT local 3-D descriptors, with and without an intensity texture, on a voxel-down-sampled
//! cloud (Khan 2017, §4.5.2: "SHOT … with and without (only geometry) intensity textures",
//! support radius 5ψ, ψ = 0.1 m).
//!
//! Pipeline of [`describe_cloud`]:
//!
//! 1. **Voxel grid** of size ψ ([`voxel_downsample`]): one point per occupied voxel, the
//!    centroid of its points, with their mean intensity; voxels in lexicographic `(i, j, k)`
//!    order, so the result does not depend on the input order.
//! 2. **Keypoints** — the thesis names no detector; **ours** ([`uniform_keypoints`]): on a
//!    coarser grid of [`ShotConfig::keypoint_spacing`] the down-sampled point nearest each
//!    occupied cell's centroid; if there are more than [`ShotConfig::max_keypoints`], those
//!    nearest the sensor (densest, and shared most by nearby frames).
//! 3. **Normals** by PCA over [`ShotConfig::normal_radius_factor`]` × ψ` (smallest-eigenvalue
//!    eigenvector, ≥ 3 points), oriented towards the viewpoint (the sensor origin), computed
//!    only for points inside some keypoint's support.
//! 4. **SHOT** (Tombari, Salti & Di Stefano, "Unique signatures of histograms for local
//!    surface description", ECCV 2010) with support radius `R = 5ψ`:
//!    * local reference frame: eigenvectors of `M = Σ (R − d_i)(p_i − p)(p_i − p)ᵀ / Σ (R − d_i)`
//!      (decreasing eigenvalues → x, y, z), x and z pointing to where the majority of
//!      `p_i − p` lie, `y = z × x`. A tied count (the paper keeps `+`) is broken, **ours**, by
//!      the sign of `Σ (R − d_i)(p_i − p)·x`, which is repeatable;
//!    * a spherical grid of 8 azimuth × 2 elevation × 2 radial (split at `R/2`) volumes, each
//!      with an 11-bin histogram of `cos θ_i = n_i · z`, every neighbour spread over the 16
//!      nearest (volume, bin) cells by **quadrilinear interpolation** (cos θ, azimuth
//!      (circular), elevation, radius; clamped beyond the outer bin centres) → 352 values,
//!      L2-normalised. The keypoint itself and neighbours without a normal are left out.
//! 5. **Intensity texture** (CSHOT, Tombari, Salti & Di Stefano, "A combined texture-shape
//!    descriptor for enhanced 3D feature matching", ICIP 2011, with the lidar intensity as the
//!    texture): per volume a 31-bin histogram of the **signed** intensity difference
//!    `ΔI = (I_i − I_p) / s` clamped to `[−1, 1]` (CSHOT uses the L1 colour distance; a scalar
//!    keeps its sign — ours), interpolated like the shape part → 992 values. `s` is
//!    [`ShotConfig::intensity_scale`] or the 99th percentile of `|I|` in the cloud. Each part
//!    is L2-normalised and scaled by `1/√2`, so the 1344-vector has unit norm and both parts
//!    weigh the same (ours).
//!
//! Keypoints with fewer than [`ShotConfig::min_support`] usable neighbours are skipped.
//! Neighbours come from a kiddo k-d tree (exact duplicate points share one tree entry); the
//! keypoints are described in parallel (rayon).

mod descriptor;
mod voxel;

#[cfg(test)]
mod tests;

use nalgebra::Point3;
use raypath_geometry::PointCloud;

use crate::error::require_positive;
use crate::{PlaceError, Result};

pub use descriptor::shot_at_keypoints;
pub use voxel::{uniform_keypoints, voxel_downsample};

/// Length of the geometric SHOT descriptor: 32 volumes × 11 cos θ bins.
pub const SHOT_SHAPE_LEN: usize = 352;

/// Parameters of the SHOT pipeline.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ShotConfig {
    /// Voxel size ψ of the down-sampling, metres. Default 0.1 m (Khan 2017, §4.6.2).
    pub voxel_size: f64,
    /// Support radius in units of ψ. Default 5 (Khan 2017, §4.5.2).
    pub support_factor: f64,
    /// Normal-estimation radius in units of ψ. Default 3 (ours).
    pub normal_radius_factor: f64,
    /// Spacing of the keypoint grid, metres. Default 1 m (ours).
    pub keypoint_spacing: f64,
    /// Maximum number of keypoints per cloud. Default 250 (ours: keeps a query fast).
    pub max_keypoints: usize,
    /// Minimum number of usable neighbours in the support. Default 10 (ours).
    pub min_support: usize,
    /// Add the intensity texture (CSHOT-style, 1344 values) to the shape part (352 values).
    /// Default false.
    pub with_intensity: bool,
    /// Bins of the intensity-difference histogram per volume. Default 31 (ours, after the
    /// colour histogram of CSHOT).
    pub intensity_bins: usize,
    /// Intensity difference that maps to ±1; `None` = the cloud's 99th percentile of `|I|`.
    /// Default `None` (ours).
    pub intensity_scale: Option<f64>,
}

impl Default for ShotConfig {
    fn default() -> Self {
        Self {
            voxel_size: 0.1,
            support_factor: 5.0,
            normal_radius_factor: 3.0,
            keypoint_spacing: 1.0,
            max_keypoints: 250,
            min_support: 10,
            with_intensity: false,
            intensity_bins: 31,
            intensity_scale: None,
        }
    }
}

impl ShotConfig {
    /// Support radius `R = support_factor × ψ`, metres.
    pub fn support_radius(&self) -> f64 {
        self.support_factor * self.voxel_size
    }

    /// Length of one descriptor: 352, plus `32 × intensity_bins` with intensity.
    pub fn descriptor_len(&self) -> usize {
        SHOT_SHAPE_LEN
            + if self.with_intensity {
                32 * self.intensity_bins
            } else {
                0
            }
    }

    /// Checks every parameter.
    pub fn validate(&self) -> Result<()> {
        require_positive("voxel_size", self.voxel_size)?;
        require_positive("support_factor", self.support_factor)?;
        require_positive("normal_radius_factor", self.normal_radius_factor)?;
        require_positive("keypoint_spacing", self.keypoint_spacing)?;
        if let Some(s) = self.intensity_scale {
            require_positive("intensity_scale", s)?;
        }
        for (name, value) in [
            ("max_keypoints", self.max_keypoints),
            ("min_support", self.min_support),
            ("intensity_bins", self.intensity_bins),
        ] {
            if value == 0 {
                return Err(PlaceError::InvalidParameter {
                    name,
                    reason: "must be at least 1".into(),
                });
            }
        }
        Ok(())
    }
}

/// SHOT descriptors of one cloud, contiguous `f32`.
#[derive(Clone, Debug, PartialEq)]
pub struct ShotDescriptors {
    /// Length of one descriptor (352 or 352 + 32 × bins).
    pub dim: usize,
    /// Descriptors one after another (`len = dim × keypoints.len()`).
    pub values: Vec<f32>,
    /// Index of each described keypoint in the cloud it was computed on.
    pub keypoints: Vec<usize>,
}

impl ShotDescriptors {
    /// Number of descriptors.
    pub fn len(&self) -> usize {
        self.keypoints.len()
    }

    /// True when no keypoint could be described.
    pub fn is_empty(&self) -> bool {
        self.keypoints.is_empty()
    }

    /// Descriptor `i`.
    pub fn get(&self, i: usize) -> &[f32] {
        &self.values[i * self.dim..(i + 1) * self.dim]
    }
}

/// The whole pipeline on a sensor-frame cloud: voxel grid, keypoints, normals (oriented
/// towards the origin) and SHOT. Keypoint indices refer to the down-sampled cloud.
pub fn describe_cloud(cloud: &PointCloud, config: &ShotConfig) -> Result<ShotDescriptors> {
    config.validate()?;
    let down = voxel_downsample(cloud, config.voxel_size)?;
    let keypoints = uniform_keypoints(&down, config.keypoint_spacing, config.max_keypoints)?;
    shot_at_keypoints(&down, &keypoints, &Point3::origin(), config)
}
