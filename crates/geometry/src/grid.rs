//! Uniform grids: index maths between metric points, integer cells and linear indices.
//!
//! A grid covers the box `[origin, origin + dims · cell_size)` with square (2-D) or cubic
//! (3-D) cells of edge `cell_size` metres. Cell `c` spans
//! `[origin + c · cell_size, origin + (c + 1) · cell_size)`, so points on a shared face
//! belong to the cell with the larger index (the grid's upper faces are its closed end).
//! Linear indices run x fastest, then y, then z — the layout of every dense map in raypath.

use nalgebra::{Point2, Point3, Vector2, Vector3};
use serde::{Deserialize, Serialize};

use crate::{Aabb2, Aabb3, GeometryError};

macro_rules! grid_impl {
    ($name:ident, $point:ident, $vector:ident, $aabb:ident, $dim:literal, $doc:literal) => {
        #[doc = $doc]
        #[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
        pub struct $name {
            /// The grid's lower corner in metres.
            origin: $point<f64>,
            /// Edge length of a cell in metres.
            cell_size: f64,
            /// Number of cells along each axis.
            dims: [usize; $dim],
        }

        impl $name {
            /// A grid with lower corner `origin`, cells of edge `cell_size` metres and `dims`
            /// cells per axis. Fails for a non-positive or non-finite cell size, a
            /// non-finite origin, a zero dimension or more than `2^40` cells.
            pub fn new(
                origin: $point<f64>,
                cell_size: f64,
                dims: [usize; $dim],
            ) -> Result<Self, GeometryError> {
                if !(cell_size.is_finite() && cell_size > 0.0) {
                    return Err(GeometryError::InvalidGrid {
                        reason: format!("cell size must be positive and finite, got {cell_size}"),
                    });
                }
                if !origin.iter().all(|v| v.is_finite()) {
                    return Err(GeometryError::InvalidGrid {
                        reason: format!("origin must be finite, got {origin:?}"),
                    });
                }
                let mut total: u128 = 1;
                for &d in &dims {
                    total *= d as u128;
                }
                if total == 0 || total > 1 << 40 {
                    return Err(GeometryError::InvalidGrid {
                        reason: format!(
                            "dimensions {dims:?} give {total} cells (allowed 1 to 2^40)"
                        ),
                    });
                }
                Ok(Self {
                    origin,
                    cell_size,
                    dims,
                })
            }

            /// The smallest grid with cells of `cell_size` metres whose lower corner is
            /// `aabb.min` and that contains the whole box.
            pub fn covering(aabb: &$aabb, cell_size: f64) -> Result<Self, GeometryError> {
                if aabb.is_empty() {
                    return Err(GeometryError::InvalidGrid {
                        reason: "cannot cover an empty box".into(),
                    });
                }
                let extents = aabb.extents();
                let mut dims = [0usize; $dim];
                for i in 0..$dim {
                    let cells = (extents[i] / cell_size).floor() + 1.0;
                    if !cells.is_finite() || cells > 1e12 {
                        return Err(GeometryError::InvalidGrid {
                            reason: format!("box of extent {} m needs too many cells", extents[i]),
                        });
                    }
                    dims[i] = cells as usize;
                }
                Self::new(aabb.min, cell_size, dims)
            }

            /// The lower corner in metres.
            pub fn origin(&self) -> $point<f64> {
                self.origin
            }

            /// Cell edge length in metres.
            pub fn cell_size(&self) -> f64 {
                self.cell_size
            }

            /// Number of cells along each axis.
            pub fn dims(&self) -> [usize; $dim] {
                self.dims
            }

            /// Total number of cells.
            pub fn num_cells(&self) -> usize {
                self.dims.iter().product()
            }

            /// The region the grid covers.
            pub fn bounds(&self) -> $aabb {
                let mut max = self.origin;
                for i in 0..$dim {
                    max[i] += self.dims[i] as f64 * self.cell_size;
                }
                $aabb {
                    min: self.origin,
                    max,
                }
            }

            /// Lattice coordinates of the cell containing `point` (may lie outside the grid):
            /// `floor((point − origin) / cell_size)` per axis.
            pub fn lattice_coords(&self, point: &$point<f64>) -> [i64; $dim] {
                let mut c = [0i64; $dim];
                for i in 0..$dim {
                    c[i] = ((point[i] - self.origin[i]) / self.cell_size).floor() as i64;
                }
                c
            }

            /// The cell containing `point`, or `None` outside the grid.
            pub fn cell_of(&self, point: &$point<f64>) -> Option<[usize; $dim]> {
                self.checked_cell(self.lattice_coords(point))
            }

            /// Converts lattice coordinates to a cell of this grid, `None` outside.
            pub fn checked_cell(&self, lattice: [i64; $dim]) -> Option<[usize; $dim]> {
                let mut c = [0usize; $dim];
                for i in 0..$dim {
                    if lattice[i] < 0 || lattice[i] as u64 >= self.dims[i] as u64 {
                        return None;
                    }
                    c[i] = lattice[i] as usize;
                }
                Some(c)
            }

            /// The linear index of a cell (x fastest). The cell must lie inside the grid.
            #[inline]
            pub fn linear_index(&self, cell: [usize; $dim]) -> usize {
                let mut index = 0;
                let mut stride = 1;
                for i in 0..$dim {
                    debug_assert!(
                        cell[i] < self.dims[i],
                        "cell {cell:?} outside {:?}",
                        self.dims
                    );
                    index += cell[i] * stride;
                    stride *= self.dims[i];
                }
                index
            }

            /// The cell of a linear index (inverse of [`Self::linear_index`]).
            pub fn cell_from_linear(&self, mut index: usize) -> [usize; $dim] {
                let mut cell = [0usize; $dim];
                for i in 0..$dim {
                    cell[i] = index % self.dims[i];
                    index /= self.dims[i];
                }
                cell
            }

            /// The region of one cell.
            pub fn cell_bounds(&self, cell: [usize; $dim]) -> $aabb {
                let mut min = self.origin;
                for i in 0..$dim {
                    min[i] += cell[i] as f64 * self.cell_size;
                }
                $aabb {
                    min,
                    max: min + $vector::repeat(self.cell_size),
                }
            }

            /// The centre of one cell.
            pub fn cell_center(&self, cell: [usize; $dim]) -> $point<f64> {
                self.cell_bounds(cell).center()
            }
        }
    };
}

