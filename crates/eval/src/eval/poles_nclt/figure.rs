//! SVG map of the semi-NCLT campus: the real path, the real poles, the windows the sessions
//! drive and the reference map's poles (world frame, x right, y up, metres, equal scales), with
//! axes in metres and the legend below.

use anyhow::{Context, Result};
use nalgebra::Point2;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use crate::render::PALETTE;
use crate::render::canvas::{self, FONT};
use crate::render::legend::{self, Entry, Mark};

/// Pixels per metre, metres of padding around the data, and the pixels of the axes.
const SCALE: f64 = 1.2;
const PAD_M: f64 = 10.0;
const LEFT: u32 = 70;
const RIGHT: u32 = 16;
const TOP: u32 = 12;
const BOTTOM: u32 = 50;

const PATH: RGBColor = RGBColor(200, 200, 200);
const POLE: RGBColor = RGBColor(68, 68, 68);
const MAP: RGBColor = RGBColor(214, 39, 40);

/// What the figure shows.
pub(super) struct CampusFigure<'a> {
    /// The real path.
    pub path: &'a [Point2<f64>],
    /// The real poles.
    pub poles: &'a [Point2<f64>],
    /// Per session: its label and the positions it drives.
    pub sessions: Vec<(String, Vec<Point2<f64>>)>,
    /// The reference map's poles.
    pub map: Vec<Point2<f64>>,
}

impl CampusFigure<'_> {
    /// The SVG document (1.2 px per metre plus the axes and the legend).
    ///
    /// # Panics
    ///
    /// Never: drawing into a string cannot fail once the embedded font is registered.
    pub fn svg(&self) -> String {
        let (lo, hi) = self.bounds();
        let plot = (
            ((hi.x - lo.x) * SCALE).round() as u32,
            ((hi.y - lo.y) * SCALE).round() as u32,
        );
        let entries = self.entries();
        let legend_h = legend::height(&entries, plot.0 + RIGHT);
        let size = (LEFT + plot.0 + RIGHT, TOP + plot.1 + BOTTOM + legend_h + 6);
        canvas::svg(size, |root| {
            let (chart_area, legend_area) = root.split_vertically(TOP + plot.1 + BOTTOM);
            let mut chart = ChartBuilder::on(&chart_area)
                .margin_top(TOP)
                .margin_right(RIGHT)
                .x_label_area_size(BOTTOM)
                .y_label_area_size(LEFT)
                .build_cartesian_2d(lo.x..hi.x, lo.y..hi.y)
                .context("drawing the campus")?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_label_formatter(&|v| canvas::number(*v))
                .y_label_formatter(&|v| canvas::number(*v))
                .label_style((FONT, 16))
                .axis_desc_style((FONT, 17))
                .x_desc("x (m)")
                .y_desc("y (m)")
                .draw()
                .context("drawing the axes")?;
            self.draw_data(&mut chart)?;
            legend::draw(&legend_area.margin(6, 0, LEFT, 0), &entries)
        })
        .expect("an SVG drawn into a string with the font registered cannot fail")
    }

    /// The corners of the figure: path and poles, padded (a unit square for no data).
    fn bounds(&self) -> (Point2<f64>, Point2<f64>) {
        let (mut lo, mut hi) = (
            Point2::new(f64::MAX, f64::MAX),
            Point2::new(f64::MIN, f64::MIN),
        );
        for p in self.path.iter().chain(self.poles) {
            if p.x.is_finite() && p.y.is_finite() {
                lo = lo.inf(p);
                hi = hi.sup(p);
            }
        }
        if lo.x > hi.x {
            (lo, hi) = (Point2::origin(), Point2::new(1.0, 1.0));
        }
        let pad = nalgebra::Vector2::new(PAD_M, PAD_M);
        (lo - pad, hi + pad)
    }

    /// The legend: path, poles, map, then the sessions in their colours.
    fn entries(&self) -> Vec<Entry> {
        let fixed = [
            Entry::new("real NCLT path", PATH, Mark::Line),
            Entry::new("real poles", POLE, Mark::Dot),
            Entry::new("reference map poles", MAP, Mark::Ring),
        ];
        let sessions = self.sessions.iter().enumerate().map(|(k, (label, _))| {
            Entry::new(
                format!("session {label}"),
                PALETTE[k % PALETTE.len()],
                Mark::Line,
            )
        });
        fixed.into_iter().chain(sessions).collect()
    }

    /// Path, session windows, poles and map poles, in that order (later on top).
    fn draw_data(
        &self,
        chart: &mut ChartContext<SVGBackend, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    ) -> Result<()> {
        let xy = |p: &Point2<f64>| (p.x, p.y);
        chart
            .draw_series(LineSeries::new(
                self.path.iter().map(xy),
                PATH.stroke_width(3),
            ))
            .context("drawing the path")?;
        for (k, (_, points)) in self.sessions.iter().enumerate() {
            let colour = PALETTE[k % PALETTE.len()].mix(0.8);
            chart
                .draw_series(LineSeries::new(
                    points.iter().map(xy),
                    colour.stroke_width(2),
                ))
                .context("drawing a session")?;
        }
        chart
            .draw_series(
                self.poles
                    .iter()
                    .map(|p| Circle::new(xy(p), 1.5, POLE.filled())),
            )
            .context("drawing the poles")?;
        chart
            .draw_series(
                self.map
                    .iter()
                    .map(|p| Circle::new(xy(p), 3, MAP.stroke_width(1))),
            )
            .context("drawing the map")?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn figure_svg() -> String {
        let path = [Point2::new(0.0, 0.0), Point2::new(100.0, 50.0)];
        let poles = [Point2::new(10.0, 10.0), Point2::new(50.0, 20.0)];
        CampusFigure {
            path: &path,
            poles: &poles,
            sessions: vec![("2012-01-08".into(), path.to_vec())],
            map: vec![poles[0]],
        }
        .svg()
    }

    #[test]
    fn svg_holds_every_element() {
        let dir = tempfile::tempdir().expect("temp dir");
        let file = dir.path().join("campus.svg");
        std::fs::write(&file, figure_svg()).expect("written");
        let svg = std::fs::read_to_string(&file).expect("read");
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        // 120 m × 70 m at 1.2 px/m plus the axes.
        let (w, h) = (LEFT + 144 + RIGHT, TOP + 84 + BOTTOM);
        assert!(svg.contains(&format!(r#"width="{w}""#)), "{svg}");
        assert!(
            !svg.contains(&format!(r#"height="{h}""#)),
            "the legend adds height"
        );
        // Path and session, each drawn and in the legend; two poles, one map pole, and the
        // legend's dot and ring.
        assert_eq!(svg.matches(r##"stroke="#C8C8C8""##).count(), 2, "{svg}");
        assert_eq!(svg.matches(r##"stroke="#1F77B4""##).count(), 2, "{svg}");
        assert_eq!(svg.matches("<circle").count(), 5);
        for text in ["session 2012-01-08", "real poles", "x (m)", "y (m)"] {
            assert!(svg.contains(text), "{text}");
        }
    }

    #[test]
    fn same_input_same_bytes() {
        assert_eq!(figure_svg(), figure_svg());
    }
}
