//! The raw-pixel baseline: SeqSLAM's single-image comparison (Milford & Wyeth, ICRA 2012,
//! §III-A) — each image is downsampled, normalised in patches, and two images are compared
//! by their sum of absolute differences. Name `"raw-pixels"`.
//!
//! * **Downsampling** to [`RawPixelConfig::width`] × [`RawPixelConfig::height`] (bilinear,
//!   the `image` crate's triangle filter; an image of that size is used as it is).
//! * **Patch normalisation**: the image is cut into square patches of side
//!   [`RawPixelConfig::patch`] (a last, smaller patch where the side does not divide), and each
//!   pixel becomes `(I − μ_P) / σ_P` with the mean and standard deviation of its patch (a
//!   constant patch becomes 0) — ours: the paper rescales patches to a fixed range, the z-score
//!   is the same normalisation up to a scale shared by all patches.
//! * **Storage** (ours, for speed): each normalised value is quantised to a byte,
//!   `q = clamp(round(32 z) + 128, 0, 255)` (steps of 1/32 σ, clipped at ±4 σ), so a query
//!   compares bytes — at 10 000 frames of 64 × 32 px that is 20 MB per query.
//! * **Difference** `D(i, j) = (1 / 32 N) Σ_p |q_i(p) − q_j(p)|` over the `N` pixels (the
//!   paper's sum of absolute differences, Eq. (1), divided by `N`, in units of σ); the score
//!   is `−D` (higher = more similar), so a frame scores 0 against itself and never less than
//!   another frame.
//!
//! This is also the difference matrix SeqSLAM feeds to its sequence search
//! ([`crate::sequence_match`]); any other method's scores can feed it too.

use crate::{Candidate, Frame, ImageConfig, PlaceError, PlaceRecognizer, Result, frame_image};

/// Parameters of the raw-pixel baseline.
#[derive(Clone, Debug, PartialEq)]
pub struct RawPixelConfig {
    /// Width after downsampling, pixels. Default 64 (SeqSLAM on Nordland uses 64 × 32).
    pub width: u32,
    /// Height after downsampling, pixels. Default 32.
    pub height: u32,
    /// Side of the normalisation patches, pixels. Default 8 (ours).
    pub patch: u32,
    /// How frames become images (lidar frames: intensity image or rasterised scan).
    pub image: ImageConfig,
}

impl Default for RawPixelConfig {
    fn default() -> Self {
        Self {
            width: 64,
            height: 32,
            patch: 8,
            image: ImageConfig::default(),
        }
    }
}

impl RawPixelConfig {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        let bad = |name, reason: &str| {
            Err(PlaceError::InvalidParameter {
                name,
                reason: reason.into(),
            })
        };
        if self.width == 0 || self.height == 0 {
            return bad("width/height", "must be at least 1 pixel");
        }
        if self.patch < 2 {
            return bad("patch", "must be at least 2 pixels");
        }
        self.image.validate()
    }
}

/// Quantisation steps per standard deviation of the stored thumbnails.
const STEPS_PER_SIGMA: f32 = 32.0;

/// A database of patch-normalised thumbnails compared by mean absolute difference.
#[derive(Clone, Debug)]
pub struct RawPixels {
    config: RawPixelConfig,
    /// All quantised thumbnails, one after the other, `width × height` bytes each.
    data: Vec<u8>,
}

impl RawPixels {
    /// An empty database with a validated configuration.
    pub fn new(config: RawPixelConfig) -> Result<Self> {
        config.validate()?;
        Ok(Self {
            config,
            data: Vec::new(),
        })
    }

    fn size(&self) -> usize {
        (self.config.width * self.config.height) as usize
    }

    /// The stored (quantised) thumbnail of frame `index`.
    pub fn thumbnail(&self, index: usize) -> Option<&[u8]> {
        let n = self.size();
        self.data.get(index * n..(index + 1) * n)
    }

    fn scores(&self, d: &[u8], before: usize) -> Vec<Candidate> {
        let n = self.size();
        if d.len() != n {
            return Vec::new();
        }
        self.data
            .chunks_exact(n)
            .take(before)
            .enumerate()
            .map(|(frame, stored)| Candidate {
                frame,
                score: -f64::from(mean_abs_difference(d, stored)),
            })
            .collect()
    }
}

/// `(1 / 32 N) Σ |a − b|` over equal-length quantised thumbnails (Milford & Wyeth 2012,
/// Eq. (1), over `N`, in units of σ). Written as a plain sum of byte differences, which the
/// compiler turns into packed sum-of-absolute-differences instructions (at most 2²⁴ values:
/// the sum is 32-bit).
pub fn mean_abs_difference(a: &[u8], b: &[u8]) -> f32 {
    let total: u32 = a
        .iter()
        .zip(b)
        .map(|(x, y)| u32::from(x.abs_diff(*y)))
        .sum();
    total as f32 / (STEPS_PER_SIGMA * a.len().max(1) as f32)
}

/// Quantises normalised values to bytes: `clamp(round(32 z) + 128, 0, 255)`.
pub fn quantise(values: &[f32]) -> Vec<u8> {
    values
        .iter()
        .map(|&z| (z * STEPS_PER_SIGMA + 128.0).round().clamp(0.0, 255.0) as u8)
        .collect()
}

