//! Outputs users can open elsewhere: the occupancy map as PGM + YAML (the ROS `map_server`
//! format), the reflectivity map as PNG, and trajectories in the TUM format.
//!
//! * PGM (binary `P5`): free cells (P < 0.196) 254, occupied (P > 0.65) 0, unknown 205, the
//!   first image row at the top (largest y). Cropped to the observed cells plus a margin.
//! * YAML: `image`, `resolution` (m/cell), `origin` `[x, y, yaw]` of the lower-left pixel,
//!   `negate: 0`, `occupied_thresh: 0.65`, `free_thresh: 0.196`.
//! * Reflectivity PNG: 8-bit grey `255 · ϱ̄ / ϱ̄_max` of observed cells (ϱ̄_max the 99th
//!   percentile), unobserved cells black.
//! * TUM (Sturm et al., IROS 2012): `t x y z qx qy qz qw` per line, z = 0, the rotation about
//!   z as a unit quaternion.

use std::fmt::Write as _;
use std::path::Path;

use crate::error::{ReflectivityError, Result};
use crate::grid::{GridLevel, probability};

/// The index box `[i0, j0, i1, j1)` (half-open) of the observed cells (non-zero log-odds)
/// plus `margin` cells, clipped to the grid; `None` when no cell is observed.
pub fn observed_box(level: &GridLevel, margin: usize) -> Option<[usize; 4]> {
    let (mut i0, mut j0, mut i1, mut j1) = (usize::MAX, usize::MAX, 0, 0);
    for j in 0..level.height() {
        for i in 0..level.width() {
            if level.log_odds(i, j) != 0.0 {
                i0 = i0.min(i);
                j0 = j0.min(j);
                i1 = i1.max(i + 1);
                j1 = j1.max(j + 1);
            }
        }
    }
    (i1 > 0).then(|| {
        [
            i0.saturating_sub(margin),
            j0.saturating_sub(margin),
            (i1 + margin).min(level.width()),
            (j1 + margin).min(level.height()),
        ]
    })
}

fn io_error(path: &Path, e: impl std::fmt::Display) -> ReflectivityError {
    ReflectivityError::BadInput(format!("{}: {e}", path.display()))
}

/// Writes `<prefix>.pgm` and `<prefix>.yaml` for `level`; returns the image size.
pub fn write_occupancy_map(level: &GridLevel, prefix: &Path) -> Result<(usize, usize)> {
    let [i0, j0, i1, j1] = observed_box(level, 10).unwrap_or([0, 0, 1, 1]);
    let (w, h) = (i1 - i0, j1 - j0);
    let mut bytes = format!("P5\n{w} {h}\n255\n").into_bytes();
    bytes.reserve(w * h);
    for j in (j0..j1).rev() {
        for i in i0..i1 {
            let l = level.log_odds(i, j);
            let p = probability(l);
            bytes.push(if l == 0.0 {
                205
            } else if p > 0.65 {
                0
            } else if p < 0.196 {
                254
            } else {
                205
            });
        }
    }
    let pgm = prefix.with_extension("pgm");
    std::fs::write(&pgm, bytes).map_err(|e| io_error(&pgm, e))?;
    let res = level.resolution_m();
    let origin = level.origin();
    let mut yaml = String::new();
    let name = pgm
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let _ = writeln!(yaml, "image: {name}");
    let _ = writeln!(yaml, "resolution: {res}");
    let _ = writeln!(
        yaml,
        "origin: [{}, {}, 0.0]",
        origin[0] + i0 as f64 * res,
        origin[1] + j0 as f64 * res
    );
    let _ = writeln!(yaml, "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196");
    let path = prefix.with_extension("yaml");
    std::fs::write(&path, yaml).map_err(|e| io_error(&path, e))?;
    Ok((w, h))
}

/// Writes the reflectivity of `level` as an 8-bit grey PNG (same crop as the PGM); returns
/// `false` (and writes nothing) when the map has no reflectivity.
pub fn write_reflectivity_png(level: &GridLevel, path: &Path) -> Result<bool> {
    if !level.has_reflectivity() {
        return Ok(false);
    }
    let [i0, j0, i1, j1] = observed_box(level, 10).unwrap_or([0, 0, 1, 1]);
    let mut values: Vec<f32> = (j0..j1)
        .flat_map(|j| (i0..i1).map(move |i| (i, j)))
        .filter_map(|(i, j)| level.cell_reflectivity(i, j).map(|(m, _)| m))
        .collect();
    values.sort_by(f32::total_cmp);
    let top = values
        .get(values.len().saturating_sub(1) * 99 / 100)
        .copied()
        .unwrap_or(1.0)
        .max(1e-6);
    let (w, h) = (i1 - i0, j1 - j0);
    let mut img = image::GrayImage::new(w as u32, h as u32);
    for (row, j) in (j0..j1).rev().enumerate() {
        for (col, i) in (i0..i1).enumerate() {
            let v = level.cell_reflectivity(i, j).map_or(0, |(m, _)| {
                (255.0 * (m / top).clamp(0.0, 1.0)).round() as u8
            });
            img.put_pixel(col as u32, row as u32, image::Luma([v]));
        }
    }
    img.save(path).map_err(|e| io_error(path, e))?;
    Ok(true)
}
