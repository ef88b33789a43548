//! Grouped bar charts (PNG) of ours vs OctoMap: one panel per data set (three to a row), one
//! group of bars per resolution, a shared log₁₀ value axis with a grid line and a label per
//! decade, and the legend of the four bars above the panels.

use std::path::Path;

use anyhow::{Context, Result};
use plotters::prelude::*;

use crate::render::canvas::{self, FONT};
use crate::render::legend::{self, Entry, Mark};

/// Bar colours: ours beam, OctoMap beam, ours end-point, OctoMap end-point.
pub const COLORS: [RGBColor; 4] = [
    RGBColor(31, 91, 170),
    RGBColor(230, 120, 20),
    RGBColor(130, 180, 235),
    RGBColor(250, 200, 140),
];

/// What the four bars of a group are, in [`COLORS`] order.
const BARS: [&str; 4] = [
    "ours, beam-based",
    "OctoMap, beam-based",
    "ours, end-point",
    "OctoMap, end-point",
];

/// Panels in a row, and the size of a panel in pixels.
const COLUMNS: usize = 3;
const PANEL: (u32, u32) = (330, 250);

/// One panel: a data set's groups (one per resolution), each with up to four bar values
/// (`None` or non-positive = no bar).
pub struct Panel {
    /// Groups of bars, left to right, each with its label (the resolution in metres).
    pub groups: Vec<(String, [Option<f64>; 4])>,
}

/// Writes the chart of `panels` (titled with `names`, in order) to `path`; `y_label` names the
/// plotted value.
pub fn bar_chart(path: &Path, y_label: &str, names: &[&str], panels: &[Panel]) -> Result<()> {
    let decades = decades(panels);
    let entries: Vec<Entry> = BARS
        .iter()
        .zip(COLORS)
        .map(|(label, color)| Entry::new(*label, color, Mark::Swatch))
        .collect();
    let columns = panels.len().clamp(1, COLUMNS);
    let rows = panels.len().div_ceil(COLUMNS).max(1);
    let width = columns as u32 * PANEL.0;
    let top = legend::height(&entries, width - 20) + 8;
    let size = (width, top + rows as u32 * PANEL.1);
    canvas::png(path, size, |root| {
        let (head, body) = root.split_vertically(top);
        legend::draw(&head.margin(6, 0, 20, 0), &entries)?;
        let cells = body.split_evenly((rows, columns));
        for (k, (panel, area)) in panels.iter().zip(&cells).enumerate() {
            let labels = Labels {
                title: names.get(k).copied().unwrap_or(""),
                x: (k + columns >= panels.len()).then_some("resolution r (m)"),
                y: (k % columns == 0).then_some(y_label),
            };
            draw_panel(area, panel, decades, &labels)?;
        }
        Ok(())
    })
}

/// The texts of a panel: its title and its axis labels (`None`: not on this panel).
struct Labels<'a> {
    title: &'a str,
    x: Option<&'a str>,
    y: Option<&'a str>,
}

/// The decades `(d0, d1)` spanned by the positive finite values (at least one).
fn decades(panels: &[Panel]) -> (i32, i32) {
    let values = panels
        .iter()
        .flat_map(|p| p.groups.iter().flat_map(|g| g.1.iter().flatten().copied()))
        .filter(|v| v.is_finite() && *v > 0.0);
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if !lo.is_finite() {
        return (0, 1);
    }
    let d0 = lo.log10().floor() as i32;
    (d0, (hi.log10().ceil() as i32).max(d0 + 1))
}

/// `10ⁿ` for a power of ten, with the exponent in superscript digits.
fn power_of_ten(v: f64) -> String {
    let exponent = format!("{}", v.log10().round() as i32);
    let sup: String = exponent
        .chars()
        .map(|c| match c {
            '-' => '⁻',
            d => ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹']
                [d.to_digit(10).unwrap_or(0) as usize],
        })
        .collect();
    format!("10{sup}")
}

