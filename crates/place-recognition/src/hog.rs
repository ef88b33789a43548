//! Histogram of oriented gradients over a whole image as a global descriptor
//! (Khan 2017, §4.5.2, after Dalal & Triggs, CVPR 2005, without the classifier).
//!
//! 1. Optional Gaussian pre-smoothing with standard deviation σ (pixels).
//! 2. Centred gradients `e_x(x, y) = I(x+1, y) − I(x−1, y)`, `e_y(x, y) = I(x, y+1) − I(x, y−1)`
//!    on intensities scaled to `[0, 1]`.
//! 3. Unsigned orientation `θ = atan(e_y / e_x) ∈ [0, π)` and magnitude `γ = √(e_x² + e_y²)`.
//! 4. Magnitude-weighted orientation histograms per cell of `L × L` pixels.
//! 5. Blocks of `2 × 2` cells with a stride of one cell; each block's cell histograms are
//!    concatenated and L2-normalised, `v / √(‖v‖² + ε²)`.
//! 6. All blocks concatenated (block rows top to bottom, left to right within a row; cells
//!    row-major within a block; bins in order of angle) give the descriptor.
//!
//! ## Decisions (the thesis gives no values)
//!
//! * Defaults (ours, after Dalal & Triggs): 9 unsigned bins, `2 × 2`-cell blocks, stride 1 cell,
//!   `L = 16` px (the thesis sweeps none; 16 px gives 4 cell rows on a 64-row lidar image),
//!   σ = 1 px, ε = 10⁻³.
//! * Bin `b` is centred at `θ = b·π/B`; a vote is shared linearly between the two nearest bins
//!   (cyclically, so θ near π also votes for bin 0). A vertical edge (horizontal gradient,
//!   θ = 0) votes into bin 0 only. No spatial (trilinear) interpolation between cells.
//! * `y` grows downwards (image rows); for unsigned orientations this only mirrors the bin
//!   order of oblique edges.
//! * Image borders repeat the edge pixel (for the smoothing and the gradients). Pixels beyond
//!   the last whole cell (right and bottom) are ignored. An image with fewer cells than a
//!   block in either direction is an error. A constant image gives the zero vector.

use image::GrayImage;

use crate::{PlaceError, Result};

/// HOG parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct HogConfig {
    /// Cell side `L` in pixels. Default 16 (ours).
    pub cell_size: u32,
    /// Standard deviation σ of the Gaussian pre-smoothing, pixels; 0 = none. Default 1 (ours).
    pub sigma: f64,
    /// Unsigned orientation bins over `[0, π)`. Default 9 (Dalal & Triggs).
    pub bins: usize,
    /// Block side in cells. Default 2 (Dalal & Triggs).
    pub block_cells: u32,
    /// Block stride in cells. Default 1 (Dalal & Triggs).
    pub block_stride: u32,
    /// ε of the block normalisation `v / √(‖v‖² + ε²)`. Default 10⁻³ (ours).
    pub epsilon: f32,
}

impl Default for HogConfig {
    fn default() -> Self {
        Self {
            cell_size: 16,
            sigma: 1.0,
            bins: 9,
            block_cells: 2,
            block_stride: 1,
            epsilon: 1e-3,
        }
    }
}

impl HogConfig {
    fn validate(&self) -> Result<()> {
        let positive = [
            ("cell_size", self.cell_size as usize),
            ("bins", self.bins),
            ("block_cells", self.block_cells as usize),
            ("block_stride", self.block_stride as usize),
        ];
        for (name, value) in positive {
            if value == 0 {
                return Err(PlaceError::InvalidParameter {
                    name,
                    reason: "must be at least 1".into(),
                });
            }
        }
        if !(self.sigma.is_finite() && self.sigma >= 0.0) {
            return Err(PlaceError::InvalidParameter {
                name: "sigma",
                reason: format!("must be finite and non-negative, got {}", self.sigma),
            });
        }
        if !(self.epsilon.is_finite() && self.epsilon >= 0.0) {
            return Err(PlaceError::InvalidParameter {
                name: "epsilon",
                reason: format!("must be finite and non-negative, got {}", self.epsilon),
            });
        }
        Ok(())
    }

