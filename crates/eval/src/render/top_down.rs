//! Top-down maps (north up, metres): hit counts in grey, coloured overlays (trajectories,
//! poles, polygons) on top, axes in metres around and a legend of the overlays.

use std::path::Path;

use anyhow::{Context, Result, anyhow};
use plotters::prelude::*;

use super::canvas::{self, FONT};
use super::legend::{self, Entry, Mark};

/// Pixels around the map: left (y tick labels and axis label), right, top, bottom.
const LEFT: u32 = 72;
const RIGHT: u32 = 16;
const TOP: u32 = 12;
const BOTTOM: u32 = 52;

/// An overlay drawn over the hits.
enum Shape {
    Line((f64, f64), (f64, f64), RGBColor),
    Dot((f64, f64), i32, RGBColor),
}

/// A top-down picture of the ground plane (north up): one pixel per cell, hit counts in grey,
/// coloured overlays on top, x and y axes in metres and a legend.
pub struct TopDown {
    min_x: f64,
    max_y: f64,
    cell_m: f64,
    width: u32,
    height: u32,
    counts: Vec<u32>,
    overlay: Vec<Shape>,
    legend: Vec<(String, RGBColor)>,
}

impl TopDown {
    /// A picture of the region spanned by `points` (the `quantile`–(1 − `quantile`) range of
    /// each axis, so a few stray points do not shrink it), with cells of at least `min_cell_m`
    /// and at most `max_side_px` pixels on the longer side. `None` for no points.
    pub fn fit(
        points: &[(f64, f64)],
        quantile: f64,
        min_cell_m: f64,
        max_side_px: f64,
    ) -> Option<Self> {
        if points.is_empty() {
            return None;
        }
        let (min_x, max_x) = robust_bounds(points.iter().map(|p| p.0).collect(), quantile);
        let (min_y, max_y) = robust_bounds(points.iter().map(|p| p.1).collect(), quantile);
        let cell_m = ((max_x - min_x).max(max_y - min_y) / max_side_px).max(min_cell_m);
        let width = ((max_x - min_x) / cell_m).floor() as u32 + 1;
        let height = ((max_y - min_y) / cell_m).floor() as u32 + 1;
        Some(Self {
            min_x,
            max_y,
            cell_m,
            width,
            height,
            counts: vec![0; width as usize * height as usize],
            overlay: Vec::new(),
            legend: Vec::new(),
        })
    }

    /// Counts one hit at `(x, y)` metres.
    pub fn hit(&mut self, x: f64, y: f64) {
        let col = (x - self.min_x) / self.cell_m;
        let row = (self.max_y - y) / self.cell_m;
        if col >= 0.0 && row >= 0.0 && col < f64::from(self.width) && row < f64::from(self.height) {
            self.counts[row as usize * self.width as usize + col as usize] += 1;
        }
    }

    /// A filled dot of `radius_px` pixels at `(x, y)` metres (none at a non-finite place).
    pub fn dot(&mut self, x: f64, y: f64, radius_px: i32, color: [u8; 3]) {
        if finite(&[(x, y)]) {
            self.overlay.push(Shape::Dot((x, y), radius_px, rgb(color)));
        }
    }

    /// A line from `a` to `b` (metres; none with a non-finite end).
    pub fn line(&mut self, a: (f64, f64), b: (f64, f64), color: [u8; 3]) {
        if finite(&[a, b]) {
            self.overlay.push(Shape::Line(a, b, rgb(color)));
        }
    }

    /// Names an overlay colour in the legend (the hits have their entry when there are any).
    pub fn legend(&mut self, label: &str, color: [u8; 3]) {
        self.legend.push((label.to_owned(), rgb(color)));
    }

    /// The size of the picture in pixels: the map, the axes around it and the legend below.
    pub fn size(&self) -> (u32, u32) {
        let legend = legend::height(&self.entries(), self.width);
        (
            self.width + LEFT + RIGHT,
            self.height + TOP + BOTTOM + legend,
        )
    }

