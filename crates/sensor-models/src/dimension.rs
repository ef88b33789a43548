//! 2-D and 3-D behind one small trait, so that statistics and models are written once.
//!
//! [`Planar`] (grids of square cells, [`Ray2`]) and [`Spatial`] (grids of cubic voxels,
//! [`Ray3`]) are zero-sized markers. The crate's public types are generic over them and
//! have concrete aliases (`DenseStats2 = DenseStats<Planar>`, …); user code names the
//! aliases and never implements [`Dimension`] (it is sealed).

use std::fmt::Debug;

use nalgebra::{Point2, Point3};
use raypath_geometry::{CellCrossing, Grid2, Grid3, Range, Ray2, Ray3, Traversal2, Traversal3};

mod sealed {
    pub trait Sealed {}
    impl Sealed for super::Planar {}
    impl Sealed for super::Spatial {}
}

/// The plane: [`Grid2`], [`Ray2`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Planar;

/// Space: [`Grid3`], [`Ray3`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Spatial;

/// What the crate needs from a dimension: its grid and ray types, the exact traversal and
/// a few cell queries. Sealed; implemented by [`Planar`] and [`Spatial`].
pub trait Dimension: sealed::Sealed + Copy + Debug + Default + Send + Sync + 'static {
    /// Number of axes (2 or 3).
    const AXES: usize;
    /// The grid type ([`Grid2`] or [`Grid3`]).
    type Grid: Copy + Debug + PartialEq + Send + Sync;
    /// The ray type ([`Ray2`] or [`Ray3`]).
    type Ray: Copy + Debug + Send + Sync;
    /// The traversal iterator of the grid.
    type Traversal: Iterator<Item = Self::Crossing>;
    /// One cell crossed by a traversal.
    type Crossing: Crossing;

    /// The cells `ray` crosses from its origin up to `length_m` (exact Amanatides–Woo
    /// traversal of `raypath-geometry`; the segment is clipped to the grid).
    fn traverse(grid: &Self::Grid, ray: &Self::Ray, length_m: f64) -> Self::Traversal;
    /// What the ray returned.
    fn range(ray: &Self::Ray) -> Range;
    /// Number of cells of the grid.
    fn num_cells(grid: &Self::Grid) -> usize;
    /// Cell edge in metres.
    fn cell_size(grid: &Self::Grid) -> f64;
    /// Cells per axis, padded with 1 to three axes.
    fn dims3(grid: &Self::Grid) -> [usize; 3];
    /// Linear index of the cell containing the point at `t_m` along the ray, `None` outside
    /// the grid (faces belong to the cell with the larger index, like `cell_of`).
    fn cell_index_at(grid: &Self::Grid, ray: &Self::Ray, t_m: f64) -> Option<usize>;
    /// The interval `[t_enter, t_exit]` in which the ray's infinite line lies in the cell
    /// with linear index `index` (the chord of the cell; empty when `t_exit <= t_enter`).
    fn chord(grid: &Self::Grid, ray: &Self::Ray, index: usize) -> (f64, f64);
    /// The part `[t0, t1]` of `[0, length_m]` inside the grid box, `None` when the segment
    /// misses the box.
    fn clip(grid: &Self::Grid, ray: &Self::Ray, length_m: f64) -> Option<(f64, f64)>;
}

/// What the crate reads from a traversal step; implemented for [`CellCrossing`].
pub trait Crossing: Copy {
    /// Linear index of the cell (x fastest).
    fn index(&self) -> usize;
    /// Cell coordinates padded with 0 to three axes.
    fn cell3(&self) -> [usize; 3];
    /// Entry parameter in metres.
    fn t_enter(&self) -> f64;
    /// Exit parameter in metres.
    fn t_exit(&self) -> f64;
    /// In-cell path length `d_i` in metres.
    #[inline]
    fn length(&self) -> f64 {
        self.t_exit() - self.t_enter()
    }
}

impl<const N: usize> Crossing for CellCrossing<N> {
    #[inline(always)]
    fn index(&self) -> usize {
        self.index
    }
    #[inline(always)]
    fn cell3(&self) -> [usize; 3] {
        let mut c = [0; 3];
        for (axis, value) in self.cell.iter().enumerate().take(3) {
            c[axis] = *value;
        }
        c
    }
    #[inline(always)]
    fn t_enter(&self) -> f64 {
        self.t_enter
    }
    #[inline(always)]
    fn t_exit(&self) -> f64 {
        self.t_exit
    }
}