    /// Cells and blocks along an image side of `n` pixels.
    fn layout(&self, n: u32) -> (usize, usize) {
        let cells = (n / self.cell_size) as usize;
        let (bc, bs) = (self.block_cells as usize, self.block_stride as usize);
        let blocks = if cells >= bc {
            (cells - bc) / bs + 1
        } else {
            0
        };
        (cells, blocks)
    }

    /// Length of the descriptor of a `width × height` image (0 if the image is too small).
    pub fn descriptor_len(&self, width: u32, height: u32) -> usize {
        let (_, bx) = self.layout(width);
        let (_, by) = self.layout(height);
        let per_block = (self.block_cells * self.block_cells) as usize * self.bins;
        bx * by * per_block
    }
}

/// Separable Gaussian smoothing with a radius of ⌈3σ⌉ and repeated borders.
pub(crate) fn gaussian_blur(data: &[f32], w: usize, h: usize, sigma: f64) -> Vec<f32> {
    let radius = (3.0 * sigma).ceil() as i64;
    let kernel: Vec<f32> = (-radius..=radius)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp() as f32)
        .collect();
    let total: f32 = kernel.iter().sum();
    let kernel: Vec<f32> = kernel.iter().map(|k| k / total).collect();
    let mut tmp = vec![0.0f32; w * h];
    let mut out = vec![0.0f32; w * h];
    let (wi, hi) = (w as i64, h as i64);
    for y in 0..h {
        let row = &data[y * w..(y + 1) * w];
        for x in 0..w {
            let mut acc = 0.0;
            for (k, &kv) in kernel.iter().enumerate() {
                let xs = (x as i64 + k as i64 - radius).clamp(0, wi - 1) as usize;
                acc += kv * row[xs];
            }
            tmp[y * w + x] = acc;
        }
    }
    for y in 0..h {
        for x in 0..w {
            let mut acc = 0.0;
            for (k, &kv) in kernel.iter().enumerate() {
                let ys = (y as i64 + k as i64 - radius).clamp(0, hi - 1) as usize;
                acc += kv * tmp[ys * w + x];
            }
            out[y * w + x] = acc;
        }
    }
    out
}

/// Magnitude-weighted orientation histograms of the `cells_x × cells_y` cells.
fn cell_histograms(
    img: &[f32],
    w: usize,
    h: usize,
    cfg: &HogConfig,
    cells: (usize, usize),
) -> Vec<f32> {
    let (cells_x, cells_y) = cells;
    let (l, bins) = (cfg.cell_size as usize, cfg.bins);
    let bin_width = std::f32::consts::PI / bins as f32;
    let mut hist = vec![0.0f32; cells_x * cells_y * bins];
    for y in 0..cells_y * l {
        let (up, down) = (y.saturating_sub(1), (y + 1).min(h - 1));
        let cell_row = (y / l) * cells_x;
        for x in 0..cells_x * l {
            let (left, right) = (x.saturating_sub(1), (x + 1).min(w - 1));
            let ex = img[y * w + right] - img[y * w + left];
            let ey = img[down * w + x] - img[up * w + x];
            let magnitude = (ex * ex + ey * ey).sqrt();
            if magnitude == 0.0 {
                continue;
            }
            let theta = ey.atan2(ex).rem_euclid(std::f32::consts::PI);
            let position = theta / bin_width;
            let lower = position.floor();
            let frac = position - lower;
            let b0 = (lower as usize) % bins;
            let b1 = (b0 + 1) % bins;
            let cell = (cell_row + x / l) * bins;
            hist[cell + b0] += magnitude * (1.0 - frac);
            hist[cell + b1] += magnitude * frac;
        }
    }
    hist
}