    /// The legend: the hits (when there are any), then the named overlays.
    fn entries(&self) -> Vec<Entry> {
        let hits = self.counts.iter().any(|&c| c > 0).then(|| {
            Entry::new(
                "laser hits (darker = more)",
                RGBColor(110, 110, 110),
                Mark::Swatch,
            )
        });
        let named = self
            .legend
            .iter()
            .map(|(label, color)| Entry::new(label, *color, Mark::Swatch));
        hits.into_iter().chain(named).collect()
    }

    /// Writes the PNG: white background, 1 hit light grey, 8 or more black; overlays on top.
    pub fn save(&self, path: &Path) -> Result<()> {
        let layer = self.map_layer()?;
        let (width, height) = (self.width, self.height);
        let x = self.min_x..self.min_x + f64::from(width) * self.cell_m;
        let y = self.max_y - f64::from(height) * self.cell_m..self.max_y;
        canvas::png(path, self.size(), |root| {
            let (chart_area, legend_area) = root.split_vertically(TOP + height + BOTTOM);
            let mut chart = ChartBuilder::on(&chart_area)
                .margin_top(TOP)
                .margin_right(RIGHT)
                .x_label_area_size(BOTTOM)
                .y_label_area_size(LEFT)
                .build_cartesian_2d(x, y)
                .context("drawing the map")?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_labels((width / 90).max(3) as usize)
                .y_labels((height / 70).max(3) as usize)
                .x_label_formatter(&|v| canvas::number(*v))
                .y_label_formatter(&|v| canvas::number(*v))
                .label_style((FONT, 14))
                .axis_desc_style((FONT, 15))
                .x_desc("x (m)")
                .y_desc("y (m)")
                .draw()
                .context("drawing the axes")?;
            let area = chart.plotting_area().strip_coord_spec();
            let map = BitMapElement::with_owned_buffer((0, 0), (width, height), layer)
                .ok_or_else(|| anyhow!("map buffer size"))?;
            area.draw(&map).context("drawing the map")?;
            area.draw(&Rectangle::new(
                [(0, 0), (width as i32 - 1, height as i32 - 1)],
                BLACK,
            ))
            .context("drawing the frame")?;
            legend::draw(&legend_area.margin(0, 0, LEFT, RIGHT), &self.entries())
        })
    }

    /// The map as an RGB buffer of `width × height`: hits shaded, overlays drawn (and clipped
    /// at its border).
    fn map_layer(&self) -> Result<Vec<u8>> {
        let mut layer: Vec<u8> = self.counts.iter().flat_map(|&c| [shade(c); 3]).collect();
        {
            let area = BitMapBackend::with_buffer(&mut layer, (self.width, self.height))
                .into_drawing_area();
            // Cell centres map to pixel centres: the first and last cell of each axis span it.
            let half = 0.5 * self.cell_m;
            let x = self.min_x + half..self.min_x + (f64::from(self.width) - 0.5) * self.cell_m;
            let y = self.max_y - (f64::from(self.height) - 0.5) * self.cell_m..self.max_y - half;
            let mut chart = ChartBuilder::on(&area)
                .build_cartesian_2d(x, y)
                .context("drawing the map")?;
            for shape in &self.overlay {
                match *shape {
                    Shape::Line(a, b, color) => {
                        chart.draw_series([PathElement::new([a, b], color)])
                    }
                    Shape::Dot(at, radius, color) => {
                        chart.draw_series([Circle::new(at, radius, color.filled())])
                    }
                }
                .context("drawing the overlays")?;
            }
            area.present().context("drawing the map")?;
        }
        Ok(layer)
    }
}

/// Grey of a cell with `count` hits: white for none, light grey for 1, black for 8 or more.
fn shade(count: u32) -> u8 {
    if count == 0 {
        255
    } else {
        (200.0 * (1.0 - (f64::from(count).log2() / 3.0).min(1.0))) as u8
    }
}

/// Whether every coordinate of `points` is finite.
fn finite(points: &[(f64, f64)]) -> bool {
    points.iter().all(|p| p.0.is_finite() && p.1.is_finite())
}

