//! Precision–recall curves as PNG (through [`crate::render`]): recall on the horizontal axis,
//! precision on the vertical, both 0–1 with grid lines every 0.1, tick and axis labels, and a
//! legend strip (colour → method) below the chart. The report also names the colours in
//! text beside the picture.

use std::path::Path;

use anyhow::{Context, Result};
use plotters::prelude::*;

use crate::render::canvas::{self, FONT};
use crate::render::legend::{self, Entry, Mark};

/// Colours of the curves in order, with their names for the text legend.
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

/// Width of the picture and height of the chart above the legend, in pixels.
const WIDTH: u32 = 520;
const CHART_H: u32 = 420;
/// Margin around the legend strip.
const LEGEND_PAD: u32 = 10;

/// The colour of curve `k`.
fn color(k: usize) -> RGBColor {
    PALETTE[k % PALETTE.len()].1
}

/// Draws the curves with axes and a legend and writes the PNG.
pub fn write_pr_png(path: &Path, curves: &[Curve]) -> Result<()> {
    let entries: Vec<Entry> = curves
        .iter()
        .enumerate()
        .map(|(k, c)| Entry::new(c.label.as_str(), color(k), Mark::Line))
        .collect();
    let legend_w = WIDTH - 2 * LEGEND_PAD;
    let legend_h = legend::height(&entries, legend_w);
    let height = CHART_H + legend_h + LEGEND_PAD;
    canvas::png(path, (WIDTH, height), |root| {
        root.fill(&WHITE).context("drawing the picture")?;
        let (plot, below) = root.split_vertically(CHART_H);
        let mut chart = ChartBuilder::on(&plot)
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(54)
            .build_cartesian_2d(0.0..1.0f64, 0.0..1.0f64)
            .context("drawing the chart")?;
        chart
            .configure_mesh()
            .x_labels(6)
            .y_labels(6)
            .max_light_lines(1)
            .bold_line_style(RGBColor(200, 200, 200))
            .light_line_style(RGBColor(235, 235, 235))
            .x_label_formatter(&|v| canvas::number(*v))
            .y_label_formatter(&|v| canvas::number(*v))
            .label_style((FONT, 15))
            .axis_desc_style((FONT, 16))
            .x_desc("recall")
            .y_desc("precision")
            .draw()
            .context("drawing the axes")?;
        for (k, curve) in curves.iter().enumerate() {
            chart
                .draw_series(LineSeries::new(
                    curve.points.iter().copied(),
                    color(k).stroke_width(2),
                ))
                .context("drawing a curve")?;
        }
        legend::draw(
            &below.margin(0, LEGEND_PAD, LEGEND_PAD, LEGEND_PAD),
            &entries,
        )
    })
}

/// The legend of a picture in text: "method (colour)" in curve order.
pub fn legend(curves: &[Curve]) -> String {
    curves
        .iter()
        .enumerate()
        .map(|(k, c)| format!("{} ({})", c.label, PALETTE[k % PALETTE.len()].0))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two curves give a picture taller than the chart (the legend strip), the same bytes
    /// twice, and pixels in the first curve's colour.
    #[test]
    fn pr_png_is_deterministic_with_a_legend() {
        let dir = tempfile::tempdir().unwrap();
        let curves = vec![
            Curve {
                label: "scan context".into(),
                points: vec![(0.0, 1.0), (0.5, 0.9), (1.0, 0.4)],
            },
            Curve {
                label: "M2DP".into(),
                points: vec![(0.0, 1.0), (0.3, 0.8), (0.9, 0.3)],
            },
        ];
        let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
        write_pr_png(&a, &curves).unwrap();
        write_pr_png(&b, &curves).unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        let img = image::open(&a).unwrap().to_rgb8();
        assert!(img.height() > CHART_H);
        let blue = PALETTE[0].1;
        assert!(img.pixels().any(|p| p.0 == [blue.0, blue.1, blue.2]));
    }
}