/// The HOG descriptor of an image (Khan 2017, §4.5.2); its length is
/// [`HogConfig::descriptor_len`].
pub fn hog(image: &GrayImage, config: &HogConfig) -> Result<Vec<f32>> {
    config.validate()?;
    let (w, h) = (image.width() as usize, image.height() as usize);
    let ((cells_x, blocks_x), (cells_y, blocks_y)) =
        (config.layout(image.width()), config.layout(image.height()));
    if blocks_x == 0 || blocks_y == 0 {
        return Err(PlaceError::BadInput(format!(
            "hog: a {w} × {h} image has fewer than {b} × {b} cells of {l} px",
            b = config.block_cells,
            l = config.cell_size
        )));
    }
    let mut data: Vec<f32> = image
        .as_raw()
        .iter()
        .map(|&v| f32::from(v) / 255.0)
        .collect();
    if config.sigma > 0.0 {
        data = gaussian_blur(&data, w, h, config.sigma);
    }
    let hist = cell_histograms(&data, w, h, config, (cells_x, cells_y));
    let (bins, bc, bs) = (
        config.bins,
        config.block_cells as usize,
        config.block_stride as usize,
    );
    let eps2 = config.epsilon * config.epsilon;
    let mut out = Vec::with_capacity(config.descriptor_len(image.width(), image.height()));
    for by in 0..blocks_y {
        for bx in 0..blocks_x {
            let start = out.len();
            for cy in by * bs..by * bs + bc {
                for cx in bx * bs..bx * bs + bc {
                    let cell = (cy * cells_x + cx) * bins;
                    out.extend_from_slice(&hist[cell..cell + bins]);
                }
            }
            let block = &mut out[start..];
            let norm2: f32 = block.iter().map(|v| v * v).sum();
            let scale = 1.0 / (norm2 + eps2).sqrt();
            if norm2 > 0.0 {
                block.iter_mut().for_each(|v| *v *= scale);
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_image_gives_zero() {
        let img = GrayImage::from_pixel(64, 32, image::Luma([77]));
        let d = hog(&img, &HogConfig::default()).unwrap();
        assert_eq!(d.len(), HogConfig::default().descriptor_len(64, 32));
        assert_eq!(d.len(), 3 * 36); // 4 × 2 cells → 3 × 1 blocks of 36
        assert!(d.iter().all(|&v| v == 0.0));
    }

    #[test]
    fn vertical_edge_peaks_in_bin_zero_and_horizontal_in_the_middle() {
        let cfg = HogConfig {
            sigma: 0.0,
            ..HogConfig::default()
        };
        let vertical =
            GrayImage::from_fn(32, 32, |x, _| image::Luma([if x < 15 { 0 } else { 200 }]));
        let d = hog(&vertical, &cfg).unwrap();
        assert_eq!(d.len(), 36);
        let mut bins = [0.0f32; 9];
        for (i, v) in d.iter().enumerate() {
            bins[i % 9] += v;
        }
        assert!(bins[0] > 0.0);
        assert!(bins[1..].iter().all(|&b| b == 0.0), "{bins:?}");
        // A horizontal edge: θ = π/2 lies between bins 4 (80°) and 5 (100°).
        let horizontal =
            GrayImage::from_fn(32, 32, |_, y| image::Luma([if y < 15 { 0 } else { 200 }]));
        let d = hog(&horizontal, &HogConfig::default()).unwrap();
        let mut bins = [0.0f32; 9];
        for (i, v) in d.iter().enumerate() {
            bins[i % 9] += v;
        }
        assert!(
            (bins[4] - bins[5]).abs() < 1e-5 && bins[4] > 0.0,
            "{bins:?}"
        );
        assert!(
            bins.iter()
                .enumerate()
                .all(|(i, &b)| i == 4 || i == 5 || b < 1e-6)
        );
    }

    #[test]
    fn blocks_are_unit_length_and_small_images_are_errors() {
        let img = GrayImage::from_fn(70, 40, |x, y| image::Luma([((x * 7 + y * 13) % 256) as u8]));
        let cfg = HogConfig {
            cell_size: 8,
            ..HogConfig::default()
        };
        let d = hog(&img, &cfg).unwrap();
        assert_eq!(d.len(), 7 * 4 * 36); // 8 × 5 cells → 7 × 4 blocks
        for block in d.chunks(36) {
            let n: f32 = block.iter().map(|v| v * v).sum();
            assert!((n - 1.0).abs() < 1e-3, "{n}");
        }
        assert!(hog(&GrayImage::new(31, 64), &HogConfig::default()).is_err());
        let zero = HogConfig {
            cell_size: 0,
            ..HogConfig::default()
        };
        assert!(hog(&img, &zero).is_err());
    }
}
