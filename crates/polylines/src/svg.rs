//! A picture of a scan and its polylines as SVG (scan frame, x right, y up, metres).

use std::fmt::Write;

use raypath_geometry::Scan2;

use crate::Polylines;

/// An SVG picture `size_px` wide (at most) showing the sensor (black cross), the measured
/// endpoints (grey dots) and the polylines (blue, vertices as red dots).
pub fn scan_svg(scan: &Scan2, map: &Polylines, size_px: f64) -> String {
    let points: Vec<(f64, f64)> = (0..scan.len())
        .filter_map(|k| {
            scan.range(k).hit().map(|r| {
                let a = scan.angle(k);
                (r * a.cos(), r * a.sin())
            })
        })
        .chain(map.vertices().map(|v| (v.x, v.y)))
        .chain([(0.0, 0.0)])
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    let (mut x0, mut x1, mut y0, mut y1) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for &(x, y) in &points {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let margin = 0.05 * (x1 - x0).max(y1 - y0).max(1.0);
    let (x0, x1, y0, y1) = (x0 - margin, x1 + margin, y0 - margin, y1 + margin);
    let scale = size_px / (x1 - x0).max(y1 - y0);
    let (w, h) = ((x1 - x0) * scale, (y1 - y0) * scale);
    let px = |x: f64, y: f64| ((x - x0) * scale, (y1 - y) * scale);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0}" height="{h:.0}" viewBox="0 0 {w:.1} {h:.1}">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    for &(x, y) in points.iter().take(points.len().saturating_sub(1)) {
        let (u, v) = px(x, y);
        let _ = writeln!(
            s,
            r##"<circle cx="{u:.1}" cy="{v:.1}" r="1.5" fill="#999"/>"##
        );
    }
    for line in &map.lines {
        let mut d = String::new();
        for (i, v) in line.vertices.iter().enumerate() {
            let (u, w) = px(v.x, v.y);
            let _ = write!(d, "{}{u:.1},{w:.1} ", if i == 0 { "M" } else { "L" });
        }
        if line.closed {
            d.push('Z');
        }
        let _ = writeln!(
            s,
            r##"<path d="{d}" fill="none" stroke="#1f5fbf" stroke-width="1.5"/>"##
        );
        for v in &line.vertices {
            let (u, w) = px(v.x, v.y);
            let _ = writeln!(
                s,
                r##"<circle cx="{u:.1}" cy="{w:.1}" r="2.5" fill="#d62728"/>"##
            );
        }
    }
    let (u, v) = px(0.0, 0.0);
    let _ = writeln!(
        s,
        r#"<path d="M{:.1},{v:.1} L{:.1},{v:.1} M{u:.1},{:.1} L{u:.1},{:.1}" stroke="black" stroke-width="1.5"/>"#,
        u - 5.0,
        u + 5.0,
        v - 5.0,
        v + 5.0
    );
    s.push_str("</svg>\n");
    s
}
