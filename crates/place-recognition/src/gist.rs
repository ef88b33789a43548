//! The GIST global image descriptor (Oliva & Torralba, IJCV 2001; Khan 2017, §4.5.2): mean
//! Gabor energies of a φ × φ grid of blocks, for Ω scales and χ orientations per scale.
//!
//! Steps, with the parameters of Oliva and Torralba's reference implementation:
//!
//! 1. The image is resized to `S × S` pixels (bilinear, widened when shrinking) and its grey
//!    levels stretched to `[0, 255]`.
//! 2. **Prefilter** (local contrast normalisation): `I ← log(I + 1)`, mirror-padded by 5 px;
//!    `I' = I − I ∗ g` with the Gaussian low-pass `ĝ(f) = exp(−‖f‖² / s²)`,
//!    `s = f_c / √(ln 2)`, `f_c = 4` cycles per image, then `I'' = I' / (0.2 + √|I'² ∗ g|)`.
//! 3. The result is mirror-padded by 32 px to `N × N` and filtered in the frequency domain by
//!    the Gabor bank `G_{ij}(f) = exp(−10·a·(‖f‖/(N·b_i) − 1)² − 2·c·π·(∠f + θ_j)²)` with
//!    `a = 0.35`, `b_i = 0.3 / 1.85^i` (scale `i = 0…Ω−1`), `c = 16 χ² / 32²` and
//!    `θ_j = π j / χ` (`j = 0…χ−1`; the angle wrapped to `[−π, π]`).
//! 4. The magnitude of each filtered image, cropped back to `S × S`, is averaged over each
//!    block of a `φ × φ` grid (block edges at `⌊k S / φ⌋`).
//! 5. The descriptor lists the filters scale by scale, orientations within a scale, and for
//!    each filter the blocks row by row: `Ω · χ · φ²` values (512 with the defaults).
//!
//! ## Decisions
//!
//! * Symbols follow the thesis body text: **Ω = scales, χ = orientations per scale, φ =
//!   blocks per side** (its notation list swaps Ω and χ). The thesis gives no values; the
//!   defaults are the reference's: Ω = 4, χ = 8, φ = 4 → 512 values.
//! * The reference crops the image to a centred square before resizing. A lidar panorama
//!   (1024 × 64) would lose 15/16 of its columns, so we resize the whole image to the square
//!   instead (anisotropically). `S = 128` px, the reference's default.
//! * The FFTs are `rustfft`'s (2-D by rows, then columns); everything is deterministic.
//! * A constant image has no contrast to stretch and gives the zero vector. `S` must be even
//!   (the FFT grid is centred at `N/2`).

use std::sync::Arc;

use image::imageops::{self, FilterType};
use image::{GrayImage, ImageBuffer, Luma};
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

use crate::error::require_positive;
use crate::{PlaceError, Result};

/// Padding of the prefilter, pixels (reference implementation).
const PREFILTER_PAD: usize = 5;

/// GIST parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct GistConfig {
    /// Side `S` of the square the image is resized to, pixels (even). Default 128 (reference).
    pub image_size: u32,
    /// Number of scales Ω. Default 4 (reference).
    pub scales: usize,
    /// Orientations per scale χ. Default 8 (reference).
    pub orientations: usize,
    /// Blocks per side φ of the averaging grid. Default 4 (reference).
    pub blocks: usize,
    /// Cut-off `f_c` of the prefilter, cycles per image. Default 4 (reference).
    pub prefilter_fc: f64,
    /// Mirror padding before the Gabor filtering, pixels. Default 32 (reference).
    pub boundary_extension: u32,
}

impl Default for GistConfig {
    fn default() -> Self {
        Self {
            image_size: 128,
            scales: 4,
            orientations: 8,
            blocks: 4,
            prefilter_fc: 4.0,
            boundary_extension: 32,
        }
    }
}

impl GistConfig {
    /// Length of the descriptor, `Ω · χ · φ²`.
    pub fn descriptor_len(&self) -> usize {
        self.scales * self.orientations * self.blocks * self.blocks
    }

    fn validate(&self) -> Result<()> {
        let invalid = |name, reason: &str| {
            Err(PlaceError::InvalidParameter {
                name,
                reason: reason.into(),
            })
        };
        if self.image_size < 2 || self.image_size % 2 == 1 {
            return invalid("image_size", "must be even and at least 2");
        }
        for (name, value) in [
            ("scales", self.scales),
            ("orientations", self.orientations),
            ("blocks", self.blocks),
        ] {
            if value == 0 {
                return invalid(name, "must be at least 1");
            }
        }
        if self.blocks > self.image_size as usize {
            return invalid("blocks", "must not exceed image_size");
        }
        require_positive("prefilter_fc", self.prefilter_fc)
    }
}

