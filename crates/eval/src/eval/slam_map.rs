//! The map picture of `cargo xtask eval slam`: the finished submaps' finest levels painted at
//! their optimised poses (grey unknown, white free, black occupied; later submaps over
//! earlier ones where both are confident), and in red the cells where two submaps of
//! different visits disagree ([`raypath_slam::benchmark::disagreement_points`]).

use std::path::Path;

use anyhow::{Context, Result};
use raypath_slam::SlamOutput;

/// Pixel size of the picture, metres.
const PIXEL_M: f64 = 0.1;
/// Largest picture side, pixels.
const MAX_SIDE: usize = 4000;

/// Writes the map of `out` as a PNG, the cells where its submaps disagree in red.
pub fn write_png(out: &SlamOutput, path: &Path) -> Result<()> {
    // World positions of every submap's observed cells (log-odds, world x, world y).
    let mut cells: Vec<(f32, f64, f64)> = Vec::new();
    for s in &out.submaps {
        let (Some(pose), Some(level)) = (out.nodes.get(s.anchor()), s.levels().first()) else {
            continue;
        };
        let (res, o) = (level.resolution_m(), level.origin());
        for j in (0..level.height()).step_by(2) {
            for i in (0..level.width()).step_by(2) {
                let l = level.log_odds(i, j);
                if l == 0.0 {
                    continue;
                }
                let p = *pose
                    * nalgebra::Point2::new(
                        o[0] + (i as f64 + 0.5) * res,
                        o[1] + (j as f64 + 0.5) * res,
                    );
                cells.push((l, p.x, p.y));
            }
        }
    }
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for &(_, x, y) in &cells {
        x0 = x0.min(x);
        y0 = y0.min(y);
        x1 = x1.max(x);
        y1 = y1.max(y);
    }
    if cells.is_empty() {
        (x0, y0, x1, y1) = (0.0, 0.0, 1.0, 1.0);
    }
    let w = (((x1 - x0) / PIXEL_M) as usize + 1).min(MAX_SIDE);
    let h = (((y1 - y0) / PIXEL_M) as usize + 1).min(MAX_SIDE);
    // Sum of clamped log-odds per pixel.
    let mut sum = vec![0f32; w * h];
    for &(l, x, y) in &cells {
        let i = (((x - x0) / PIXEL_M) as usize).min(w - 1);
        let j = (((y1 - y) / PIXEL_M) as usize).min(h - 1);
        sum[j * w + i] += l.clamp(-2.0, 4.0);
    }
    let mut red = vec![false; w * h];
    for p in raypath_slam::benchmark::disagreement_points(out) {
        if (x0..=x1).contains(&p.x) && (y0..=y1).contains(&p.y) {
            let i = (((p.x - x0) / PIXEL_M) as usize).min(w - 1);
            let j = (((y1 - p.y) / PIXEL_M) as usize).min(h - 1);
            red[j * w + i] = true;
        }
    }
    // Four colours in a palette: the pictures stay as small as grey ones.
    let pixels: Vec<u8> = sum
        .iter()
        .zip(&red)
        .map(|(&v, &r)| match (r, v) {
            (true, _) => 3,
            (false, v) if v > 1.0 => 0,
            (false, v) if v < -0.5 => 1,
            _ => 2,
        })
        .collect();
    let file =
        std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w as u32, h as u32);
    encoder.set_color(png::ColorType::Indexed);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_palette(vec![0, 0, 0, 255, 255, 255, 200, 200, 200, 220, 0, 0]);
    encoder
        .write_header()
        .and_then(|mut writer| writer.write_image_data(&pixels))
        .with_context(|| format!("writing {}", path.display()))
}
