//! A pole landmark.

use serde::{Deserialize, Serialize};

/// A pole: centre in the ground plane, vertical extent, footprint width and score (Schaefer
/// 2020, §12.4.1; the row `[x, y, z_start, z_end, width, score]` of `poles.py`). Metres in the
/// frame of the map it was extracted in.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pole {
    /// Centre x, metres.
    pub x: f64,
    /// Centre y, metres.
    pub y: f64,
    /// Bottom of the pole's voxel stack, metres.
    pub z_start: f64,
    /// Top of the pole's voxel stack, metres.
    pub z_end: f64,
    /// Footprint edge length, metres (score-weighted mean over the widths scored).
    pub width: f64,
    /// Mean remapped pole score in `[0, 1]`.
    pub score: f64,
}

impl Pole {
    /// Height of the voxel stack, metres.
    pub fn height(&self) -> f64 {
        self.z_end - self.z_start
    }

    /// True when the axis-aligned squares (centre, width) of the two poles overlap (closed
    /// intervals on both axes; Schaefer 2020, §12.4.2, and `cluster.py`).
    pub fn overlaps(&self, other: &Pole) -> bool {
        let reach = 0.5 * (self.width + other.width);
        (self.x - other.x).abs() <= reach && (self.y - other.y).abs() <= reach
    }
}