/// A square 2-D FFT of side `n` (rows, then columns through a transpose).
struct Fft2 {
    n: usize,
    forward: Arc<dyn Fft<f32>>,
    inverse: Arc<dyn Fft<f32>>,
}

impl Fft2 {
    fn new(planner: &mut FftPlanner<f32>, n: usize) -> Self {
        Self {
            n,
            forward: planner.plan_fft_forward(n),
            inverse: planner.plan_fft_inverse(n),
        }
    }

    fn scratch_len(&self) -> usize {
        self.forward
            .get_inplace_scratch_len()
            .max(self.inverse.get_inplace_scratch_len())
    }

    /// In-place transform of `data` (`n × n`, row-major); the inverse is scaled by `1/n²`.
    fn run(
        &self,
        data: &mut [Complex<f32>],
        tmp: &mut [Complex<f32>],
        scratch: &mut [Complex<f32>],
        inverse: bool,
    ) {
        let (fft, n) = (
            if inverse {
                &self.inverse
            } else {
                &self.forward
            },
            self.n,
        );
        fft.process_with_scratch(data, scratch);
        transpose(data, tmp, n);
        fft.process_with_scratch(tmp, scratch);
        transpose(tmp, data, n);
        if inverse {
            let s = 1.0 / (n * n) as f32;
            data.iter_mut().for_each(|v| *v *= s);
        }
    }
}

fn transpose(src: &[Complex<f32>], dst: &mut [Complex<f32>], n: usize) {
    for (y, row) in src.chunks_exact(n).enumerate() {
        for (x, &v) in row.iter().enumerate() {
            dst[x * n + y] = v;
        }
    }
}

/// Signed frequency of FFT index `k` on a grid of `n` (the reference's `fftshift`ed
/// `−n/2 … n/2 − 1`).
fn frequency(k: usize, n: usize) -> f64 {
    if k < n / 2 {
        k as f64
    } else {
        k as f64 - n as f64
    }
}

/// Mirror index (MATLAB's `symmetric` padding: the edge pixel is repeated).
fn reflect(i: i64, n: usize) -> usize {
    let m = i.rem_euclid(2 * n as i64) as usize;
    if m < n { m } else { 2 * n - 1 - m }
}

/// `src` (`s × s`) mirror-padded by `pad` into `dst` (`n × n`, `n ≥ s + 2·pad`).
fn pad_into(src: &[f32], s: usize, pad: usize, dst: &mut [Complex<f32>], n: usize) {
    for y in 0..n {
        let sy = reflect(y as i64 - pad as i64, s);
        for x in 0..n {
            let sx = reflect(x as i64 - pad as i64, s);
            dst[y * n + x] = Complex::new(src[sy * s + sx], 0.0);
        }
    }
}

/// A GIST extractor with its filter bank and FFT plans prepared once.
pub struct Gist {
    config: GistConfig,
    prefilter: Fft2,
    /// Gaussian low-pass of the prefilter, FFT layout.
    lowpass: Vec<f32>,
    gabor: Fft2,
    /// The Gabor transfer functions, one `N × N` plane per filter, FFT layout.
    filters: Vec<f32>,
}

impl std::fmt::Debug for Gist {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gist")
            .field("config", &self.config)
            .finish_non_exhaustive()
    }
}

impl Clone for Gist {
    fn clone(&self) -> Self {
        Self {
            config: self.config.clone(),
            prefilter: Fft2 {
                n: self.prefilter.n,
                forward: Arc::clone(&self.prefilter.forward),
                inverse: Arc::clone(&self.prefilter.inverse),
            },
            lowpass: self.lowpass.clone(),
            gabor: Fft2 {
                n: self.gabor.n,
                forward: Arc::clone(&self.gabor.forward),
                inverse: Arc::clone(&self.gabor.inverse),
            },
            filters: self.filters.clone(),
        }
    }
}

