//! Precision–recall curves as PNG (plotters on an RGB buffer, written with `image`): recall on
//! the horizontal axis, precision on the vertical, both 0–1 with grid lines every 0.1 and tick
//! labels every 0.2 (a built-in 3 × 5 pixel font: plotters is built without a font backend).
//! The legend (colour → method) is written in the report beside the picture.

use std::path::Path;

use anyhow::{Context, Result, anyhow};
use image::RgbImage;
use plotters::prelude::*;

/// Colours of the curves in order, with their names for the legend.
pub const PALETTE: [(&str, RGBColor); 12] = [
    ("blue", RGBColor(31, 91, 170)),
    ("orange", RGBColor(230, 120, 20)),
    ("green", RGBColor(40, 150, 60)),
    ("red", RGBColor(200, 40, 40)),
    ("purple", RGBColor(130, 80, 170)),
    ("brown", RGBColor(140, 90, 60)),
    ("pink", RGBColor(220, 110, 180)),
    ("grey", RGBColor(110, 110, 110)),
    ("olive", RGBColor(160, 160, 40)),
    ("cyan", RGBColor(30, 170, 190)),
    ("black", RGBColor(0, 0, 0)),
    ("light green", RGBColor(150, 220, 120)),
];

/// One curve: its label and `(recall, precision)` points in threshold order.
pub struct Curve {
    /// The method.
    pub label: String,
    /// `(recall, precision)` points.
    pub points: Vec<(f64, f64)>,
}

const WIDTH: u32 = 480;
const HEIGHT: u32 = 400;
const LEFT: i32 = 40;
const BOTTOM: i32 = 30;
const MARGIN: i32 = 12;

/// Draws the curves and writes the PNG.
pub fn write_pr_png(path: &Path, curves: &[Curve]) -> Result<()> {
    let mut buffer = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (WIDTH, HEIGHT)).into_drawing_area();
        let plot = root.margin(MARGIN, BOTTOM, LEFT, MARGIN);
        let mut chart = ChartBuilder::on(&plot)
            .build_cartesian_2d(0.0..1.0f64, 0.0..1.0f64)
            .map_err(|e| anyhow!("plot: {e}"))?;
        let grid = RGBColor(225, 225, 225);
        for k in 0..=10 {
            let v = f64::from(k) / 10.0;
            for line in [[(v, 0.0), (v, 1.0)], [(0.0, v), (1.0, v)]] {
                chart
                    .draw_series(LineSeries::new(line, &grid))
                    .map_err(|e| anyhow!("plot: {e}"))?;
            }
        }
        chart
            .draw_series(LineSeries::new(
                [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.0, 0.0)],
                &BLACK,
            ))
            .map_err(|e| anyhow!("plot: {e}"))?;
        for (k, curve) in curves.iter().enumerate() {
            let color = PALETTE[k % PALETTE.len()].1;
            chart
                .draw_series(LineSeries::new(
                    curve.points.iter().copied(),
                    color.stroke_width(2),
                ))
                .map_err(|e| anyhow!("plot: {e}"))?;
        }
        root.present().map_err(|e| anyhow!("plot: {e}"))?;
    }
    let mut img =
        RgbImage::from_raw(WIDTH, HEIGHT, buffer).ok_or_else(|| anyhow!("plot: buffer size"))?;
    tick_labels(&mut img);
    img.save(path)
        .with_context(|| format!("writing {}", path.display()))
}

/// The legend of a picture: "method (colour)" in curve order.
pub fn legend(curves: &[Curve]) -> String {
    curves
        .iter()
        .enumerate()
        .map(|(k, c)| format!("{} ({})", c.label, PALETTE[k % PALETTE.len()].0))
        .collect::<Vec<_>>()
        .join(", ")
}

/// 3 × 5 glyphs of digits and '.', rows top to bottom, 3 bits per row.
fn glyph(c: char) -> [u8; 5] {
    match c {
        '0' => [7, 5, 5, 5, 7],
        '1' => [2, 6, 2, 2, 7],
        '2' => [7, 1, 7, 4, 7],
        '4' => [5, 5, 7, 1, 1],
        '6' => [7, 4, 7, 5, 7],
        '8' => [7, 5, 7, 5, 7],
        '.' => [0, 0, 0, 0, 2],
        _ => [0; 5],
    }
}

/// Draws `text` at pixel `(x, y)` (top left), 2 × scaled.
fn text(img: &mut RgbImage, x: i32, y: i32, text: &str) {
    for (k, c) in text.chars().enumerate() {
        for (row, bits) in glyph(c).iter().enumerate() {
            for col in 0..3 {
                if bits >> (2 - col) & 1 == 1 {
                    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let px = x + 8 * k as i32 + 2 * col + dx;
                        let py = y + 2 * row as i32 + dy;
                        if px >= 0
                            && py >= 0
                            && (px as u32) < img.width()
                            && (py as u32) < img.height()
                        {
                            img.put_pixel(px as u32, py as u32, image::Rgb([0, 0, 0]));
                        }
                    }
                }
            }
        }
    }
}

/// Tick labels 0, 0.2, …, 1 on both axes.
fn tick_labels(img: &mut RgbImage) {
    let (x0, x1) = (LEFT, WIDTH as i32 - MARGIN);
    let (y0, y1) = (HEIGHT as i32 - BOTTOM, MARGIN);
    for k in 0..=5 {
        let v = f64::from(k) / 5.0;
        let label = match k {
            0 => "0".to_string(),
            5 => "1".to_string(),
            _ => format!("{v:.1}"),
        };
        let x = x0 + ((x1 - x0) as f64 * v) as i32;
        let y = y0 + ((y1 - y0) as f64 * v) as i32;
        let w = 8 * label.len() as i32;
        text(img, x - w / 2, y0 + 6, &label);
        text(img, x0 - w - 6, y - 5, &label);
    }
}
