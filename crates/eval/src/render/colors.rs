//! Colours of the figures: a categorical palette for series, viridis for values, and one colour
//! per segment label.

use plotters::prelude::*;

/// Colours of the series of a figure in order (matplotlib's "tab10").
pub const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// Viridis for `t ∈ [0, 1]` (dark blue → green → yellow; clamped, dark blue for NaN).
pub fn colormap(t: f64) -> [u8; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let RGBColor(r, g, b) = ViridisRGB.get_color_normalized(t, 0.0, 1.0);
    [r, g, b]
}

/// A distinct colour per label (black for 0, grey for labels below 10).
pub fn label_color(label: u32) -> [u8; 3] {
    match label {
        0 => [0, 0, 0],
        1..=9 => [150, 150, 150],
        _ => {
            let h = label.wrapping_mul(2_654_435_761);
            [
                64 + (h & 0xbf) as u8,
                64 + ((h >> 8) & 0xbf) as u8,
                64 + ((h >> 16) & 0xbf) as u8,
            ]
        }
    }
}

/// The colour of `#rrggbb` (black for anything else).
pub fn hex(color: &str) -> RGBColor {
    let digits = color.strip_prefix('#').filter(|d| d.len() == 6);
    let channel = |k: usize| {
        digits
            .and_then(|d| d.get(2 * k..2 * k + 2))
            .and_then(|h| u8::from_str_radix(h, 16).ok())
            .unwrap_or(0)
    };
    RGBColor(channel(0), channel(1), channel(2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colormap_runs_from_dark_blue_to_yellow() {
        assert_eq!(colormap(0.0), [68, 1, 84]);
        assert_eq!(colormap(1.0), [254, 232, 37]);
        assert_eq!(colormap(f64::NAN), colormap(0.0));
        assert_eq!(colormap(7.0), colormap(1.0));
    }

    #[test]
    fn hex_reads_rrggbb() {
        assert_eq!(hex("#1f77b4"), PALETTE[0]);
        assert_eq!(hex("red"), RGBColor(0, 0, 0));
    }
}
