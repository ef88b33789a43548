//! Hand-written SVG line charts for the Fig. 10.4 curves (metric vs number of vertices).

use std::fmt::Write;

/// One curve: label, colour, and `(x, mean, standard error)` points.
pub struct Series {
    pub label: String,
    pub color: &'static str,
    pub points: Vec<(f64, f64, f64)>,
}

/// A chart with axis labels, ticks, error bars, a legend and an optional dashed reference
/// line.
pub fn line_chart(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    reference: Option<(f64, &str)>,
) -> String {
    let (w, h) = (560.0, 380.0);
    let (left, right, top, bottom) = (70.0, 130.0, 36.0, 50.0);
    let finite = |v: f64| v.is_finite();
    let xs: Vec<f64> = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.0))
        .collect();
    let ys: Vec<f64> = series
        .iter()
        .flat_map(|s| {
            s.points
                .iter()
                .filter(|p| finite(p.1))
                .flat_map(|p| [p.1 - p.2.max(0.0), p.1 + p.2.max(0.0)])
        })
        .chain(reference.map(|r| r.0))
        .filter(|v| v.is_finite())
        .collect();
    let x0 = xs.iter().copied().fold(f64::INFINITY, f64::min);
    let x1 = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut y0 = ys.iter().copied().fold(f64::INFINITY, f64::min).min(0.0);
    let mut y1 = ys.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if y1.partial_cmp(&y0) != Some(std::cmp::Ordering::Greater) {
        y0 = 0.0;
        y1 = 1.0;
    }
    y1 += 0.05 * (y1 - y0);
    let (x0, x1) = if x1 > x0 { (x0, x1) } else { (0.0, 1.0) };
    let pw = w - left - right;
    let ph = h - top - bottom;
    let sx = |x: f64| left + (x - x0) / (x1 - x0) * pw;
    let sy = |y: f64| top + (1.0 - (y - y0) / (y1 - y0)) * ph;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="20" text-anchor="middle" font-size="14">{title}</text>"#,
        left + pw / 2.0
    );
    // Axes and ticks.
    let _ = writeln!(
        s,
        r#"<path d="M{left},{top} L{left},{} L{},{}" fill="none" stroke="black"/>"#,
        top + ph,
        left + pw,
        top + ph
    );
    let mut xt: Vec<f64> = xs.clone();
    xt.sort_by(f64::total_cmp);
    xt.dedup();
    for x in xt {
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{x}</text>"#,
            sx(x),
            top + ph + 16.0
        );
    }
    let step = nice_step((y1 - y0) / 5.0);
    let mut y = (y0 / step).ceil() * step;
    while y <= y1 + 1e-12 {
        let _ = writeln!(
            s,
            r##"<path d="M{left},{v:.1} L{:.1},{v:.1}" stroke="#ddd"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
            left + pw,
            left - 6.0,
            sy(y) + 4.0,
            format_tick(y, step),
            v = sy(y)
        );
        y += step;
    }
    let _ = writeln!(
        s,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{x_label}</text>"#,
        left + pw / 2.0,
        h - 12.0
    );
    let _ = writeln!(
        s,
        r#"<text x="16" y="{:.1}" text-anchor="middle" transform="rotate(-90 16 {:.1})">{y_label}</text>"#,
        top + ph / 2.0,
        top + ph / 2.0
    );
    if let Some((value, label)) = reference {
        let _ = writeln!(
            s,
            r##"<path d="M{left},{v:.1} L{:.1},{v:.1}" stroke="#444" stroke-dasharray="6,4"/><text x="{:.1}" y="{:.1}" font-size="10">{label}</text>"##,
            left + pw,
            left + 4.0,
            sy(value) - 4.0,
            v = sy(value)
        );
    }
    for (i, series) in series.iter().enumerate() {
        let mut d = String::new();
        for p in series.points.iter().filter(|p| finite(p.1)) {
            let _ = write!(
                d,
                "{}{:.1},{:.1} ",
                if d.is_empty() { "M" } else { "L" },
                sx(p.0),
                sy(p.1)
            );
            if p.2 > 0.0 && p.2.is_finite() {
                let _ = writeln!(
                    s,
                    r#"<path d="M{x:.1},{:.1} L{x:.1},{:.1}" stroke="{}"/>"#,
                    sy(p.1 - p.2),
                    sy(p.1 + p.2),
                    series.color,
                    x = sx(p.0)
                );
            }
        }
        let _ = writeln!(
            s,
            r#"<path d="{d}" fill="none" stroke="{}" stroke-width="2"/>"#,
            series.color
        );
        let ly = top + 14.0 + 18.0 * i as f64;
        let lx = left + pw + 12.0;
        let _ = writeln!(
            s,
            r#"<path d="M{lx},{ly} L{},{ly}" stroke="{}" stroke-width="2"/><text x="{}" y="{:.1}">{}</text>"#,
            lx + 20.0,
            series.color,
            lx + 26.0,
            ly + 4.0,
            series.label
        );
    }
    s.push_str("</svg>\n");
    s
}

fn nice_step(raw: f64) -> f64 {
    if raw.is_nan() || raw <= 0.0 || !raw.is_finite() {
        return 1.0;
    }
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    let nice = if f <= 1.0 {
        1.0
    } else if f <= 2.0 {
        2.0
    } else if f <= 5.0 {
        5.0
    } else {
        10.0
    };
    nice * mag
}

fn format_tick(v: f64, step: f64) -> String {
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    format!("{v:.decimals$}")
}