/// Patch normalisation of a `width × height` image (row-major): each pixel minus its patch's
/// mean, over its patch's standard deviation; 0 in a constant patch.
pub fn patch_normalise(pixels: &[f32], width: usize, height: usize, patch: usize) -> Vec<f32> {
    let mut out = vec![0.0f32; pixels.len()];
    for y0 in (0..height).step_by(patch) {
        for x0 in (0..width).step_by(patch) {
            let (y1, x1) = ((y0 + patch).min(height), (x0 + patch).min(width));
            let cells = || (y0..y1).flat_map(move |y| (x0..x1).map(move |x| y * width + x));
            let n = ((y1 - y0) * (x1 - x0)) as f64;
            let mean = cells().map(|i| f64::from(pixels[i])).sum::<f64>() / n;
            let var = cells()
                .map(|i| (f64::from(pixels[i]) - mean).powi(2))
                .sum::<f64>()
                / n;
            let sd = var.sqrt();
            for i in cells() {
                out[i] = if sd > 1e-9 {
                    ((f64::from(pixels[i]) - mean) / sd) as f32
                } else {
                    0.0
                };
            }
        }
    }
    out
}

impl PlaceRecognizer for RawPixels {
    type Description = Vec<u8>;

    fn name(&self) -> &'static str {
        "raw-pixels"
    }

    fn describe(&mut self, frame: &Frame<'_>) -> Result<Vec<u8>> {
        let image = frame_image(frame, &self.config.image)?;
        if image.width() == 0 || image.height() == 0 {
            return Err(PlaceError::BadInput("empty image".into()));
        }
        let (w, h) = (self.config.width, self.config.height);
        let small = if image.dimensions() == (w, h) {
            image.into_owned()
        } else {
            image::imageops::resize(image.as_ref(), w, h, image::imageops::FilterType::Triangle)
        };
        let pixels: Vec<f32> = small.as_raw().iter().map(|&p| f32::from(p)).collect();
        Ok(quantise(&patch_normalise(
            &pixels,
            w as usize,
            h as usize,
            self.config.patch as usize,
        )))
    }

    fn query(&self, description: &Vec<u8>, before: usize) -> Vec<Candidate> {
        self.scores(description, before)
    }

    fn query_stored(&self, index: usize, before: usize) -> Vec<Candidate> {
        match self.thumbnail(index) {
            Some(d) => self.scores(d, before),
            None => Vec::new(),
        }
    }

    fn insert(&mut self, description: Vec<u8>) {
        if description.len() == self.size() {
            self.data.extend_from_slice(&description);
        } else {
            // Not from `describe`: store a constant thumbnail so frame indices stay aligned.
            self.data.extend(std::iter::repeat_n(128, self.size()));
        }
    }

    fn len(&self) -> usize {
        self.data.len() / self.size().max(1)
    }
}

#[cfg(test)]
mod tests {
    use image::GrayImage;

    use super::*;

    fn scene(seed: u32) -> GrayImage {
        GrayImage::from_fn(64, 32, |x, y| {
            let v = (x * 7 + y * 13 + seed * 31) ^ (x * y + seed);
            image::Luma([(v % 251) as u8])
        })
    }

    #[test]
    fn patches_have_zero_mean_and_unit_deviation() {
        let pixels: Vec<f32> = (0..64).map(|i| ((i * 37) % 17) as f32).collect();
        let out = patch_normalise(&pixels, 8, 8, 4);
        let out = &out;
        for (y0, x0) in [(0, 0), (0, 4), (4, 0), (4, 4)] {
            let v: Vec<f32> = (y0..y0 + 4)
                .flat_map(|y| (x0..x0 + 4).map(move |x| out[y * 8 + x]))
                .collect();
            let mean = v.iter().sum::<f32>() / 16.0;
            let var = v.iter().map(|a| (a - mean).powi(2)).sum::<f32>() / 16.0;
            assert!(
                mean.abs() < 1e-5 && (var - 1.0).abs() < 1e-4,
                "{mean} {var}"
            );
        }
        assert!(
            patch_normalise(&[5.0; 16], 4, 4, 2)
                .iter()
                .all(|&v| v == 0.0)
        );
    }

    #[test]
    fn brightness_and_contrast_changes_do_not_matter() {
        let mut db = RawPixels::new(RawPixelConfig::default()).expect("config");
        for seed in 0..4 {
            let d = db.describe(&Frame::Image(&scene(seed))).expect("describe");
            db.insert(d);
        }
        // Frame 2 at half contrast plus an offset: patch normalisation undoes both (up to
        // rounding to 8 bits).
        let dim = GrayImage::from_fn(64, 32, |x, y| {
            image::Luma([40 + scene(2).get_pixel(x, y).0[0] / 2])
        });
        let d = db.describe(&Frame::Image(&dim)).expect("describe");
        let best = db
            .query(&d, 4)
            .into_iter()
            .max_by(|a, b| a.score.total_cmp(&b.score))
            .expect("four frames");
        assert_eq!(best.frame, 2);
        let own = db.query_stored(1, 4);
        assert_eq!(own[1].score, 0.0);
        assert!(own.iter().all(|c| c.score <= 0.0));
    }

    #[test]
    fn mean_abs_difference_matches_the_formula() {
        let a: Vec<u8> = (0..71).map(|i| (i * 37 % 256) as u8).collect();
        let b: Vec<u8> = (0..71).map(|i| (i * i % 251) as u8).collect();
        let direct = a
            .iter()
            .zip(&b)
            .map(|(x, y)| f32::from(x.abs_diff(*y)))
            .sum::<f32>();
        assert!((mean_abs_difference(&a, &b) - direct / (32.0 * 71.0)).abs() < 1e-5);
        assert_eq!(
            quantise(&[0.0, 1.0, -1.0, 10.0, -10.0]),
            [128, 160, 96, 255, 0]
        );
        assert!(
            RawPixels::new(RawPixelConfig {
                patch: 1,
                ..RawPixelConfig::default()
            })
            .is_err()
        );
    }
}
