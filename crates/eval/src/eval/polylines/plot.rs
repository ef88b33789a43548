//! Line charts (SVG) of the Fig. 10.4 curves: a metric's mean ± standard error against the
//! number of vertices, one curve per extractor, the legend on the right and an optional dashed
//! reference line.

use anyhow::{Context, Result};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::render::canvas::{self, FONT};
use crate::render::hex;
use crate::render::legend::{self, Entry, Mark};

/// Size of a chart and width of its legend column, in pixels.
const SIZE: (u32, u32) = (640, 400);
const LEGEND_W: u32 = 130;

/// One curve: label, colour, and `(x, mean, standard error)` points.
pub struct Series {
    /// The extractor.
    pub label: String,
    /// Its colour as `#rrggbb`.
    pub color: &'static str,
    /// `(x, mean, standard error)`; non-finite means are left out.
    pub points: Vec<(f64, f64, f64)>,
}

/// A chart with a title, axis labels, tick labels, error bars, a legend and an optional dashed
/// reference line `(value, label)`; the SVG document.
///
/// # Panics
///
/// Never: drawing into a string cannot fail once the embedded font is registered.
pub fn line_chart(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    reference: Option<(f64, &str)>,
) -> String {
    canvas::svg(SIZE, |root| {
        let (plot, side) = root.split_horizontally(SIZE.0 - LEGEND_W);
        let (x, y) = ranges(series, reference);
        let mut chart = ChartBuilder::on(&plot)
            .caption(title, (FONT, 21))
            .margin(10)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .build_cartesian_2d(x, y)
            .context("drawing the chart")?;
        let xs = series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.0.to_bits()));
        let distinct = xs.collect::<std::collections::BTreeSet<u64>>().len();
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(distinct.clamp(2, 10))
            .y_max_light_lines(0)
            .bold_line_style(RGBColor(221, 221, 221))
            .x_label_formatter(&|v| canvas::number(*v))
            .y_label_formatter(&|v| canvas::number(*v))
            .label_style((FONT, 16))
            .axis_desc_style((FONT, 17))
            .x_desc(x_label)
            .y_desc(y_label)
            .draw()
            .context("drawing the axes")?;
        if let Some((value, label)) = reference {
            draw_reference(&mut chart, value, label)?;
        }
        for s in series {
            draw_series(&mut chart, s)?;
        }
        let entries: Vec<Entry> = series
            .iter()
            .map(|s| Entry::new(s.label.as_str(), hex(s.color), Mark::Line))
            .collect();
        legend::draw(&side.margin(40, 0, 0, 0), &entries)
    })
    .expect("an SVG drawn into a string with the font registered cannot fail")
}

type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The axes' ranges: the x values padded by 5 %, the y values (error bars and reference
/// included) from 0 or below, padded by 5 % at the top.
fn ranges(
    series: &[Series],
    reference: Option<(f64, &str)>,
) -> (std::ops::Range<f64>, std::ops::Range<f64>) {
    let finite = |p: &&(f64, f64, f64)| p.0.is_finite() && p.1.is_finite();
    let points = || series.iter().flat_map(|s| s.points.iter().filter(finite));
    let span = |values: &mut dyn Iterator<Item = f64>| {
        values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        })
    };
    let (x0, x1) = span(&mut points().map(|p| p.0));
    let (x0, x1) = if x1 > x0 {
        (x0, x1)
    } else if x0.is_finite() {
        (x0 - 1.0, x0 + 1.0)
    } else {
        (0.0, 1.0)
    };
    let pad = 0.05 * (x1 - x0);
    let err = |p: &(f64, f64, f64)| if p.2.is_finite() { p.2.max(0.0) } else { 0.0 };
    let (y0, y1) = span(
        &mut points()
            .flat_map(|p| [p.1 - err(p), p.1 + err(p)])
            .chain(reference.map(|r| r.0).filter(|v| v.is_finite())),
    );
    let (y0, y1) = if y1 > y0.min(0.0) {
        (y0.min(0.0), y1)
    } else {
        (0.0, 1.0)
    };
    (x0 - pad..x1 + pad, y0..y1 + 0.05 * (y1 - y0))
}

/// The dashed horizontal reference line with its label above its left end.
fn draw_reference(chart: &mut Chart, value: f64, label: &str) -> Result<()> {
    let grey = RGBColor(68, 68, 68);
    let (x0, x1) = (chart.x_range().start, chart.x_range().end);
    chart
        .draw_series(DashedLineSeries::new(
            [(x0, value), (x1, value)],
            6,
            4,
            grey.into(),
        ))
        .context("drawing the reference")?;
    let style = canvas::text_style(15, grey).pos(Pos::new(HPos::Left, VPos::Bottom));
    chart
        .draw_series([EmptyElement::at((x0, value)) + Text::new(label.to_owned(), (4, -3), style)])
        .context("drawing the reference")?;
    Ok(())
}

/// A curve: mean line, points and error bars.
fn draw_series(chart: &mut Chart, series: &Series) -> Result<()> {
    let color = hex(series.color);
    let points: Vec<(f64, f64, f64)> = series
        .points
        .iter()
        .copied()
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    chart
        .draw_series(LineSeries::new(
            points.iter().map(|p| (p.0, p.1)),
            color.stroke_width(2),
        ))
        .context("drawing a curve")?;
    chart
        .draw_series(
            points
                .iter()
                .map(|p| Circle::new((p.0, p.1), 3, color.filled())),
        )
        .context("drawing a curve")?;
    let bars = points.iter().filter(|p| p.2.is_finite() && p.2 > 0.0);
    chart
        .draw_series(bars.map(|p| ErrorBar::new_vertical(p.0, p.1 - p.2, p.1, p.1 + p.2, color, 6)))
        .context("drawing the error bars")?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chart() -> String {
        let series = [
            Series {
                label: "PLE+".into(),
                color: "#1f77b4",
                points: vec![(10.0, 2.0, 0.1), (20.0, 1.5, 0.2), (30.0, f64::NAN, 0.0)],
            },
            Series {
                label: "VVL".into(),
                color: "#2ca02c",
                points: vec![(10.0, 3.0, 0.0), (20.0, 2.5, f64::NAN)],
            },
        ];
        line_chart(
            "RMSE",
            "number of vertices J",
            "RMSE (mm)",
            &series,
            Some((1.0, "thesis")),
        )
    }

    #[test]
    fn chart_holds_curves_axes_and_legend() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("sim-rmse.svg");
        std::fs::write(&path, chart()).expect("written");
        let svg = std::fs::read_to_string(&path).expect("read");
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains(r#"width="640" height="400""#));
        for text in [
            "RMSE (mm)",
            "number of vertices J",
            "PLE+",
            "VVL",
            "thesis",
            "\n20\n",
        ] {
            assert!(svg.contains(text), "{text}");
        }
        // Each curve: its line, its legend mark, and for PLE+ two error bars (the NaN mean and
        // the NaN error are left out); the dots of the
        // 4 finite means and the 2 error bars' centres.
        assert!(svg.matches(r##"stroke="#1F77B4""##).count() >= 4, "{svg}");
        assert_eq!(svg.matches(r##"stroke="#2CA02C""##).count(), 2, "{svg}");
        assert_eq!(svg.matches(r##"<circle"##).count(), 6, "{svg}");
        assert_eq!(svg.matches(r##"fill="#2CA02C""##).count(), 2, "{svg}");
    }

    #[test]
    fn same_input_same_bytes() {
        assert_eq!(chart(), chart());
    }
}
