//! A picture of a scan and its polylines as SVG (scan frame, x right, y up, metres, equal
//! scales), with axes in metres and a legend below; drawn with plotters (feature `svg`).

use std::sync::Once;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::register_font;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use raypath_geometry::Scan2;

use crate::Polylines;

/// The font family of the picture's text (DejaVu Sans, embedded: no system font is needed).
const FONT: &str = "sans-serif";
/// Pixels of the axes around the plot: left, right, top, bottom; a legend row's height.
const LEFT: u32 = 64;
const RIGHT: u32 = 16;
const TOP: u32 = 12;
const BOTTOM: u32 = 48;
const ROW: u32 = 24;
/// The legend's entries.
const ENTRIES: [&str; 4] = ["sensor", "measured endpoints", "polylines", "vertices"];

const SENSOR: RGBColor = RGBColor(0, 0, 0);
const ENDPOINT: RGBColor = RGBColor(153, 153, 153);
const LINE: RGBColor = RGBColor(31, 95, 191);
const VERTEX: RGBColor = RGBColor(214, 39, 40);

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;
type Drawn<'a> = Result<(), DrawingAreaErrorKind<<SVGBackend<'a> as DrawingBackend>::ErrorType>>;

/// An SVG picture whose plot is `size_px` on its longer side, showing the sensor (black
/// cross), the measured endpoints (grey dots) and the polylines (blue, vertices as red dots),
/// with x and y axes in metres and a legend.
///
/// # Panics
///
/// Never: drawing into a string cannot fail once the embedded font is registered.
pub fn scan_svg(scan: &Scan2, map: &Polylines, size_px: f64) -> String {
    let endpoints: Vec<(f64, f64)> = (0..scan.len())
        .filter_map(|k| {
            scan.range(k).hit().map(|r| {
                let a = scan.angle(k);
                (r * a.cos(), r * a.sin())
            })
        })
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    let (x, y) = bounds(&endpoints, map);
    let scale = size_px.max(1.0) / (x.end - x.start).max(y.end - y.start);
    let plot = (
        ((x.end - x.start) * scale).round() as u32,
        ((y.end - y.start) * scale).round() as u32,
    );
    register();
    let legend = legend_layout(plot.0 + RIGHT);
    let size = (
        LEFT + plot.0 + RIGHT,
        TOP + plot.1 + BOTTOM + rows_px(&legend),
    );
    let mut document = String::new();
    draw(&mut document, size, (x, y), &endpoints, map, &legend)
        .expect("an SVG drawn into a string with the font registered cannot fail");
    document.push('\n');
    document
}

/// Registers DejaVu Sans as [`FONT`] (once per process).
fn register() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let _ = register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
    });
}

/// The plotted region: the endpoints, the vertices and the sensor, with 5 % margins.
fn bounds(
    endpoints: &[(f64, f64)],
    map: &Polylines,
) -> (std::ops::Range<f64>, std::ops::Range<f64>) {
    let vertices = map.vertices().map(|v| (v.x, v.y));
    let points = endpoints
        .iter()
        .copied()
        .chain(vertices)
        .chain([(0.0, 0.0)]);
    let (mut x0, mut x1, mut y0, mut y1) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (x, y) in points.filter(|p| p.0.is_finite() && p.1.is_finite()) {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    let margin = 0.05 * (x1 - x0).max(y1 - y0).max(1.0);
    (x0 - margin..x1 + margin, y0 - margin..y1 + margin)
}

/// Draws the picture of `size` pixels into `document`.
fn draw(
    document: &mut String,
    size: (u32, u32),
    (x, y): (std::ops::Range<f64>, std::ops::Range<f64>),
    endpoints: &[(f64, f64)],
    map: &Polylines,
    legend: &[(i32, u32)],
) -> Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::with_string(document, size).into_drawing_area();
    root.fill(&WHITE)?;
    let (chart_area, legend_area) = root.split_vertically(size.1 - rows_px(legend));
    let mut chart = ChartBuilder::on(&chart_area)
        .margin_top(TOP)
        .margin_right(RIGHT)
        .x_label_area_size(BOTTOM)
        .y_label_area_size(LEFT)
        .build_cartesian_2d(x, y)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_label_formatter(&|v| number(*v))
        .y_label_formatter(&|v| number(*v))
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 15))
        .x_desc("x (m)")
        .y_desc("y (m)")
        .draw()?;
    draw_data(&mut chart, endpoints, map)?;
    draw_legend(&legend_area.margin(0, 0, LEFT, 0), legend)?;
    root.present()?;
    Ok(())
}