impl Gist {
    /// Prepares the prefilter, the Gabor bank and the FFT plans.
    pub fn new(config: GistConfig) -> Result<Self> {
        config.validate()?;
        let s = config.image_size as usize;
        let mut planner = FftPlanner::new();
        let np = s + 2 * PREFILTER_PAD;
        let s1 = config.prefilter_fc / std::f64::consts::LN_2.sqrt();
        let mut lowpass = vec![0.0f32; np * np];
        for (k, g) in lowpass.iter_mut().enumerate() {
            let (fy, fx) = (frequency(k / np, np), frequency(k % np, np));
            *g = (-(fx * fx + fy * fy) / (s1 * s1)).exp() as f32;
        }
        let n = s + 2 * config.boundary_extension as usize;
        let (chi, nf) = (config.orientations, config.scales * config.orientations);
        let c = 16.0 * (chi * chi) as f64 / (32.0 * 32.0);
        let mut filters = vec![0.0f32; nf * n * n];
        for (f, plane) in filters.chunks_exact_mut(n * n).enumerate() {
            let (scale, orientation) = (f / chi, f % chi);
            let b = 0.3 / 1.85f64.powi(scale as i32);
            let theta = std::f64::consts::PI / chi as f64 * orientation as f64;
            for (k, g) in plane.iter_mut().enumerate() {
                let (fy, fx) = (frequency(k / n, n), frequency(k % n, n));
                let radius = (fx * fx + fy * fy).sqrt();
                let mut tr = fy.atan2(fx) + theta;
                if tr > std::f64::consts::PI {
                    tr -= std::f64::consts::TAU;
                }
                let radial = radius / n as f64 / b - 1.0;
                *g = (-10.0 * 0.35 * radial * radial - 2.0 * c * std::f64::consts::PI * tr * tr)
                    .exp() as f32;
            }
        }
        Ok(Self {
            prefilter: Fft2::new(&mut planner, np),
            lowpass,
            gabor: Fft2::new(&mut planner, n),
            filters,
            config,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &GistConfig {
        &self.config
    }

    /// The image resized to `S × S` and stretched to `[0, 255]`; `None` for a constant image.
    fn normalised(&self, image: &GrayImage) -> Option<Vec<f32>> {
        let s = self.config.image_size;
        // In [0, 1]: `image` clamps floating-point pixels to that range when resampling.
        let data: Vec<f32> = image
            .as_raw()
            .iter()
            .map(|&v| f32::from(v) / 255.0)
            .collect();
        let buffer: ImageBuffer<Luma<f32>, Vec<f32>> =
            ImageBuffer::from_raw(image.width(), image.height(), data)?;
        let mut resized = imageops::resize(&buffer, s, s, FilterType::Triangle).into_raw();
        let (lo, hi) = resized
            .iter()
            .fold((f32::MAX, f32::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        if hi - lo <= 1e-6 * hi.abs().max(1.0) {
            return None;
        }
        resized
            .iter_mut()
            .for_each(|v| *v = 255.0 * (*v - lo) / (hi - lo));
        Some(resized)
    }

    /// Local contrast normalisation (step 2 of the module docs).
    fn prefiltered(&self, img: &[f32]) -> Vec<f32> {
        let (s, np) = (self.config.image_size as usize, self.prefilter.n);
        let logged: Vec<f32> = img.iter().map(|v| (v + 1.0).ln()).collect();
        let mut a = vec![Complex::new(0.0f32, 0.0); np * np];
        let mut tmp = a.clone();
        let mut scratch = vec![Complex::new(0.0f32, 0.0); self.prefilter.scratch_len()];
        pad_into(&logged, s, PREFILTER_PAD, &mut a, np);
        let padded: Vec<f32> = a.iter().map(|v| v.re).collect();
        self.prefilter.run(&mut a, &mut tmp, &mut scratch, false);
        a.iter_mut().zip(&self.lowpass).for_each(|(v, &g)| *v *= g);
        self.prefilter.run(&mut a, &mut tmp, &mut scratch, true);
        let high: Vec<f32> = padded.iter().zip(&a).map(|(p, v)| p - v.re).collect();
        a.iter_mut()
            .zip(&high)
            .for_each(|(v, &h)| *v = Complex::new(h * h, 0.0));
        self.prefilter.run(&mut a, &mut tmp, &mut scratch, false);
        a.iter_mut().zip(&self.lowpass).for_each(|(v, &g)| *v *= g);
        self.prefilter.run(&mut a, &mut tmp, &mut scratch, true);
        let mut out = vec![0.0f32; s * s];
        for y in 0..s {
            for x in 0..s {
                let k = (y + PREFILTER_PAD) * np + x + PREFILTER_PAD;
                out[y * s + x] = high[k] / (0.2 + a[k].norm().sqrt());
            }
        }
        out
    }

    /// The GIST descriptor of an image, [`GistConfig::descriptor_len`] values.
    pub fn describe(&self, image: &GrayImage) -> Result<Vec<f32>> {
        if image.width() == 0 || image.height() == 0 {
            return Err(PlaceError::BadInput("gist: empty image".into()));
        }
        let phi = self.config.blocks;
        let mut out = vec![0.0f32; self.config.descriptor_len()];
        let Some(img) = self.normalised(image) else {
            return Ok(out);
        };
        let pre = self.prefiltered(&img);
        let (s, n, be) = (
            self.config.image_size as usize,
            self.gabor.n,
            self.config.boundary_extension as usize,
        );
        let mut spectrum = vec![Complex::new(0.0f32, 0.0); n * n];
        let mut a = spectrum.clone();
        let mut tmp = spectrum.clone();
        let mut scratch = vec![Complex::new(0.0f32, 0.0); self.gabor.scratch_len()];
        pad_into(&pre, s, be, &mut spectrum, n);
        self.gabor.run(&mut spectrum, &mut tmp, &mut scratch, false);
        let edges: Vec<usize> = (0..=phi).map(|k| k * s / phi).collect();
        for (filter, block_means) in self
            .filters
            .chunks_exact(n * n)
            .zip(out.chunks_exact_mut(phi * phi))
        {
            a.iter_mut()
                .zip(&spectrum)
                .zip(filter)
                .for_each(|((v, &f), &g)| *v = f * g);
            self.gabor.run(&mut a, &mut tmp, &mut scratch, true);
            for (by, ys) in edges.windows(2).enumerate() {
                for (bx, xs) in edges.windows(2).enumerate() {
                    let mut sum = 0.0f32;
                    for y in ys[0]..ys[1] {
                        let row = (y + be) * n + be;
                        sum += a[row + xs[0]..row + xs[1]]
                            .iter()
                            .map(|v| v.norm())
                            .sum::<f32>();
                    }
                    let count = (ys[1] - ys[0]) * (xs[1] - xs[0]);
                    block_means[by * phi + bx] = sum / count as f32;
                }
            }
        }
        Ok(out)
    }
}

/// The GIST descriptor of an image (prepares a [`Gist`] each call; keep one for many images).
pub fn gist(image: &GrayImage, config: &GistConfig) -> Result<Vec<f32>> {
    Gist::new(config.clone())?.describe(image)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(shift: u32) -> GrayImage {
        GrayImage::from_fn(256, 64, |x, y| {
            let x = (x + shift) % 256;
            let stripes = if (x / 16) % 2 == 0 { 60 } else { 0 };
            let blob = if (100..140).contains(&x) && y > 20 {
                150
            } else {
                0
            };
            Luma([(stripes + blob + y) as u8])
        })
    }

    #[test]
    fn gist_has_512_values_and_is_deterministic() {
        let gist = Gist::new(GistConfig::default()).unwrap();
        let d = gist.describe(&scene(0)).unwrap();
        assert_eq!(d.len(), 512);
        assert!(d.iter().all(|v| v.is_finite() && *v >= 0.0));
        assert!(d.iter().any(|&v| v > 0.0));
        assert_eq!(d, gist.describe(&scene(0)).unwrap());
        let c = crate::cosine_similarity(&d, &d);
        assert!((c - 1.0).abs() < 1e-6, "{c}");
        // A different scene is less similar than the scene itself.
        let other = gist.describe(&scene(64)).unwrap();
        assert!(crate::cosine_similarity(&d, &other) < 0.999);
    }

    #[test]
    fn constant_images_give_zero_and_bad_configs_are_errors() {
        let gist = Gist::new(GistConfig {
            image_size: 32,
            ..GistConfig::default()
        })
        .unwrap();
        let d = gist
            .describe(&GrayImage::from_pixel(40, 10, Luma([9])))
            .unwrap();
        assert!(d.iter().all(|&v| v == 0.0));
        assert!(gist.describe(&GrayImage::new(0, 0)).is_err());
        assert!(
            Gist::new(GistConfig {
                image_size: 33,
                ..GistConfig::default()
            })
            .is_err()
        );
        assert!(
            Gist::new(GistConfig {
                orientations: 0,
                ..GistConfig::default()
            })
            .is_err()
        );
    }

    #[test]
    fn vertical_stripes_excite_the_horizontal_frequency_filter() {
        // Vertical stripes have horizontal frequencies (angle 0): the orientation-0 filters
        // answer more than the orientation-4 (π/2) ones.
        let config = GistConfig {
            image_size: 64,
            ..GistConfig::default()
        };
        let img = GrayImage::from_fn(64, 64, |x, _| {
            Luma([if (x / 4) % 2 == 0 { 0 } else { 255 }])
        });
        let d = Gist::new(config).unwrap().describe(&img).unwrap();
        let energy = |scale: usize, orientation: usize| -> f32 {
            let f = scale * 8 + orientation;
            d[f * 16..(f + 1) * 16].iter().sum()
        };
        let (along, across): (f32, f32) =
            (0..4).fold((0.0, 0.0), |(a, c), s| (a + energy(s, 0), c + energy(s, 4)));
        assert!(along > 5.0 * across, "{along} vs {across}");
    }
}