/// Chord of a ray's line through an axis-aligned cell: slab intersection.
#[inline]
fn chord_slabs<const N: usize>(
    origin: [f64; N],
    direction: [f64; N],
    min: [f64; N],
    size: f64,
) -> (f64, f64) {
    let mut t0 = f64::NEG_INFINITY;
    let mut t1 = f64::INFINITY;
    for axis in 0..N {
        let d = direction[axis];
        let lo = min[axis];
        let hi = lo + size;
        if d == 0.0 {
            if origin[axis] < lo || origin[axis] > hi {
                return (0.0, 0.0);
            }
            continue;
        }
        let a = (lo - origin[axis]) / d;
        let b = (hi - origin[axis]) / d;
        let (near, far) = if a < b { (a, b) } else { (b, a) };
        t0 = t0.max(near);
        t1 = t1.min(far);
    }
    (t0, t1)
}

impl Dimension for Planar {
    const AXES: usize = 2;
    type Grid = Grid2;
    type Ray = Ray2;
    type Traversal = Traversal2;
    type Crossing = CellCrossing<2>;

    #[inline]
    fn traverse(grid: &Grid2, ray: &Ray2, length_m: f64) -> Traversal2 {
        grid.traverse(&ray.origin, &ray.direction, length_m)
    }
    #[inline]
    fn range(ray: &Ray2) -> Range {
        ray.range
    }
    fn num_cells(grid: &Grid2) -> usize {
        grid.num_cells()
    }
    #[inline]
    fn cell_size(grid: &Grid2) -> f64 {
        grid.cell_size()
    }
    fn dims3(grid: &Grid2) -> [usize; 3] {
        let [x, y] = grid.dims();
        [x, y, 1]
    }
    #[inline]
    fn cell_index_at(grid: &Grid2, ray: &Ray2, t_m: f64) -> Option<usize> {
        let point: Point2<f64> = ray.at(t_m);
        grid.cell_of(&point).map(|c| grid.linear_index(c))
    }
    #[inline]
    fn chord(grid: &Grid2, ray: &Ray2, index: usize) -> (f64, f64) {
        let cell = grid.cell_from_linear(index);
        let min = grid.cell_bounds(cell).min;
        chord_slabs(
            ray.origin.coords.into(),
            ray.direction.into_inner().into(),
            min.coords.into(),
            grid.cell_size(),
        )
    }
    #[inline]
    fn clip(grid: &Grid2, ray: &Ray2, length_m: f64) -> Option<(f64, f64)> {
        grid.bounds()
            .clip_segment(&ray.origin, ray.direction.as_ref(), 0.0, length_m)
    }
}

impl Dimension for Spatial {
    const AXES: usize = 3;
    type Grid = Grid3;
    type Ray = Ray3;
    type Traversal = Traversal3;
    type Crossing = CellCrossing<3>;

    #[inline]
    fn traverse(grid: &Grid3, ray: &Ray3, length_m: f64) -> Traversal3 {
        grid.traverse(&ray.origin, &ray.direction, length_m)
    }
    #[inline]
    fn range(ray: &Ray3) -> Range {
        ray.range
    }
    fn num_cells(grid: &Grid3) -> usize {
        grid.num_cells()
    }
    #[inline]
    fn cell_size(grid: &Grid3) -> f64 {
        grid.cell_size()
    }
    fn dims3(grid: &Grid3) -> [usize; 3] {
        grid.dims()
    }
    #[inline]
    fn cell_index_at(grid: &Grid3, ray: &Ray3, t_m: f64) -> Option<usize> {
        let point: Point3<f64> = ray.at(t_m);
        grid.cell_of(&point).map(|c| grid.linear_index(c))
    }
    #[inline]
    fn chord(grid: &Grid3, ray: &Ray3, index: usize) -> (f64, f64) {
        let cell = grid.cell_from_linear(index);
        let min = grid.cell_bounds(cell).min;
        chord_slabs(
            ray.origin.coords.into(),
            ray.direction.into_inner().into(),
            min.coords.into(),
            grid.cell_size(),
        )
    }
    #[inline]
    fn clip(grid: &Grid3, ray: &Ray3, length_m: f64) -> Option<(f64, f64)> {
        grid.bounds()
            .clip_segment(&ray.origin, ray.direction.as_ref(), 0.0, length_m)
    }
}
