//! Keypoints and 512-bit binary descriptors on 8-bit images, for IBuILD (Khan 2017, §4.4.1)
//! and the DBoW2-style baseline.
//!
//! The thesis uses BRISK keypoints and descriptors (Leutenegger et al., ICCV 2011) with
//! p = 512 bits (§4.4.1, §4.6.1). We write our own detector/descriptor from the papers:
//!
//! 1. **Pyramid**: [`FeatureConfig::octaves`] levels, each [`FeatureConfig::scale_factor`]
//!    (default √2) smaller than the previous (bilinear resampling). BRISK's octaves halve the
//!    image with an intermediate layer at 1.5; √2 per level spans the same scales with one
//!    uniform step, for scale robustness like BRISK's.
//! 2. **FAST-9 corners** (Rosten & Drummond, ECCV 2006) on every level with the threshold
//!    [`FeatureConfig::threshold`], the paper's score `V` (sum of absolute differences over the
//!    bright or dark arc, minus the threshold) and 3 × 3 non-maximum suppression. Corners closer
//!    to the level's border than the patch radius are dropped. The strongest
//!    [`FeatureConfig::max_keypoints`] over all levels are kept; ties are broken by level, row
//!    and column, so the result is deterministic.
//! 3. **Orientation** by the intensity centroid of the patch (Rublee et al., ORB, ICCV 2011).
//! 4. **Steered BRIEF-512**: 512 point pairs drawn once from an isotropic Gaussian
//!    (σ = patch size / 5, BRIEF's G II; Calonder et al., ECCV 2010) with a fixed seed, so the
//!    pattern never changes; each bit compares two pixels of the level image smoothed with a
//!    Gaussian of [`FeatureConfig::sigma`]; the pattern is rotated by the keypoint angle, using
//!    32 pre-rotated tables (11.25° bins; quarter turns map bins onto bins exactly).
//!
//! **Why ORB-style, BRISK-dimensioned.** IBuILD only needs a binary, rotation- and
//! scale-robust descriptor compared by Hamming distance (eq. (4.1) and the threshold δ act on
//! bits), and its δ values are given for p = 512 bits. BRISK's concentric sampling rings with
//! distance-based short/long pair selection are specific to its published pattern; a seeded
//! Gaussian pattern of 512 pairs, steered by the intensity centroid, has the same size and
//! invariances, is written entirely from the papers, and is cheap (one lookup pair per bit).
//! Its bits are therefore not interchangeable with OpenCV's BRISK, and the δ sweep of
//! §4.6.1 (not printed in the thesis) has to be chosen for this descriptor.
//!
//! Empty images and images smaller than a patch give no keypoints (not an error); zero-size
//! configuration values give [`PlaceError::InvalidParameter`].

mod brief;
mod fast;
mod pyramid;

use image::GrayImage;

use crate::{Bits512, PlaceError, Result};
use brief::Pattern;
use fast::Corner;
use pyramid::Plane;

/// Parameters of keypoint detection and description.
#[derive(Clone, Debug, PartialEq)]
pub struct FeatureConfig {
    /// FAST intensity threshold `t` in grey levels (default 20, ORB's default; ours).
    pub threshold: u8,
    /// Number of pyramid levels, at least 1 (default 4; ours).
    pub octaves: usize,
    /// Size ratio between consecutive pyramid levels, > 1 (default √2; ours, see the module
    /// docs).
    pub scale_factor: f32,
    /// Keep at most this many keypoints, strongest first (default 500; ORB's default).
    pub max_keypoints: usize,
    /// Side of the square descriptor and orientation patch in pixels of its level, 7..=255
    /// (default 31, ORB's). Keypoints closer than `(patch_size − 1) / 2` pixels to the border
    /// of their level are dropped.
    pub patch_size: usize,
    /// Standard deviation in pixels of the Gaussian smoothing before the binary tests
    /// (default 2, BRIEF's; Calonder et al. 2010).
    pub sigma: f32,
}