fn rgb(color: [u8; 3]) -> RGBColor {
    RGBColor(color[0], color[1], color[2])
}

/// The `q`–(1 − `q`) quantile range of the finite values, padded by 2 % on each side
/// (`(0, 1)` when there are none).
fn robust_bounds(mut values: Vec<f64>, q: f64) -> (f64, f64) {
    values.retain(|v| v.is_finite());
    if values.is_empty() {
        return (0.0, 1.0);
    }
    values.sort_by(f64::total_cmp);
    let at = |f: f64| values[((values.len() - 1) as f64 * f) as usize];
    let (lo, hi) = (at(q), at(1.0 - q));
    if hi <= lo {
        return (lo - 0.5, lo + 0.5);
    }
    let pad = 0.02 * (hi - lo);
    (lo - pad, hi + pad)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 20 m × 10 m room's walls, a path through it and a pole.
    fn room() -> TopDown {
        let mut walls = Vec::new();
        for k in 0..=200 {
            let t = f64::from(k) / 10.0;
            walls.extend([(t, 0.0), (t, 10.0)]);
            if k <= 100 {
                walls.extend([(0.0, t), (20.0, t)]);
            }
        }
        let mut top = TopDown::fit(&walls, 0.0, 0.05, 300.0).expect("points");
        for &(x, y) in &walls {
            top.hit(x, y);
        }
        top.line((2.0, 2.0), (18.0, 8.0), [220, 40, 40]);
        top.line((-50.0, 5.0), (50.0, 5.0), [40, 90, 200]);
        top.dot(10.0, 5.0, 3, [0, 160, 0]);
        top.dot(f64::NAN, 5.0, 3, [0, 160, 0]);
        top.line((0.0, 0.0), (f64::INFINITY, 1.0), [0, 160, 0]);
        top.legend("path", [220, 40, 40]);
        top.legend("pole", [0, 160, 0]);
        top
    }

    #[test]
    fn map_with_axes_is_written_and_decodes() {
        let dir = tempfile::tempdir().expect("temp dir");
        let top = room();
        let path = dir.path().join("room.png");
        top.save(&path).expect("saved");
        let image = image::open(&path).expect("decodes").to_rgb8();
        assert_eq!(image.dimensions(), top.size());
        // The legend's three entries take two rows below the 301 px wide map.
        assert_eq!(
            top.size(),
            (
                top.width + LEFT + RIGHT,
                top.height + TOP + BOTTOM + 2 * legend::ROW_PX
            )
        );
        // The map's corner pixel is a wall hit (dark), the margin left of it is white, the
        // path is red somewhere and the long blue line stops at the map's frame.
        let at = |x: u32, y: u32| image.get_pixel(x, y).0;
        assert!(at(LEFT + 2, TOP + top.height / 2)[0] < 200);
        assert_eq!(at(LEFT / 2, TOP + 2), [255, 255, 255]);
        assert!(image.pixels().any(|p| p.0 == [220, 40, 40]));
        let blue = |x: u32| (0..image.height()).any(|y| at(x, y) == [40, 90, 200]);
        assert!(blue(LEFT + top.width / 4) && !blue(2) && !blue(image.width() - 2));
        // Tick labels: dark pixels below the map.
        assert!((LEFT..LEFT + top.width).any(|x| at(x, TOP + top.height + 14)[0] < 128));
    }

    #[test]
    fn same_input_same_bytes() {
        let dir = tempfile::tempdir().expect("temp dir");
        let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
        room().save(&a).expect("saved");
        room().save(&b).expect("saved");
        assert_eq!(std::fs::read(a).expect("a"), std::fs::read(b).expect("b"));
    }

    #[test]
    fn robust_bounds_ignore_stray_values() {
        let mut values: Vec<f64> = (0..1000).map(f64::from).collect();
        values.push(1e9);
        values.push(f64::NAN);
        let (lo, hi) = robust_bounds(values, 0.01);
        assert!(lo < 10.0 && hi < 1100.0);
        assert_eq!(robust_bounds(vec![], 0.0), (0.0, 1.0));
    }
}
