//! PNG rendering of decay-rate maps as `p_ref = 1 − exp(−λ)` (Sec. 9.5.1): the probability
//! that a ray is reflected within 1 m of a medium of rate `λ`, coloured like the thesis's
//! figures (blue 0, green 0.5, yellow 1).

use std::path::Path;

use crate::DctError;

/// `p_ref = 1 − e^{−λ}` (Sec. 9.5.1).
#[inline]
pub fn p_ref(rate_per_m: f64) -> f64 {
    -(-rate_per_m).exp_m1()
}

/// The colour of `p ∈ [0, 1]`: blue → green → yellow.
pub fn colour(p: f64) -> [u8; 3] {
    let p = if p.is_finite() {
        p.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (a, b, t) = if p < 0.5 {
        ([0.16, 0.20, 0.75], [0.13, 0.70, 0.35], p / 0.5)
    } else {
        ([0.13, 0.70, 0.35], [0.98, 0.90, 0.10], (p - 0.5) / 0.5)
    };
    let mix = |k: usize| ((a[k] + (b[k] - a[k]) * t) * 255.0).round() as u8;
    [mix(0), mix(1), mix(2)]
}

/// Writes an `nx × ny` lattice of rates (row-major `ix · ny + iy`, x to the right, y up)
/// as a PNG of `p_ref`, each cell `scale × scale` pixels.
pub fn write_p_ref_png(
    path: &Path,
    rates: &[f64],
    nx: usize,
    ny: usize,
    scale: u32,
) -> Result<(), DctError> {
    if rates.len() != nx * ny || nx == 0 || ny == 0 {
        return Err(DctError::InvalidParameter {
            name: "rates",
            reason: format!("{} rates for a {nx} × {ny} lattice", rates.len()),
        });
    }
    let s = scale.max(1);
    let (w, h) = (nx as u32 * s, ny as u32 * s);
    let img = image::RgbImage::from_fn(w, h, |px, py| {
        let ix = (px / s) as usize;
        let iy = ny - 1 - (py / s) as usize;
        image::Rgb(colour(p_ref(
            rates.get(ix * ny + iy).copied().unwrap_or(0.0),
        )))
    });
    img.save(path).map_err(|e| DctError::Io {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })
}