grid_impl!(
    Grid2,
    Point2,
    Vector2,
    Aabb2,
    2,
    "A uniform 2-D grid of square cells."
);
grid_impl!(
    Grid3,
    Point3,
    Vector3,
    Aabb3,
    3,
    "A uniform 3-D grid of cubic cells (voxels)."
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_index_round_trip() {
        let grid = Grid3::new(Point3::new(-1.0, -2.0, 0.5), 0.25, [3, 4, 5]).unwrap();
        for index in 0..grid.num_cells() {
            assert_eq!(grid.linear_index(grid.cell_from_linear(index)), index);
        }
        assert_eq!(grid.linear_index([1, 0, 0]), 1);
        assert_eq!(grid.linear_index([0, 1, 0]), 3);
        assert_eq!(grid.linear_index([0, 0, 1]), 12);
    }

    #[test]
    fn cell_of_faces_and_outside() {
        let grid = Grid2::new(Point2::new(0.0, 0.0), 1.0, [2, 2]).unwrap();
        assert_eq!(grid.cell_of(&Point2::new(1.0, 0.5)), Some([1, 0]));
        assert_eq!(grid.cell_of(&Point2::new(-0.1, 0.5)), None);
        assert_eq!(grid.cell_of(&Point2::new(2.0, 0.5)), None);
        assert_eq!(grid.lattice_coords(&Point2::new(-0.1, 5.5)), [-1, 5]);
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(Grid2::new(Point2::origin(), 0.0, [1, 1]).is_err());
        assert!(Grid2::new(Point2::origin(), f64::NAN, [1, 1]).is_err());
        assert!(Grid2::new(Point2::origin(), 1.0, [0, 1]).is_err());
        assert!(Grid3::new(Point3::origin(), 1.0, [1 << 20, 1 << 20, 2]).is_err());
    }

    #[test]
    fn covering_contains_box() {
        let aabb = Aabb3::new(Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 0.3, 0.0));
        let grid = Grid3::covering(&aabb, 0.1).unwrap();
        assert!(grid.cell_of(&aabb.max).is_some());
    }
}
