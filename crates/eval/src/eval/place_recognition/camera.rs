//! Day/night camera stand-ins and image statistics.
//!
//! There is no camera in the semi-synthetic drives, so a "camera-like" image per frame is the
//! lidar intensity image passed through a lighting model: **day** (every frame before the
//! second pass) = the intensity image with mild sensor noise (σ = 3 grey levels) and two to
//! four cast shadows (column bands darkened to 55 %); **night** (the second pass) = gamma 2.2
//! and 50 % exposure (dark surfaces vanish in the noise floor), stronger noise (σ = 10), no
//! shadows, and two or three street-light glows (Gaussian blobs of up to +90 grey levels). The
//! camera texture changes between passes while the lidar intensity does not — the thesis'
//! argument for active sensing (Khan 2017, §4.7.2). Seeded per frame (splitmix64).

use image::GrayImage;

/// The lighting model in words, for the report.
pub const DESCRIPTION: &str = "the lidar intensity image through a lighting model — day (first \
pass): sensor noise σ = 3 grey levels and two to four cast shadows (column bands at 55 %); \
night (second pass): gamma 2.2 at 50 % exposure, noise σ = 10, no shadows, two or three \
street-light glows (Gaussian blobs up to +90 grey levels); seeded per frame.";

/// A small deterministic generator (splitmix64), enough for noise and shadow placement.
struct Mix(u64);

impl Mix {
    fn new(seed: u64, frame: u64) -> Self {
        Self(seed ^ frame.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03)
    }

    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal (Box–Muller).
    fn normal(&mut self) -> f64 {
        let u = self.uniform().max(1e-12);
        let v = self.uniform();
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// The lighting of a camera stand-in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lighting {
    /// First pass.
    Day,
    /// Second pass.
    Night,
}

/// The camera stand-in of an intensity image under `lighting` (module docs).
pub fn camera_image(intensity: &GrayImage, lighting: Lighting, seed: u64, frame: u64) -> GrayImage {
    let (w, h) = intensity.dimensions();
    let mut rng = Mix::new(seed, frame);
    let mut gain = vec![1.0f64; w as usize];
    let mut glows: Vec<(f64, f64, f64)> = Vec::new();
    match lighting {
        Lighting::Day => {
            let shadows = 2 + (rng.next_u64() % 3) as usize;
            for _ in 0..shadows {
                let start = (rng.uniform() * f64::from(w)) as usize;
                let width = (0.03 + 0.07 * rng.uniform()) * f64::from(w);
                for k in 0..width as usize {
                    gain[(start + k) % w as usize] = 0.55;
                }
            }
        }
        Lighting::Night => {
            for _ in 0..2 + (rng.next_u64() % 2) {
                glows.push((
                    rng.uniform() * f64::from(w),
                    rng.uniform() * f64::from(h) * 0.5,
                    0.02 * f64::from(w) + 0.03 * f64::from(w) * rng.uniform(),
                ));
            }
        }
    }
    let sigma = if lighting == Lighting::Day { 3.0 } else { 10.0 };
    let mut out = GrayImage::new(w, h);
    for (x, y, p) in intensity.enumerate_pixels() {
        let v = f64::from(p.0[0]) / 255.0;
        let mut lit = match lighting {
            Lighting::Day => 255.0 * v * gain[x as usize],
            Lighting::Night => 255.0 * 0.5 * v.powf(2.2),
        };
        for &(cx, cy, r) in &glows {
            let d2 = ((f64::from(x) - cx) / r).powi(2) + ((f64::from(y) - cy) / (0.5 * r)).powi(2);
            lit += 90.0 * (-0.5 * d2).exp();
        }
        lit += sigma * rng.normal();
        out.put_pixel(x, y, image::Luma([lit.round().clamp(0.0, 255.0) as u8]));
    }
    out
}

/// Statistics of an 8-bit image; pixel value 0 counts as empty (no return).
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct ImageStats {
    /// Mean grey level of the non-empty pixels.
    pub mean: f64,
    /// Standard deviation of the non-empty pixels.
    pub std: f64,
    /// Share of empty pixels.
    pub empty_share: f64,
    /// 5th, 25th, 50th, 75th and 95th percentiles of the non-empty pixels.
    pub percentiles: [u8; 5],
}

/// Pooled statistics of several images.
pub fn image_stats<'a>(images: impl IntoIterator<Item = &'a GrayImage>) -> ImageStats {
    let mut hist = [0u64; 256];
    for img in images {
        for p in img.pixels() {
            hist[p.0[0] as usize] += 1;
        }
    }
    let total: u64 = hist.iter().sum();
    let filled: u64 = total - hist[0];
    if filled == 0 {
        return ImageStats {
            empty_share: if total > 0 { 1.0 } else { f64::NAN },
            mean: f64::NAN,
            std: f64::NAN,
            percentiles: [0; 5],
        };
    }
    let n = filled as f64;
    let mean = (1..256).map(|v| v as f64 * hist[v] as f64).sum::<f64>() / n;
    let var = (1..256)
        .map(|v| (v as f64 - mean).powi(2) * hist[v] as f64)
        .sum::<f64>()
        / n;
    let mut percentiles = [0u8; 5];
    for (k, q) in [0.05, 0.25, 0.5, 0.75, 0.95].into_iter().enumerate() {
        let target = (q * n).ceil().max(1.0) as u64;
        let mut acc = 0;
        for (v, &c) in hist.iter().enumerate().skip(1) {
            acc += c;
            if acc >= target {
                percentiles[k] = v as u8;
                break;
            }
        }
    }
    ImageStats {
        mean,
        std: var.sqrt(),
        empty_share: hist[0] as f64 / total as f64,
        percentiles,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stats_of_a_known_image() {
        let mut img = GrayImage::new(4, 1);
        for (x, v) in [0u8, 10, 20, 30].into_iter().enumerate() {
            img.put_pixel(x as u32, 0, image::Luma([v]));
        }
        let s = image_stats([&img]);
        assert!((s.mean - 20.0).abs() < 1e-12);
        assert!((s.empty_share - 0.25).abs() < 1e-12);
        assert_eq!(s.percentiles[2], 20);
    }

    #[test]
    fn night_is_darker_and_deterministic() {
        let img = GrayImage::from_fn(64, 16, |x, _| image::Luma([(x * 3 + 40) as u8]));
        let day = camera_image(&img, Lighting::Day, 7, 3);
        let night = camera_image(&img, Lighting::Night, 7, 3);
        assert_eq!(night, camera_image(&img, Lighting::Night, 7, 3));
        assert!(image_stats([&night]).mean < image_stats([&day]).mean);
    }
}
