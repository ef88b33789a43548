//! The frozen probability grid a scan is matched against (Hess et al. 2016 §V: the
//! submap's probability grid `M_nearest`).

use raypath_reflectivity::{GridLevel, probability};

use crate::error::{Result, SlamError};

/// The probability given to never-observed cells (log-odds exactly 0) by
/// [`ProbabilityGrid::from_level`].
///
/// Correlative scoring rewards points that fall into likely-occupied cells. An unknown cell at
/// 0.5 would reward poses that push a scan into unexplored space, beyond the walls, over poses
/// that put it onto observed free space, which is backwards for loop-closure verification.
/// Cartographer's grids (Hess et al. 2016) give unknown cells their minimum probability 0.1;
/// we do the same, so unknown counts like well-observed free space.
pub const UNKNOWN_PROBABILITY: f32 = 0.1;

/// Full scale of the 16-bit quantization of probabilities: `q = round(p · 65535)`.
pub(crate) const QUANT_MAX: u16 = u16::MAX;

/// A frozen probability grid of a submap.
///
/// Submap frame, metres; values in `[0, 1]` at cell centres; cell `(i, j)` covers
/// `[x₀ + i·res, x₀ + (i+1)·res) × [y₀ + j·res, y₀ + (j+1)·res)` (the convention of
/// [`GridLevel`]). Values are stored with 16-bit precision (steps of 1/65535): scores are then
/// exact integer sums, so branch and bound and brute force rank candidates identically.
#[derive(Clone, Debug, PartialEq)]
pub struct ProbabilityGrid {
    resolution_m: f64,
    origin: [f64; 2],
    width: usize,
    height: usize,
    /// Row-major (`j * width + i`), quantized to `0 ..= QUANT_MAX`.
    cells: Vec<u16>,
}

/// Quantizes a probability in `[0, 1]` to 16 bits.
fn quantize(p: f64) -> u16 {
    (p.clamp(0.0, 1.0) * f64::from(QUANT_MAX)).round() as u16
}

impl ProbabilityGrid {
    /// A grid of `width × height` cells of `resolution_m` whose cell `(0, 0)` has its lower
    /// corner at `origin`; `values` row-major (`j * width + i`), each in `[0, 1]`.
    ///
    /// Errors: `InvalidParameter` for a non-positive resolution, `BadInput` for a non-finite
    /// origin, `values.len() != width · height` or a value that is non-finite or outside
    /// `[0, 1]`.
    pub fn new(
        resolution_m: f64,
        origin: [f64; 2],
        width: usize,
        height: usize,
        values: Vec<f32>,
    ) -> Result<Self> {
        crate::error::require_positive("resolution_m", resolution_m)?;
        if !origin.iter().all(|v| v.is_finite()) {
            return Err(SlamError::BadInput(format!(
                "correlative::ProbabilityGrid::new: non-finite origin {origin:?}"
            )));
        }
        if width.checked_mul(height) != Some(values.len()) {
            return Err(SlamError::BadInput(format!(
                "correlative::ProbabilityGrid::new: {} values for a {width} × {height} grid",
                values.len()
            )));
        }
        if let Some((k, v)) = values
            .iter()
            .enumerate()
            .find(|(_, v)| !(0.0..=1.0).contains(*v))
        {
            return Err(SlamError::BadInput(format!(
                "correlative::ProbabilityGrid::new: value {v} at cell ({}, {}) is not a \
                 probability in [0, 1]",
                k % width.max(1),
                k / width.max(1)
            )));
        }
        let cells = values.iter().map(|&v| quantize(f64::from(v))).collect();
        Ok(Self {
            resolution_m,
            origin,
            width,
            height,
            cells,
        })
    }

    /// The occupancy probability `probability(L)` of each cell of a reflectivity-crate grid,
    /// never-observed cells (log-odds exactly 0) at [`UNKNOWN_PROBABILITY`].
    ///
    /// `bounds = Some([i0, j0, i1, j1])` crops to the half-open index box
    /// `[i0, i1) × [j0, j1)` (the convention of `raypath_reflectivity::export::observed_box`),
    /// clipped to the level; the origin moves to the box's lower corner. An empty box gives
    /// an empty grid (no match can be found in it).
    pub fn from_level(level: &GridLevel, bounds: Option<[usize; 4]>) -> Self {
        let [i0, j0, i1, j1] = bounds.unwrap_or([0, 0, level.width(), level.height()]);
        let (i1, j1) = (i1.min(level.width()), j1.min(level.height()));
        let (i0, j0) = (i0.min(i1), j0.min(j1));
        let (width, height) = (i1 - i0, j1 - j0);
        let mut cells = Vec::with_capacity(width * height);
        for j in j0..j1 {
            for i in i0..i1 {
                let l = level.log_odds(i, j);
                let p = if l == 0.0 {
                    f64::from(UNKNOWN_PROBABILITY)
                } else {
                    probability(l)
                };
                cells.push(quantize(p));
            }
        }
        let res = level.resolution_m();
        let origin = level.origin();
        Self {
            resolution_m: res,
            origin: [origin[0] + i0 as f64 * res, origin[1] + j0 as f64 * res],
            width,
            height,
            cells,
        }
    }

    /// Cell size in metres.
    pub fn resolution_m(&self) -> f64 {
        self.resolution_m
    }

    /// Submap-frame position of the lower corner of cell `(0, 0)`, metres.
    pub fn origin(&self) -> [f64; 2] {
        self.origin
    }

    /// Number of cells along x.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Number of cells along y.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The probability of cell `(i, j)` (as stored, 16-bit precision); 0 outside the grid.
    pub fn value(&self, i: usize, j: usize) -> f32 {
        f32::from(self.quantized(i, j)) / f32::from(QUANT_MAX)
    }

    /// The stored 16-bit value of cell `(i, j)`; 0 outside the grid.
    pub(crate) fn quantized(&self, i: usize, j: usize) -> u16 {
        if i < self.width && j < self.height {
            self.cells.get(j * self.width + i).copied().unwrap_or(0)
        } else {
            0
        }
    }

    /// The stored cells, row-major.
    pub(crate) fn cells(&self) -> &[u16] {
        &self.cells
    }
}
