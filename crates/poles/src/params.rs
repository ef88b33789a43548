//! Named parameters of pole extraction with the NCLT and KITTI presets (Schaefer 2020,
//! §12.4.1–§12.4.2 and §12.5, with the reference implementation's values).

use serde::{Deserialize, Serialize};

use crate::error::{Result, require};

/// Parameters of pole extraction from one local map.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PoleParams {
    /// Voxel edge length, metres (NCLT 0.2, KITTI 0.1; Schaefer 2020, §12.5.1, §12.5.2).
    pub voxel_m: f64,
    /// Local map extent `(x, y, z)`, metres (NCLT 30 × 30 × 5, KITTI 30 × 30 × 3; §12.4.2).
    pub extent_m: [f64; 3],
    /// Where the sensor at the segment's centre sits in grid coordinates, metres
    /// (NCLT `(15, 15, 0.5)`, KITTI `(15, 15, 2.0)`; `ncltpoles.py`, `kittipoles.py`).
    pub sensor_in_grid_m: [f64; 3],
    /// Largest pole footprint edge in cells; widths `a = 1..=max_width_cells` are scored
    /// (NCLT 7, KITTI 10).
    pub max_width_cells: usize,
    /// Free length around a pole, metres: the hull thickness `f = round_ties_even(free/voxel)`
    /// cells and the non-maximum-suppression distance (NCLT 0.5, KITTI 0.2; rounded half to
    /// even as NumPy, so NCLT's 0.5/0.2 gives `f = 2`).
    pub free_length_m: f64,
    /// Reflection-rate threshold `μ_o` of the occupancy (thesis 0.2 for NCLT; the reference
    /// code's `mapping.py` uses 0.05; the default follows the thesis).
    pub occupancy_threshold: f64,
    /// Minimum pole score `q_min` on the `[0, 1]`-remapped score `q' = q/2 + 1/2` (0.6, as the
    /// reference code; the thesis applies it to the raw `q ∈ [−1, 1]`); must exceed 1/2 (raw
    /// score 0).
    pub min_score: f64,
    /// Minimum pole height `h_min`, metres (1.0).
    pub min_height_m: f64,
    /// Standard deviation of the Gaussian mean-shift kernel, metres (0.2, `normstd`).
    pub mean_shift_sigma_m: f64,
    /// Mean shift stops when a step is shorter than this, metres (1e-3, `dstop`).
    pub mean_shift_stop_m: f64,
    /// Points farther than this from the sensor are not traced, metres (no-returns are not
    /// stored by the readers).
    pub max_range_m: f64,
}

impl PoleParams {
    /// The NCLT preset (§12.5.1 and `ncltpoles.py`): 0.2 m voxels, 30 × 30 × 5 m, widths
    /// 0.2–1.4 m, free length 0.5 m (f = 2), μ_o = 0.2, q_min = 0.6, h_min = 1 m.
    pub fn nclt() -> Self {
        Self {
            voxel_m: 0.2,
            extent_m: [30.0, 30.0, 5.0],
            sensor_in_grid_m: [15.0, 15.0, 0.5],
            max_width_cells: 7,
            free_length_m: 0.5,
            occupancy_threshold: 0.2,
            min_score: 0.6,
            min_height_m: 1.0,
            mean_shift_sigma_m: 0.2,
            mean_shift_stop_m: 1e-3,
            max_range_m: 120.0,
        }
    }

    /// The KITTI preset (§12.5.2 and `kittipoles.py`): 0.1 m voxels, 30 × 30 × 3 m, widths
    /// 0.1–1.0 m, free length 0.2 m (f = 2), otherwise as NCLT.
    pub fn kitti() -> Self {
        Self {
            voxel_m: 0.1,
            extent_m: [30.0, 30.0, 3.0],
            sensor_in_grid_m: [15.0, 15.0, 2.0],
            max_width_cells: 10,
            free_length_m: 0.2,
            ..Self::nclt()
        }
    }

    /// The hull thickness `f` in cells: `round_ties_even(free_length / voxel)`, at least 1
    /// (ties to even as NumPy, which rounds 2.5 to 2; `f64::round` would give 3).
    pub fn hull_cells(&self) -> usize {
        ((self.free_length_m / self.voxel_m).round_ties_even() as usize).max(1)
    }

    /// Grid dimensions in voxels.
    pub fn dims(&self) -> [usize; 3] {
        self.extent_m
            .map(|e| (e / self.voxel_m).round().max(1.0) as usize)
    }

    /// The minimum stack length in voxels (`ceil(h_min / voxel)` up to rounding).
    pub fn min_stack_cells(&self) -> usize {
        ((self.min_height_m / self.voxel_m - 1e-9).ceil() as usize).max(1)
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        require(positive(self.voxel_m), "voxel_m", || {
            format!("{} is not a positive length", self.voxel_m)
        })?;
        require(
            self.extent_m.iter().all(|&e| positive(e)),
            "extent_m",
            || format!("{:?} are not positive lengths", self.extent_m),
        )?;
        let dims = self.dims();
        require(
            dims.iter().product::<usize>() <= 200_000_000,
            "extent_m",
            || format!("{dims:?} voxels are too many"),
        )?;
        require(
            self.sensor_in_grid_m.iter().all(|v| v.is_finite()),
            "sensor_in_grid_m",
            || "not finite".into(),
        )?;
        require(
            (1..=64).contains(&self.max_width_cells),
            "max_width_cells",
            || format!("{} is not in 1..=64", self.max_width_cells),
        )?;
        require(positive(self.free_length_m), "free_length_m", || {
            format!("{} is not a positive length", self.free_length_m)
        })?;
        require(
            self.occupancy_threshold > 0.0 && self.occupancy_threshold < 1.0,
            "occupancy_threshold",
            || format!("{} is not in (0, 1)", self.occupancy_threshold),
        )?;
        require((0.0..=1.0).contains(&self.min_score), "min_score", || {
            format!("{} is not in [0, 1]", self.min_score)
        })?;
        require(positive(self.min_height_m), "min_height_m", || {
            format!("{} is not a positive length", self.min_height_m)
        })?;
        require(
            positive(self.mean_shift_sigma_m),
            "mean_shift_sigma_m",
            || format!("{} is not positive", self.mean_shift_sigma_m),
        )?;
        require(
            positive(self.mean_shift_stop_m),
            "mean_shift_stop_m",
            || format!("{} is not positive", self.mean_shift_stop_m),
        )?;
        require(positive(self.max_range_m), "max_range_m", || {
            format!("{} is not positive", self.max_range_m)
        })
    }
}

impl Default for PoleParams {
    /// The NCLT preset.
    fn default() -> Self {
        Self::nclt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_match_the_spec() {
        let nclt = PoleParams::nclt();
        assert_eq!(nclt.hull_cells(), 2, "round(2.5) ties to even");
        assert_eq!(nclt.dims(), [150, 150, 25]);
        assert_eq!(nclt.min_stack_cells(), 5);
        let kitti = PoleParams::kitti();
        assert_eq!(kitti.hull_cells(), 2);
        assert_eq!(kitti.dims(), [300, 300, 30]);
        assert_eq!(kitti.min_stack_cells(), 10);
        assert!(nclt.validate().is_ok() && kitti.validate().is_ok());
    }
}
