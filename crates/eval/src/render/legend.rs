//! Legends drawn as a strip beside a chart (never over the data): a mark in each entry's
//! colour and its label, left to right, wrapped into rows.

use anyhow::{Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::canvas::{self, FONT};

/// Height of one row of a legend in pixels.
pub const ROW_PX: u32 = 22;
/// Size of a legend's text in pixels.
const TEXT_PX: u32 = 14;
/// Width of an entry's mark and the gaps after it and after its label.
const MARK_PX: i32 = 22;
const GAP_PX: i32 = 6;
const SPACING_PX: i32 = 18;

/// How an entry shows its colour.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Mark {
    /// A filled square (bars, shaded cells).
    Swatch,
    /// A short line (paths, curves).
    Line,
    /// A filled dot (points).
    Dot,
    /// An open circle (points of another kind).
    Ring,
}

/// One entry: label, colour and mark.
#[derive(Clone, Debug)]
pub struct Entry {
    /// What the colour stands for.
    pub label: String,
    /// Its colour.
    pub color: RGBColor,
    /// How it is drawn.
    pub mark: Mark,
}

impl Entry {
    /// An entry.
    pub fn new(label: impl Into<String>, color: RGBColor, mark: Mark) -> Self {
        Self {
            label: label.into(),
            color,
            mark,
        }
    }

    /// The width of the entry in pixels, mark, label and spacing included.
    fn width(&self) -> i32 {
        canvas::register();
        let text = (FONT, TEXT_PX).into_font().box_size(&self.label);
        MARK_PX + GAP_PX + text.map_or(8 * self.label.len() as i32, |(w, _)| w as i32) + SPACING_PX
    }
}

/// The entries in rows that fit `width_px` (each row at least one entry).
fn rows(entries: &[Entry], width_px: u32) -> Vec<&[Entry]> {
    let mut rows = Vec::new();
    let (mut start, mut used) = (0, 0);
    for (k, entry) in entries.iter().enumerate() {
        let w = entry.width();
        if k > start && used + w > width_px as i32 {
            rows.push(&entries[start..k]);
            (start, used) = (k, 0);
        }
        used += w;
    }
    if start < entries.len() {
        rows.push(&entries[start..]);
    }
    rows
}

/// The height of the legend of `entries` laid out in `width_px` (0 for none).
pub fn height(entries: &[Entry], width_px: u32) -> u32 {
    rows(entries, width_px).len() as u32 * ROW_PX
}

/// Draws the legend into `area` (as wide as given to [`height`]), rows from its top left.
pub fn draw<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, entries: &[Entry]) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let width = area.dim_in_pixel().0;
    for (r, row) in rows(entries, width).into_iter().enumerate() {
        let y = r as i32 * ROW_PX as i32 + ROW_PX as i32 / 2;
        let mut x = 0;
        for entry in row {
            mark(area, (x, y), entry)?;
            let style = canvas::text_style(TEXT_PX, BLACK).pos(Pos::new(HPos::Left, VPos::Center));
            area.draw(&Text::new(
                entry.label.as_str(),
                (x + MARK_PX + GAP_PX, y),
                style,
            ))
            .context("drawing the legend")?;
            x += entry.width();
        }
    }
    Ok(())
}

/// An entry's mark centred vertically on `y`, from `x` on.
fn mark<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (x, y): (i32, i32),
    entry: &Entry,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let c = entry.color;
    let centre = (x + MARK_PX / 2, y);
    match entry.mark {
        Mark::Swatch => area.draw(&Rectangle::new(
            [(x + 4, y - 7), (x + MARK_PX - 4, y + 7)],
            c.filled(),
        )),
        Mark::Line => area.draw(&PathElement::new(
            [(x, y), (x + MARK_PX, y)],
            c.stroke_width(3),
        )),
        Mark::Dot => area.draw(&Circle::new(centre, 4, c.filled())),
        Mark::Ring => area.draw(&Circle::new(centre, 5, c.stroke_width(2))),
    }
    .context("drawing the legend")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_wrap_into_rows_that_fit() {
        let entries: Vec<Entry> = (0..6)
            .map(|k| Entry::new(format!("entry number {k}"), BLACK, Mark::Line))
            .collect();
        let one = entries[0].width() as u32;
        assert_eq!(height(&entries, 10_000), ROW_PX);
        assert_eq!(height(&entries, 2 * one + 1), 3 * ROW_PX);
        assert_eq!(height(&entries, 1), 6 * ROW_PX);
        assert_eq!(height(&[], 100), 0);
    }
}
