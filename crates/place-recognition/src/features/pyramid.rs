//! Image pyramid levels and Gaussian smoothing for the feature detector.

/// An 8-bit image as a row-major buffer.
#[derive(Clone, Debug, Default)]
pub(crate) struct Plane {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<u8>,
}

impl Plane {
    /// Bilinear resampling to `1 / factor` of the size (`factor > 1`); the centre of destination
    /// pixel `x` samples the source at `(x + ½) · factor − ½`.
    pub fn downsample(&self, factor: f32) -> Plane {
        let width = (self.width as f32 / factor).floor() as usize;
        let height = (self.height as f32 / factor).floor() as usize;
        let mut pixels = Vec::with_capacity(width * height);
        // Source columns and weights are the same for every row: computed once.
        let columns: Vec<(usize, usize, f32)> = (0..width)
            .map(|x| source_taps(x, factor, self.width))
            .collect();
        for y in 0..height {
            let (y0, y1, fy) = source_taps(y, factor, self.height);
            let (top, bottom) = (self.row(y0), self.row(y1));
            pixels.extend(columns.iter().map(|&(x0, x1, fx)| {
                let t = f32::from(top[x0]) * (1.0 - fx) + f32::from(top[x1]) * fx;
                let b = f32::from(bottom[x0]) * (1.0 - fx) + f32::from(bottom[x1]) * fx;
                to_u8(t * (1.0 - fy) + b * fy)
            }));
        }
        Plane {
            width,
            height,
            pixels,
        }
    }

    /// Row `y` of the image.
    fn row(&self, y: usize) -> &[u8] {
        &self.pixels[y * self.width..(y + 1) * self.width]
    }

    /// Separable Gaussian smoothing with standard deviation `sigma` pixels (kernel radius
    /// ⌈3σ⌉, borders clamped). `scratch` is reused between calls.
    pub fn gaussian(&self, sigma: f32, scratch: &mut Vec<f32>) -> Plane {
        let kernel = gaussian_kernel(sigma);
        let r = (kernel.len() / 2) as isize;
        let (w, h) = (self.width, self.height);
        scratch.clear();
        scratch.resize(w * h, 0.0);
        let ru = r as usize;
        for y in 0..h {
            let row = &self.pixels[y * w..(y + 1) * w];
            let out = &mut scratch[y * w..(y + 1) * w];
            if w > 2 * ru {
                // Interior: one tap at a time over the whole row, so the loop vectorises (a
                // per-pixel dot product would be a serial chain of float additions).
                let interior = &mut out[ru..w - ru];
                for (k, &g) in kernel.iter().enumerate() {
                    for (o, &v) in interior.iter_mut().zip(&row[k..k + w - 2 * ru]) {
                        *o += g * f32::from(v);
                    }
                }
            }
            for x in (0..ru.min(w)).chain(w.saturating_sub(ru).max(ru.min(w))..w) {
                let mut acc = 0.0;
                for (k, &g) in kernel.iter().enumerate() {
                    let xx = (x as isize + k as isize - r).clamp(0, w as isize - 1) as usize;
                    acc += g * f32::from(row[xx]);
                }
                out[x] = acc;
            }
        }
        // Vertical pass row by row, accumulating whole rows (cache friendly).
        let mut pixels = vec![0u8; w * h];
        let mut acc = vec![0.0f32; w];
        for y in 0..h {
            acc.fill(0.0);
            for (k, &g) in kernel.iter().enumerate() {
                let yy = (y as isize + k as isize - r).clamp(0, h as isize - 1) as usize;
                let src = &scratch[yy * w..(yy + 1) * w];
                for (a, &v) in acc.iter_mut().zip(src) {
                    *a += g * v;
                }
            }
            for (p, &a) in pixels[y * w..(y + 1) * w].iter_mut().zip(&acc) {
                *p = to_u8(a);
            }
        }
        Plane {
            width: w,
            height: h,
            pixels,
        }
    }
}

/// The two source samples and the weight of the second for destination index `i` of a
/// resampling by `factor` (`(i + ½) · factor − ½`, clamped to the source).
fn source_taps(i: usize, factor: f32, len: usize) -> (usize, usize, f32) {
    let s = ((i as f32 + 0.5) * factor - 0.5).clamp(0.0, len.saturating_sub(1) as f32);
    let i0 = s.floor() as usize;
    (i0, (i0 + 1).min(len - 1), s - i0 as f32)
}

/// Rounds a grey value to 8 bits (`+ ½` and truncation: `f32::round` is a library call on
/// baseline x86-64).
#[inline]
fn to_u8(v: f32) -> u8 {
    (v.clamp(0.0, 255.0) + 0.5) as u8
}

/// Normalised Gaussian kernel of radius ⌈3σ⌉ (at least 1).
fn gaussian_kernel(sigma: f32) -> Vec<f32> {
    let r = (3.0 * sigma).ceil().max(1.0) as i32;
    let mut k: Vec<f32> = (-r..=r)
        .map(|i| (-(i * i) as f32 / (2.0 * sigma * sigma)).exp())
        .collect();
    let sum: f32 = k.iter().sum();
    for v in &mut k {
        *v /= sum;
    }
    k
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smoothing_keeps_flat_images_and_downsampling_halves() {
        let p = Plane {
            width: 9,
            height: 7,
            pixels: vec![100; 63],
        };
        let g = p.gaussian(2.0, &mut Vec::new());
        assert!(g.pixels.iter().all(|&v| v == 100));
        let d = p.downsample(2.0);
        assert_eq!((d.width, d.height), (4, 3));
        assert!(d.pixels.iter().all(|&v| v == 100));
    }

    #[test]
    fn smoothing_matches_a_direct_convolution() {
        let (w, h) = (23usize, 17usize);
        let pixels: Vec<u8> = (0..w * h).map(|i| ((i * 7919) % 251) as u8).collect();
        let p = Plane {
            width: w,
            height: h,
            pixels,
        };
        let sigma = 1.5;
        let g = p.gaussian(sigma, &mut Vec::new());
        let k = gaussian_kernel(sigma);
        let r = (k.len() / 2) as isize;
        let clamp = |v: isize, n: usize| v.clamp(0, n as isize - 1) as usize;
        for y in 0..h {
            for x in 0..w {
                let mut acc = 0.0f32;
                for (i, &gy) in k.iter().enumerate() {
                    for (j, &gx) in k.iter().enumerate() {
                        let yy = clamp(y as isize + i as isize - r, h);
                        let xx = clamp(x as isize + j as isize - r, w);
                        acc += gy * gx * f32::from(p.pixels[yy * w + xx]);
                    }
                }
                let got = f32::from(g.pixels[y * w + x]);
                assert!((got - acc).abs() <= 1.0, "({x}, {y}): {got} vs {acc}");
            }
        }
    }
}
