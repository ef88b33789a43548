//! ROS `map_server` maps (PGM + YAML) and PNG pictures of 2-D maps.
//!
//! Format: the ROS `map_server` map format (<https://wiki.ros.org/map_server>, "Map format"):
//! an 8-bit grayscale image whose top row is the map's largest y, and a YAML file with
//! `image`, `resolution` (metres per pixel), `origin` (`[x, y, yaw]` of the lower-left
//! pixel), `negate`, `occupied_thresh`, `free_thresh` and `mode`. With `negate: 0` a pixel
//! value `x` means the probability `p = (255 − x) / 255`; we write
//! `x = round(255 · (1 − p))` and unknown cells as 205 (what `map_saver` writes; it reads
//! back as unknown in trinary mode with the default thresholds).

use std::path::{Path, PathBuf};

use raypath_geometry::Grid2;
use serde::{Deserialize, Serialize};

use crate::stats::{CellStats, DenseStats2};
use crate::{LogOddsConfig, SensorModelError};

/// Pixel value of unknown cells.
pub const UNKNOWN_PIXEL: u8 = 205;

/// What probability a 2-D map picture shows per cell.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum MapPicture {
    /// Reflection probability `μ = H / (H + M)` (Eq. 7.22).
    Reflection,
    /// Decay rate shown as the probability that a ray crossing one cell edge `c` of the
    /// cell is reflected: `p = 1 − exp(−λ c)` with `λ = H / R` (Eq. 7.10).
    DecayRate,
    /// Log-odds occupancy probability (OctoMap update, [`LogOddsConfig`] defaults).
    Occupancy,
}

/// The per-cell probabilities a picture shows (`None`: unknown cell).
pub fn picture_values(stats: &DenseStats2, picture: MapPicture) -> Vec<Option<f64>> {
    let c = stats.grid().cell_size();
    stats
        .cells()
        .iter()
        .map(|cell| picture_value(cell, picture, c))
        .collect()
}

/// The probability a picture shows for one cell of edge `cell_m` in 2-D or 3-D (`None`:
/// unknown cell).
pub fn picture_value(cell: &CellStats, picture: MapPicture, cell_m: f64) -> Option<f64> {
    match picture {
        MapPicture::Reflection => {
            let n = cell.h() + cell.m();
            (n > 0.0).then(|| cell.h() / n)
        }
        MapPicture::DecayRate => {
            let r = cell.path_length_m();
            (r > 0.0).then(|| -(-(cell.h() / r) * cell_m).exp_m1())
        }
        MapPicture::Occupancy => {
            (cell.hits() > 0 || cell.misses() > 0).then(|| LogOddsConfig::default().occupancy(cell))
        }
    }
}

/// The `map_server` YAML fields besides the image name, resolution and origin.
///
/// Defaults are `map_saver`'s: `occupied_thresh = 0.65`, `free_thresh = 0.196`,
/// `negate = false`, `mode = trinary`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RosMapOptions {
    /// Probability above which a cell is occupied.
    pub occupied_thresh: f64,
    /// Probability below which a cell is free.
    pub free_thresh: f64,
    /// Invert the meaning of pixel values (we always write `negate: 0` images; `true` only
    /// changes the YAML flag for viewers that expect it).
    pub negate: bool,
    /// `trinary`, `scale` or `raw`.
    pub mode: String,
}

impl Default for RosMapOptions {
    fn default() -> Self {
        Self {
            occupied_thresh: 0.65,
            free_thresh: 0.196,
            negate: false,
            mode: "trinary".into(),
        }
    }
}

/// The image rows (top row = largest y) of per-cell probabilities.
pub fn map_image(grid: &Grid2, values: &[Option<f64>]) -> Result<Vec<u8>, SensorModelError> {
    if values.len() != grid.num_cells() {
        return Err(SensorModelError::GridMismatch {
            reason: format!("{} values for {} cells", values.len(), grid.num_cells()),
        });
    }
    let [width, height] = grid.dims();
    let mut pixels = Vec::with_capacity(width * height);
    for row in (0..height).rev() {
        for col in 0..width {
            let value = values.get(row * width + col).copied().flatten();
            pixels.push(match value {
                Some(p) if p.is_finite() => (255.0 * (1.0 - p.clamp(0.0, 1.0))).round() as u8,
                _ => UNKNOWN_PIXEL,
            });
        }
    }
    Ok(pixels)
}

/// Writes `PREFIX.pgm` (binary P5) and `PREFIX.yaml` for `map_server`; returns both paths.
pub fn write_ros_map(
    prefix: &Path,
    grid: &Grid2,
    values: &[Option<f64>],
    options: &RosMapOptions,
) -> Result<(PathBuf, PathBuf), SensorModelError> {
    let pixels = map_image(grid, values)?;
    let [width, height] = grid.dims();
    let pgm_path = prefix.with_extension("pgm");
    let yaml_path = prefix.with_extension("yaml");
    let mut pgm = format!("P5\n# raypath map\n{width} {height}\n255\n").into_bytes();
    pgm.extend_from_slice(&pixels);
    std::fs::write(&pgm_path, pgm).map_err(|e| SensorModelError::io(&pgm_path, e))?;
    let image_name = pgm_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let origin = grid.origin();
    let yaml = format!(
        "image: {image_name}\nresolution: {}\norigin: [{}, {}, 0.0]\nnegate: {}\noccupied_thresh: {}\nfree_thresh: {}\nmode: {}\n",
        grid.cell_size(),
        origin.x,
        origin.y,
        u8::from(options.negate),
        options.occupied_thresh,
        options.free_thresh,
        options.mode,
    );
    std::fs::write(&yaml_path, yaml).map_err(|e| SensorModelError::io(&yaml_path, e))?;
    Ok((pgm_path, yaml_path))
}

/// Writes a grayscale PNG picture (same pixels as the PGM: dark = high probability,
/// gray 205 = unknown, top = largest y).
pub fn write_png(
    path: &Path,
    grid: &Grid2,
    values: &[Option<f64>],
) -> Result<(), SensorModelError> {
    let pixels = map_image(grid, values)?;
    let [width, height] = grid.dims();
    let image_error = |reason: String| SensorModelError::Image {
        name: path.display().to_string(),
        reason,
    };
    let (w, h) = (
        u32::try_from(width).map_err(|_| image_error("image too wide".into()))?,
        u32::try_from(height).map_err(|_| image_error("image too tall".into()))?,
    );
    let image = image::GrayImage::from_raw(w, h, pixels)
        .ok_or_else(|| image_error("pixel buffer does not match the size".into()))?;
    image
        .save_with_format(path, image::ImageFormat::Png)
        .map_err(|e| image_error(e.to_string()))
}
