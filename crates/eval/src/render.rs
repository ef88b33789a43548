//! Pictures for evaluation reports, drawn with plotters: top-down hit maps with overlays,
//! colours, and the canvas (PNG or SVG, embedded font) every figure is drawn on.

pub mod canvas;
mod colors;
pub mod legend;
mod top_down;

pub use colors::{PALETTE, colormap, hex, label_color};
pub use top_down::TopDown;