/// Endpoints, polylines, vertices and the sensor, in that order (later on top).
fn draw_data<'b>(
    chart: &mut Chart<'_, 'b>,
    endpoints: &[(f64, f64)],
    map: &Polylines,
) -> Drawn<'b> {
    chart.draw_series(
        endpoints
            .iter()
            .map(|&p| Circle::new(p, 1.5, ENDPOINT.filled())),
    )?;
    for line in &map.lines {
        let mut points: Vec<(f64, f64)> = line.vertices.iter().map(|v| (v.x, v.y)).collect();
        if line.closed {
            points.extend(points.first().copied());
        }
        chart.draw_series(LineSeries::new(points, LINE.stroke_width(2)))?;
    }
    let vertices = map
        .vertices()
        .map(|v| Circle::new((v.x, v.y), 2.5, VERTEX.filled()));
    chart.draw_series(vertices)?;
    chart.draw_series([Cross::new((0.0, 0.0), 5, SENSOR.stroke_width(2))])?;
    Ok(())
}

/// Where the legend's entries go within `width` pixels: `(x, row)` each, left to right,
/// wrapped into rows.
fn legend_layout(width: u32) -> Vec<(i32, u32)> {
    let (mut x, mut row) = (0, 0);
    let mut out = Vec::new();
    for label in ENTRIES {
        let text = (FONT, 14)
            .into_font()
            .box_size(label)
            .map_or(120, |(w, _)| w as i32);
        let w = 22 + text + 18;
        if x > 0 && x + w > width as i32 {
            (x, row) = (0, row + 1);
        }
        out.push((x, row));
        x += w;
    }
    out
}

/// The height of the legend laid out as `layout`.
fn rows_px(layout: &[(i32, u32)]) -> u32 {
    layout.iter().map(|e| e.1 + 1).max().unwrap_or(0) * ROW
}

/// The legend: a mark and a label per kind of element, at the places of `layout`.
fn draw_legend<'a>(area: &Area<'a>, layout: &[(i32, u32)]) -> Drawn<'a> {
    let style = TextStyle::from((FONT, 14).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
    for (k, (label, &(x, row))) in ENTRIES.iter().zip(layout).enumerate() {
        let y = (row * ROW + ROW / 2) as i32;
        let centre = (x + 8, y);
        match k {
            0 => area.draw(&Cross::new(centre, 5, SENSOR.stroke_width(2)))?,
            1 => area.draw(&Circle::new(centre, 2, ENDPOINT.filled()))?,
            2 => area.draw(&PathElement::new(
                [(x, y), (x + 16, y)],
                LINE.stroke_width(2),
            ))?,
            _ => area.draw(&Circle::new(centre, 3, VERTEX.filled()))?,
        }
        area.draw(&Text::new(*label, (x + 22, y), style.clone()))?;
    }
    Ok(())
}

/// A tick label: at most three decimals, trailing zeros dropped (`-0` as `0`).
fn number(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

#[cfg(test)]
mod tests {
    use nalgebra::Point2;

    use super::*;
    use crate::Polyline;

    /// Three beams hitting a wall 2 m ahead and the wall as one polyline.
    fn picture() -> String {
        let scan = Scan2 {
            angle_min_rad: -0.2,
            angle_increment_rad: 0.2,
            max_range_m: 30.0,
            ranges: vec![2.0 / 0.2f64.cos(), 2.0, f64::NAN],
            intensities: None,
        };
        let map = Polylines {
            lines: vec![Polyline {
                vertices: vec![Point2::new(2.0, -0.5), Point2::new(2.0, 0.5)],
                rays: vec![0, 1],
                closed: false,
            }],
        };
        scan_svg(&scan, &map, 300.0)
    }

    #[test]
    fn legend_wraps_into_rows_that_fit() {
        register();
        assert_eq!(rows_px(&legend_layout(2000)), ROW);
        assert_eq!(rows_px(&legend_layout(1)), 4 * ROW);
    }

    #[test]
    fn picture_holds_axes_points_and_legend() {
        let svg = picture();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        // 2 endpoints + 2 vertices, and the legend's 2 dots.
        assert_eq!(svg.matches("<circle").count(), 6, "{svg}");
        for text in ["x (m)", "y (m)", "measured endpoints", "vertices"] {
            assert!(svg.contains(text), "{text}");
        }
        // The longer side (x: 0 … 2 m plus margins) is 300 px.
        assert!(
            svg.contains(&format!(r#"width="{}""#, LEFT + 300 + RIGHT)),
            "{svg}"
        );
    }

    #[test]
    fn same_input_same_bytes() {
        assert_eq!(picture(), picture());
    }
}
