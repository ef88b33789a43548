//! Grouped bar charts (PNG, `image` crate) of ours vs OctoMap: one panel per data set, one
//! group of bars per resolution, a log₁₀ value axis with a grid line and label per decade.

use std::path::Path;

use anyhow::{Context, Result};
use image::{Rgb, RgbImage};

/// Bar colours: ours beam, OctoMap beam, ours end-point, OctoMap end-point.
pub const COLORS: [[u8; 3]; 4] = [
    [31, 91, 170],
    [230, 120, 20],
    [130, 180, 235],
    [250, 200, 140],
];

/// One panel: a data set's groups (one per resolution), each with up to four bar values
/// (`None` or non-positive = no bar).
pub struct Panel {
    /// Groups of bars, left to right, each with its label (digits, `.`, `e`, `-`).
    pub groups: Vec<(String, [Option<f64>; 4])>,
}

/// 3 × 5 glyphs of the digits, `e`, `-` and `.`, rows top to bottom, 3 bits per row.
fn glyph(c: char) -> [u8; 5] {
    match c {
        '0' => [7, 5, 5, 5, 7],
        '1' => [2, 6, 2, 2, 7],
        '2' => [7, 1, 7, 4, 7],
        '3' => [7, 1, 7, 1, 7],
        '4' => [5, 5, 7, 1, 1],
        '5' => [7, 4, 7, 1, 7],
        '6' => [7, 4, 7, 5, 7],
        '7' => [7, 1, 1, 1, 1],
        '8' => [7, 5, 7, 5, 7],
        '9' => [7, 5, 7, 1, 7],
        'e' => [0, 7, 7, 4, 7],
        '-' => [0, 0, 7, 0, 0],
        '.' => [0, 0, 0, 0, 2],
        _ => [0; 5],
    }
}

fn put(img: &mut RgbImage, x: i64, y: i64, color: [u8; 3]) {
    if x >= 0 && y >= 0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, Rgb(color));
    }
}

fn rect(img: &mut RgbImage, x0: i64, y0: i64, x1: i64, y1: i64, color: [u8; 3]) {
    for y in y0.min(y1)..y0.max(y1) {
        for x in x0.min(x1)..x0.max(x1) {
            put(img, x, y, color);
        }
    }
}

/// Draws `text` with its top-left corner at `(x, y)`, glyphs scaled by `scale`.
fn text(img: &mut RgbImage, x: i64, y: i64, scale: i64, s: &str) {
    for (i, c) in s.chars().enumerate() {
        let rows = glyph(c);
        for (r, bits) in rows.iter().enumerate() {
            for col in 0..3 {
                if bits & (4 >> col) != 0 {
                    let px = x + (i as i64 * 4 + col) * scale;
                    let py = y + r as i64 * scale;
                    rect(img, px, py, px + scale, py + scale, [0, 0, 0]);
                }
            }
        }
    }
}

/// Writes the chart to `path`.
pub fn bar_chart(path: &Path, panels: &[Panel]) -> Result<()> {
    let values: Vec<f64> = panels
        .iter()
        .flat_map(|p| p.groups.iter().flat_map(|g| g.1.iter().flatten().copied()))
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (d0, d1) = if lo.is_finite() && hi.is_finite() {
        let d0 = lo.log10().floor() as i32;
        (d0, (hi.log10().ceil() as i32).max(d0 + 1))
    } else {
        (0, 1)
    };
    let (bar_w, group_gap, panel_gap, left, top, plot_h, bottom) = (9i64, 10, 24, 44, 12, 260, 20);
    let panel_w: Vec<i64> = panels
        .iter()
        .map(|p| p.groups.len().max(1) as i64 * (4 * bar_w + group_gap) + group_gap)
        .collect();
    let width = left + panel_w.iter().sum::<i64>() + panel_gap * panels.len() as i64;
    let height = top + plot_h + bottom;
    let mut img = RgbImage::from_pixel(width as u32, height as u32, Rgb([255, 255, 255]));
    let y_of = |v: f64| {
        let f = (v.log10() - f64::from(d0)) / f64::from(d1 - d0);
        top + plot_h - (f.clamp(0.0, 1.0) * plot_h as f64).round() as i64
    };
    // Decade grid lines and labels.
    for d in d0..=d1 {
        let y = y_of(10f64.powi(d));
        rect(&mut img, left - 3, y, width, y + 1, [215, 215, 215]);
        text(&mut img, 2, y - 5, 2, &format!("1e{d}"));
    }
    let mut x0 = left;
    for (panel, w) in panels.iter().zip(&panel_w) {
        let base = top + plot_h;
        rect(&mut img, x0, top, x0 + 1, base, [0, 0, 0]);
        rect(&mut img, x0, base, x0 + w, base + 1, [0, 0, 0]);
        for (g, (label, bars)) in panel.groups.iter().enumerate() {
            let gx = x0 + group_gap + g as i64 * (4 * bar_w + group_gap);
            for (b, v) in bars.iter().enumerate() {
                let Some(v) = v.filter(|v| v.is_finite() && *v > 0.0) else {
                    continue;
                };
                let bx = gx + b as i64 * bar_w;
                rect(&mut img, bx, y_of(v), bx + bar_w - 1, base, COLORS[b % 4]);
            }
            let label_w = label.chars().count() as i64 * 8;
            text(&mut img, gx + 2 * bar_w - label_w / 2, base + 5, 2, label);
        }
        x0 += w + panel_gap;
    }
    img.save(path)
        .with_context(|| format!("writing {}", path.display()))
}