impl Default for FeatureConfig {
    fn default() -> Self {
        Self {
            threshold: 20,
            octaves: 4,
            scale_factor: std::f32::consts::SQRT_2,
            max_keypoints: 500,
            patch_size: 31,
            sigma: 2.0,
        }
    }
}

impl FeatureConfig {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        let invalid = |name, reason: &str| {
            Err(PlaceError::InvalidParameter {
                name,
                reason: reason.to_string(),
            })
        };
        if self.octaves == 0 {
            return invalid("octaves", "must be at least 1");
        }
        if self.max_keypoints == 0 {
            return invalid("max_keypoints", "must be at least 1");
        }
        if !(7..=255).contains(&self.patch_size) {
            return invalid("patch_size", "must be in 7..=255 pixels");
        }
        if !(self.scale_factor.is_finite() && self.scale_factor > 1.0) {
            return invalid("scale_factor", "must be finite and above 1");
        }
        if !(self.sigma.is_finite() && self.sigma > 0.0) {
            return invalid("sigma", "must be finite and positive");
        }
        Ok(())
    }
}

/// A detected keypoint in pixel coordinates of the input image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Keypoint {
    /// Column (pixels; pixel centres are at integers).
    pub x: f32,
    /// Row (pixels).
    pub y: f32,
    /// Orientation in radians in image coordinates (x right, y down), in `(−π, π]`.
    pub angle: f32,
    /// Detector response, the FAST score (higher = stronger).
    pub response: f32,
}

/// A corner selected on pyramid level `level`.
struct Selected {
    level: usize,
    corner: Corner,
}

/// Detects keypoints and computes their 512-bit descriptors (see the module docs). Returns
/// the keypoints strongest first and one descriptor per keypoint.
pub fn detect_and_describe(
    image: &GrayImage,
    config: &FeatureConfig,
) -> Result<(Vec<Keypoint>, Vec<Bits512>)> {
    config.validate()?;
    let pattern = Pattern::new(config.patch_size);
    let min_side = 2 * pattern.radius + 1;
    let (mut levels, mut selected) = (Vec::new(), Vec::new());
    let mut plane = Plane {
        width: image.width() as usize,
        height: image.height() as usize,
        pixels: image.as_raw().clone(),
    };
    let (mut scores, mut corners) = (Vec::new(), Vec::new());
    for level in 0..config.octaves {
        if plane.width < min_side || plane.height < min_side {
            break;
        }
        fast::detect(
            &plane.pixels,
            plane.width,
            plane.height,
            config.threshold,
            pattern.radius,
            &mut scores,
            &mut corners,
        );
        selected.extend(corners.iter().map(|&corner| Selected { level, corner }));
        let next = plane.downsample(config.scale_factor);
        levels.push(plane);
        plane = next;
    }
    selected.sort_by(|a, b| {
        (b.corner.score.total_cmp(&a.corner.score))
            .then(a.level.cmp(&b.level))
            .then(a.corner.y.cmp(&b.corner.y))
            .then(a.corner.x.cmp(&b.corner.x))
    });
    selected.truncate(config.max_keypoints);

    // Smooth only the levels that keep keypoints.
    let mut scratch = Vec::new();
    let smoothed: Vec<Option<Plane>> = levels
        .iter()
        .enumerate()
        .map(|(level, raw)| {
            selected
                .iter()
                .any(|s| s.level == level)
                .then(|| raw.gaussian(config.sigma, &mut scratch))
        })
        .collect();
    let mut keypoints = Vec::with_capacity(selected.len());
    let mut descriptors = Vec::with_capacity(selected.len());
    for s in &selected {
        let Some(smooth) = &smoothed[s.level] else {
            continue;
        };
        let scale = config.scale_factor.powi(s.level as i32);
        let Corner { x, y, score } = s.corner;
        let angle = pattern.orientation(smooth, x, y);
        descriptors.push(pattern.describe(smooth, x, y, angle));
        keypoints.push(Keypoint {
            x: (x as f32 + 0.5) * scale - 0.5,
            y: (y as f32 + 0.5) * scale - 0.5,
            angle,
            response: score,
        });
    }
    Ok((keypoints, descriptors))
}

#[cfg(test)]
mod tests;
