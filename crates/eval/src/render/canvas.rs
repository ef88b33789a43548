//! Where figures are drawn: plotters on an RGB buffer that `image` writes as PNG, or on an SVG
//! string. Text is set in DejaVu Sans, embedded and registered with plotters once, so no system
//! font is needed and the same inputs give the same bytes on every machine.

use std::path::Path;
use std::sync::Once;

use anyhow::{Context, Result, anyhow};
use image::RgbImage;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::register_font;

/// The font family of every text in a figure.
pub const FONT: &str = "sans-serif";

/// Registers DejaVu Sans as [`FONT`] (once per process). Should it fail, the first text drawn
/// reports the missing font as an error.
pub fn register() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let _ = register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
    });
}

/// Text of `size` pixels in [`FONT`] and `color`.
pub fn text_style(size: u32, color: RGBColor) -> TextStyle<'static> {
    (FONT, size).into_font().color(&color)
}

/// A PNG drawing area.
pub type PngArea<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// An SVG drawing area.
pub type SvgArea<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// Draws a `size` (width, height) picture on white with `draw` and writes it to `path` as PNG.
pub fn png(path: &Path, size: (u32, u32), draw: impl FnOnce(&PngArea) -> Result<()>) -> Result<()> {
    register();
    let mut buffer = vec![255u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, size).into_drawing_area();
        draw(&root)?;
        root.present().context("drawing the picture")?;
    }
    let image =
        RgbImage::from_raw(size.0, size.1, buffer).ok_or_else(|| anyhow!("picture buffer size"))?;
    image
        .save(path)
        .with_context(|| format!("writing {}", path.display()))
}

/// Draws a `size` (width, height) picture on white with `draw` and returns the SVG document.
pub fn svg(size: (u32, u32), draw: impl FnOnce(&SvgArea) -> Result<()>) -> Result<String> {
    register();
    let mut document = String::new();
    {
        let root = SVGBackend::with_string(&mut document, size).into_drawing_area();
        root.fill(&WHITE).context("drawing the picture")?;
        draw(&root)?;
        root.present().context("drawing the picture")?;
    }
    document.push('\n');
    Ok(document)
}

/// A tick label: `v` with at most three decimals, trailing zeros dropped (`-0` as `0`).
pub fn number(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}