/// One panel: bars of the groups over the decades `(d0, d1)`.
fn draw_panel(
    area: &canvas::PngArea,
    panel: &Panel,
    (d0, d1): (i32, i32),
    labels: &Labels,
) -> Result<()> {
    let n = panel.groups.len().max(1);
    // Just beyond the decades, so that rounding keeps both ends' labels.
    let (lo, hi) = (0.999 * 10f64.powi(d0), 1.001 * 10f64.powi(d1));
    let mut chart = ChartBuilder::on(area)
        .caption(labels.title, (FONT, 16))
        .margin(6)
        .margin_right(12)
        .x_label_area_size(if labels.x.is_some() { 46 } else { 26 })
        .y_label_area_size(if labels.y.is_some() { 62 } else { 44 })
        .build_cartesian_2d(-0.5..n as f64 - 0.5, (lo..hi).log_scale())
        .context("drawing a panel")?;
    let group_label = |x: &f64| {
        let g = x.round();
        (g >= 0.0 && (x - g).abs() < 1e-6)
            .then(|| panel.groups.get(g as usize).map(|group| group.0.clone()))
            .flatten()
            .unwrap_or_default()
    };
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(n)
        .y_labels((d1 - d0 + 1) as usize)
        .y_max_light_lines(0)
        .bold_line_style(RGBColor(220, 220, 220))
        .x_label_formatter(&group_label)
        .y_label_formatter(&|v| power_of_ten(*v))
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 14))
        .x_desc(labels.x.unwrap_or(""))
        .y_desc(labels.y.unwrap_or(""))
        .draw()
        .context("drawing a panel's axes")?;
    const BAR_W: f64 = 0.2;
    for (g, (_, bars)) in panel.groups.iter().enumerate() {
        for (b, value) in bars.iter().enumerate() {
            let Some(v) = value.filter(|v| v.is_finite() && *v > 0.0) else {
                continue;
            };
            let x0 = g as f64 + (b as f64 - 2.0) * BAR_W;
            chart
                .draw_series([Rectangle::new(
                    [(x0 + 0.01, lo), (x0 + BAR_W - 0.01, v)],
                    COLORS[b % COLORS.len()].filled(),
                )])
                .context("drawing the bars")?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn panels() -> Vec<Panel> {
        let group =
            |r: &str, v: f64| (r.to_owned(), [Some(v), Some(2.0 * v), None, Some(f64::NAN)]);
        vec![
            Panel {
                groups: vec![group("0.1", 50_000.0), group("0.2", 8_000.0)],
            },
            Panel {
                groups: vec![group("0.1", 3.0), group("0.2", 0.5)],
            },
        ]
    }

    #[test]
    fn chart_is_written_and_decodes() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("leaves.png");
        bar_chart(&path, "leaves", &["a", "b"], &panels()).expect("chart");
        let image = image::open(&path).expect("decodes").to_rgb8();
        assert_eq!(image.width(), 2 * PANEL.0);
        assert!(image.height() > PANEL.1);
        for color in COLORS.iter().take(2) {
            let RGBColor(r, g, b) = *color;
            assert!(image.pixels().any(|p| p.0 == [r, g, b]), "{color:?}");
        }
        // Text (tick labels, titles, legend) is drawn: dark pixels outside the bars.
        assert!(
            image
                .pixels()
                .filter(|p| p.0[0] < 60 && p.0[2] < 60)
                .count()
                > 500
        );
    }

    #[test]
    fn same_input_same_bytes() {
        let dir = tempfile::tempdir().expect("temp dir");
        let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
        bar_chart(&a, "leaves", &["a", "b"], &panels()).expect("chart");
        bar_chart(&b, "leaves", &["a", "b"], &panels()).expect("chart");
        assert_eq!(std::fs::read(a).expect("a"), std::fs::read(b).expect("b"));
    }

    #[test]
    fn decades_span_the_values() {
        assert_eq!(decades(&panels()), (-1, 5));
        assert_eq!(decades(&[]), (0, 1));
        assert_eq!(power_of_ten(1e-3), "10⁻³");
        assert_eq!(power_of_ten(100.0), "10²");
    }
}
