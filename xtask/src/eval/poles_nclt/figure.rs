//! SVG map of the semi-NCLT campus: the real path, the real poles, the windows the sessions
//! drive and the reference map's poles (world frame, x right, y up, metres).

use std::fmt::Write;

use nalgebra::Point2;

/// Colours of the session windows, in session order (repeated).
const COLOURS: [&str; 8] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#17becf",
];

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
    /// The SVG document (1.2 px per metre plus a margin and a legend).
    pub fn svg(&self) -> String {
        let (mut lo, mut hi) = (
            Point2::new(f64::MAX, f64::MAX),
            Point2::new(f64::MIN, f64::MIN),
        );
        for p in self.path.iter().chain(self.poles) {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        if lo.x > hi.x {
            (lo, hi) = (Point2::origin(), Point2::new(1.0, 1.0));
        }
        let (scale, margin, legend) = (1.2, 20.0, 24.0);
        let w = (hi.x - lo.x) * scale + 2.0 * margin;
        let h = (hi.y - lo.y) * scale + 2.0 * margin + legend;
        let xy = |p: &Point2<f64>| {
            (
                margin + (p.x - lo.x) * scale,
                margin + legend + (hi.y - p.y) * scale,
            )
        };
        let polyline = |points: &[Point2<f64>], style: &str| {
            let mut s = String::from("<polyline fill=\"none\" ");
            s.push_str(style);
            s.push_str(" points=\"");
            for p in points {
                let (x, y) = xy(p);
                let _ = write!(s, "{x:.1},{y:.1} ");
            }
            s.push_str("\"/>\n");
            s
        };
        let mut s = format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w:.0}\" height=\"{h:.0}\" \
             viewBox=\"0 0 {w:.0} {h:.0}\" font-family=\"sans-serif\" font-size=\"12\">\n\
             <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
        );
        s.push_str(&polyline(
            self.path,
            "stroke=\"#c8c8c8\" stroke-width=\"3\"",
        ));
        for (k, (_, points)) in self.sessions.iter().enumerate() {
            let colour = COLOURS[k % COLOURS.len()];
            s.push_str(&polyline(
                points,
                &format!("stroke=\"{colour}\" stroke-width=\"2\" stroke-opacity=\"0.8\""),
            ));
        }
        for p in self.poles {
            let (x, y) = xy(p);
            let _ = writeln!(
                s,
                "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"1.2\" fill=\"#444\"/>"
            );
        }
        for p in &self.map {
            let (x, y) = xy(p);
            let _ = writeln!(
                s,
                "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"3\" fill=\"none\" stroke=\"#d62728\"/>"
            );
        }
        let mut x = margin;
        let _ = writeln!(
            s,
            "<text x=\"{x:.0}\" y=\"16\">grey: real NCLT path; dots: real poles; red rings: \
             reference map; sessions:</text>"
        );
        x += 470.0;
        for (k, (label, _)) in self.sessions.iter().enumerate() {
            let colour = COLOURS[k % COLOURS.len()];
            let _ = writeln!(
                s,
                "<text x=\"{x:.0}\" y=\"16\" fill=\"{colour}\">{label}</text>"
            );
            x += 80.0;
        }
        s.push_str("</svg>\n");
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn svg_holds_every_element() {
        let path = [Point2::new(0.0, 0.0), Point2::new(100.0, 50.0)];
        let poles = [Point2::new(10.0, 10.0), Point2::new(50.0, 20.0)];
        let figure = CampusFigure {
            path: &path,
            poles: &poles,
            sessions: vec![("2012-01-08".into(), path.to_vec())],
            map: vec![poles[0]],
        };
        let svg = figure.svg();
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>\n"));
        assert_eq!(svg.matches("<polyline").count(), 2);
        assert_eq!(svg.matches("<circle").count(), 3);
        assert!(svg.contains("2012-01-08"));
        // y up: the path's end (higher y) is drawn above its start.
        assert!(svg.contains("20.0,104.0 140.0,44.0"), "{svg}");
    }
}
