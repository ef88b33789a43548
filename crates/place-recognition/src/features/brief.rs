//! The steered 512-bit BRIEF-like descriptor: a fixed random pattern of point pairs, rotated
//! by the keypoint's intensity-centroid orientation (Rublee et al., ICCV 2011).

use std::f32::consts::TAU;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::pyramid::Plane;
use crate::Bits512;

/// Number of point-pair tests, the descriptor dimension p = 512 (Khan 2017, §4.6.1).
pub(crate) const PAIRS: usize = 512;

/// Number of pre-rotated copies of the pattern (11.25° apart). A multiple of 4, so quarter
/// turns of the image map bins onto bins exactly.
pub(crate) const ANGLE_BINS: usize = 32;

/// Seed of the pattern. Fixed forever: changing it changes every descriptor.
const PATTERN_SEED: u64 = 0x4b68_616e_2032_3031; // "Khan 201"

/// The sampling pattern of one patch size, pre-rotated into [`ANGLE_BINS`] bins.
#[derive(Clone, Debug)]
pub(crate) struct Pattern {
    /// Patch radius `R`: every (rotated) offset has `|dx|, |dy| ≤ R`.
    pub radius: usize,
    /// `ANGLE_BINS × PAIRS` pairs `[dx1, dy1, dx2, dy2]`, bin-major.
    rotated: Vec<[i16; 4]>,
    /// Half-widths of the orientation disk per row offset `0..=R`.
    disk: Vec<i32>,
}

impl Pattern {
    /// The pattern for a `patch_size × patch_size` patch (`patch_size ≥ 7`): both points of
    /// each pair drawn from an isotropic Gaussian with σ = patch_size / 5 (BRIEF's G II, Calonder
    /// et al. 2010), redrawn outside the disk of radius `R = ⌊(patch_size − 1) / 2⌋` (so any
    /// rotation stays in the patch) or when the pair's points coincide.
    pub fn new(patch_size: usize) -> Self {
        let radius = (patch_size - 1) / 2;
        let r = radius as f32;
        let sigma = patch_size as f32 / 5.0;
        let mut rng = ChaCha8Rng::seed_from_u64(PATTERN_SEED);
        let draw = |rng: &mut ChaCha8Rng| loop {
            let (x, y) = gaussian_pair(rng);
            let (x, y) = ((x * sigma).round(), (y * sigma).round());
            if x * x + y * y <= r * r {
                return (x, y);
            }
        };
        let mut base = Vec::with_capacity(PAIRS);
        while base.len() < PAIRS {
            let a = draw(&mut rng);
            let b = draw(&mut rng);
            if a != b {
                base.push([a.0, a.1, b.0, b.1]);
            }
        }
        let mut rotated = Vec::with_capacity(ANGLE_BINS * PAIRS);
        for bin in 0..ANGLE_BINS {
            let (s, c) = (bin as f32 * TAU / ANGLE_BINS as f32).sin_cos();
            let rot = |x: f32, y: f32| {
                let rx = (c * x - s * y).round().clamp(-r, r) as i16;
                let ry = (s * x + c * y).round().clamp(-r, r) as i16;
                (rx, ry)
            };
            for p in &base {
                let (x1, y1) = rot(p[0], p[1]);
                let (x2, y2) = rot(p[2], p[3]);
                rotated.push([x1, y1, x2, y2]);
            }
        }
        let disk = (0..=radius as i32)
            .map(|dy| ((r * r - (dy * dy) as f32).max(0.0)).sqrt().floor() as i32)
            .collect();
        Self {
            radius,
            rotated,
            disk,
        }
    }

    /// Orientation of the patch around `(x, y)` by the intensity centroid: `θ = atan2(m01, m10)`
    /// with `m_pq = Σ x^p y^q I(x, y)` over the disk of radius `R` (ORB, Rublee et al. 2011).
    /// Image coordinates: x right, y down, so θ turns clockwise on screen.
    pub fn orientation(&self, img: &Plane, x: usize, y: usize) -> f32 {
        let w = img.width as isize;
        let centre = (y * img.width + x) as isize;
        let (mut m10, mut m01) = (0i64, 0i64);
        for (dy, &half) in self.disk.iter().enumerate() {
            let dy = dy as isize;
            for dx in -half as isize..=half as isize {
                let below = i64::from(img.pixels[(centre + dy * w + dx) as usize]);
                m10 += dx as i64 * below;
                if dy > 0 {
                    let above = i64::from(img.pixels[(centre - dy * w + dx) as usize]);
                    m10 += dx as i64 * above;
                    m01 += dy as i64 * (below - above);
                }
            }
        }
        (m01 as f32).atan2(m10 as f32)
    }

    /// The descriptor at `(x, y)` (at least `R` pixels from the border) of the smoothed level
    /// image: bit `i` is `I(q_i) < I(p_i)` for the `i`-th pair `(p_i, q_i)` rotated by `angle`.
    pub fn describe(&self, img: &Plane, x: usize, y: usize, angle: f32) -> Bits512 {
        let bin = (angle.rem_euclid(TAU) / TAU * ANGLE_BINS as f32).round() as usize % ANGLE_BINS;
        let pairs = &self.rotated[bin * PAIRS..(bin + 1) * PAIRS];
        let w = img.width as isize;
        let centre = (y * img.width + x) as isize;
        let at = |dx: i16, dy: i16| img.pixels[(centre + dy as isize * w + dx as isize) as usize];
        let mut d = Bits512::zeros();
        for (word, chunk) in d.0.iter_mut().zip(pairs.chunks_exact(64)) {
            let mut bits = 0u64;
            for (b, p) in chunk.iter().enumerate() {
                bits |= u64::from(at(p[2], p[3]) < at(p[0], p[1])) << b;
            }
            *word = bits;
        }
        d
    }
}

/// Two independent standard normal samples (Box–Muller).
fn gaussian_pair(rng: &mut ChaCha8Rng) -> (f32, f32) {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random();
    let r = (-2.0 * u1.ln()).sqrt();
    let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
    ((r * c) as f32, (r * s) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pattern_is_fixed_and_inside_the_patch() {
        let a = Pattern::new(31);
        let b = Pattern::new(31);
        assert_eq!(a.rotated, b.rotated);
        assert_eq!(a.radius, 15);
        assert!(a.rotated.iter().flatten().all(|&v| v.abs() <= 15));
        // Bin 0 is the unrotated pattern; a quarter turn maps (x, y) to (−y, x).
        let q = ANGLE_BINS / 4;
        for i in 0..PAIRS {
            let p = a.rotated[i];
            assert_eq!(a.rotated[q * PAIRS + i], [-p[1], p[0], -p[3], p[2]]);
        }
    }

    #[test]
    fn orientation_points_to_the_bright_side() {
        let (w, h) = (41, 41);
        let mut pixels = vec![0u8; w * h];
        for y in 0..h {
            for x in 21..w {
                pixels[y * w + x] = 255;
            }
        }
        let img = Plane {
            width: w,
            height: h,
            pixels,
        };
        let theta = Pattern::new(31).orientation(&img, 20, 20);
        assert!(theta.abs() < 1e-3, "{theta}");
    }
}
