//! Property tests of the Amanatides–Woo traversal in 2-D and 3-D.
//!
//! Every traversal is checked against the traversal contract and against a dense-sampling
//! reference: the segment is sampled at steps of a fraction of a cell, samples within 1e-9 m of
//! a cell face are ignored, and the cells of the remaining samples must all be reported. Cells
//! the samples did not see are allowed only where the ray grazes them: a crossing shorter than
//! the sampling step (a clipped corner) or one lying within tolerance of the cell's boundary
//! (a ray along a face).

use std::collections::HashSet;

use nalgebra::{Point2, Point3, Unit, Vector2, Vector3};
use proptest::prelude::*;
use raypath_geometry::testing::{direction2, direction3, grid2, grid3, ray2_in, ray3_in};
use raypath_geometry::{Aabb2, Aabb3, CellCrossing, Grid2, Grid3, Range, Ray2, Ray3};

/// Position tolerance in metres (coordinates stay within ~100 m).
const POSITION_TOL_M: f64 = 1e-9;

/// Generates `check2`/`check3`: all invariants of one traversal.
macro_rules! checker {
    ($check:ident, $grid:ident, $point:ident, $vector:ident, $aabb:ident, $dim:literal) => {
        /// Checks one traversal of `origin + t·direction`, `t ∈ [0, length]`. `is_hit` says
        /// whether the segment's end is a reflection (then its cell is checked).
        fn $check(
            grid: &$grid,
            origin: &$point<f64>,
            direction: &Unit<$vector<f64>>,
            length: f64,
            is_hit: bool,
        ) -> Result<(), TestCaseError> {
            // Collected twice: through `next` and through the `fold` fast path.
            let mut by_next = Vec::new();
            let mut traversal = grid.traverse(origin, direction, length);
            let announced = traversal.len();
            while let Some(crossing) = traversal.next() {
                by_next.push(crossing);
            }
            prop_assert!(traversal.next().is_none(), "not fused");
            let mut by_fold = Vec::new();
            grid.traverse(origin, direction, length)
                .for_each(|crossing| by_fold.push(crossing));
            prop_assert_eq!(&by_next, &by_fold);
            prop_assert_eq!(announced, by_next.len());
            let crossings = by_next;

            let d = direction.into_inner();
            let clip = if length > 0.0 {
                grid.bounds().clip_segment(origin, &d, 0.0, length)
            } else {
                None
            };
            let (t0, t1) = match clip {
                Some((t0, t1)) if t1 > t0 => (t0, t1),
                _ => {
                    prop_assert!(
                        crossings.is_empty(),
                        "degenerate segment gave {crossings:?}"
                    );
                    return Ok(());
                }
            };
            prop_assert!(!crossings.is_empty());

            // Contiguous intervals covering exactly [t0, t1].
            prop_assert_eq!(crossings[0].t_enter, t0);
            prop_assert_eq!(crossings[crossings.len() - 1].t_exit, t1);
            for pair in crossings.windows(2) {
                prop_assert_eq!(pair[1].t_enter, pair[0].t_exit);
            }
            let total: f64 = crossings.iter().map(CellCrossing::length).sum();
            prop_assert!(
                (total - (t1 - t0)).abs() <= 1e-9 * (t1 - t0).max(1e-3),
                "lengths sum to {total}, clipped length {}",
                t1 - t0
            );

            // Cells: inside, correct index, face neighbours, no repeats.
            let dims = grid.dims();
            for c in &crossings {
                prop_assert!(c.length() >= 0.0);
                prop_assert!((0..$dim).all(|i| c.cell[i] < dims[i]));
                prop_assert_eq!(c.index, grid.linear_index(c.cell));
            }
            for pair in crossings.windows(2) {
                let diff: usize = (0..$dim)
                    .map(|i| pair[0].cell[i].abs_diff(pair[1].cell[i]))
                    .sum();
                prop_assert_eq!(diff, 1, "{:?} -> {:?}", pair[0].cell, pair[1].cell);
            }
            let unique: HashSet<_> = crossings.iter().map(|c| c.cell).collect();
            prop_assert_eq!(unique.len(), crossings.len(), "a cell is repeated");

            // Each interval lies in its cell (entry, exit and midpoint within tolerance).
            let cell = grid.cell_size();
            let g = grid.origin();
            let lattice = |p: &$point<f64>, i: usize| (p[i] - g[i]) / cell;
            let tol = POSITION_TOL_M / cell;
            for c in &crossings {
                for t in [c.t_enter, 0.5 * (c.t_enter + c.t_exit), c.t_exit] {
                    let p = origin + d * t;
                    for i in 0..$dim {
                        let u = lattice(&p, i);
                        let lo = c.cell[i] as f64;
                        prop_assert!(
                            u >= lo - tol && u <= lo + 1.0 + tol,
                            "t = {t} puts axis {i} at {u}, outside cell {:?}",
                            c.cell
                        );
                    }
                }
            }

            // Dense-sampling reference.
            let step = (cell / 64.0).max((t1 - t0) / 20_000.0);
            let mut reference = HashSet::new();
            let samples = ((t1 - t0) / step).ceil() as usize;
            for k in 0..=samples {
                let t = (t0 + k as f64 * step).min(t1);
                let p = origin + d * t;
                let near_face = (0..$dim).any(|i| {
                    let u = lattice(&p, i);
                    (u - u.round()).abs() * cell < POSITION_TOL_M
                });
                if near_face {
                    continue;
                }
                if let Some(c) = grid.cell_of(&p) {
                    reference.insert(c);
                }
            }
            let reported: HashSet<_> = crossings.iter().map(|c| c.cell).collect();
            let missing: Vec<_> = reference.difference(&reported).collect();
            prop_assert!(
                missing.is_empty(),
                "cells {missing:?} sampled but not reported"
            );
            for c in crossings.iter().filter(|c| !reference.contains(&c.cell)) {
                let mid = origin + d * (0.5 * (c.t_enter + c.t_exit));
                let grazing = (0..$dim).any(|i| {
                    let u = lattice(&mid, i);
                    let lo = c.cell[i] as f64;
                    (u - lo).abs() <= tol || (u - lo - 1.0).abs() <= tol
                });
                prop_assert!(
                    c.length() <= 2.0 * step || grazing,
                    "cell {:?} reported with length {} but never sampled",
                    c.cell,
                    c.length()
                );
            }

            // The last cell of a hit inside the grid is the endpoint's cell.
            if is_hit && t1 == length {
                let endpoint = origin + d * length;
                if let Some(end_cell) = grid.cell_of(&endpoint) {
                    prop_assert_eq!(crossings[crossings.len() - 1].cell, end_cell);
                }
            }
            Ok(())
        }
    };
}

checker!(check2, Grid2, Point2, Vector2, Aabb2, 2);
checker!(check3, Grid3, Point3, Vector3, Aabb3, 3);

/// Checks a sensor ray through `traverse_ray` and compares with `traverse`.
fn check_ray3(grid: &Grid3, ray: &Ray3, max_range: f64) -> Result<(), TestCaseError> {
    let length = ray.range.traced_length(max_range);
    let a: Vec<_> = grid.traverse_ray(ray, max_range).collect();
    let b: Vec<_> = grid.traverse(&ray.origin, &ray.direction, length).collect();
    prop_assert_eq!(a, b);
    let is_hit = matches!(ray.range, Range::Hit(r) if r <= max_range);
    check3(grid, &ray.origin, &ray.direction, length, is_hit)
}

fn check_ray2(grid: &Grid2, ray: &Ray2, max_range: f64) -> Result<(), TestCaseError> {
    let length = ray.range.traced_length(max_range);
    let a: Vec<_> = grid.traverse_ray(ray, max_range).collect();
    let b: Vec<_> = grid.traverse(&ray.origin, &ray.direction, length).collect();
    prop_assert_eq!(a, b);
    let is_hit = matches!(ray.range, Range::Hit(r) if r <= max_range);
    check2(grid, &ray.origin, &ray.direction, length, is_hit)
}

/// The grid box grown by its extents on every side.
fn around3(grid: &Grid3) -> Aabb3 {
    let b = grid.bounds();
    let e = b.extents();
    Aabb3::new(b.min - e, b.max + e)
}

fn around2(grid: &Grid2) -> Aabb2 {
    let b = grid.bounds();
    let e = b.extents();
    Aabb2::new(b.min - e, b.max + e)
}

/// A coordinate along one axis: arbitrary in the grown box, or exactly on a lattice plane
/// (`origin + k · cell`, also just outside the grid).
fn coordinate(min: f64, cell: f64, dim: usize) -> impl Strategy<Value = f64> {
    let dim = dim as i64;
    prop_oneof![
        (-(dim + 1)..=2 * dim + 1).prop_map(move |k| min + k as f64 * cell),
        (-1.0..=2.0f64).prop_map(move |a| min + a * dim as f64 * cell),
    ]
}

/// A point whose coordinates are often on lattice planes (faces, edges, vertices).
fn snapped3(grid: Grid3) -> impl Strategy<Value = Point3<f64>> {
    let (g, c, n) = (grid.origin(), grid.cell_size(), grid.dims());
    (
        coordinate(g.x, c, n[0]),
        coordinate(g.y, c, n[1]),
        coordinate(g.z, c, n[2]),
    )
        .prop_map(|(x, y, z)| Point3::new(x, y, z))
}

fn snapped2(grid: Grid2) -> impl Strategy<Value = Point2<f64>> {
    let (g, c, n) = (grid.origin(), grid.cell_size(), grid.dims());
    (coordinate(g.x, c, n[0]), coordinate(g.y, c, n[1])).prop_map(|(x, y)| Point2::new(x, y))
}

/// A segment length: random, zero, or infinite.
fn length(reach: f64) -> impl Strategy<Value = f64> {
    prop_oneof![8 => 0.0..reach, 1 => Just(0.0), 1 => Just(f64::INFINITY)]
}

fn config() -> ProptestConfig {
    ProptestConfig::with_cases(3000)
}

proptest! {
    #![proptest_config(config())]

    /// Sensor rays starting inside the grid: hits (possibly beyond it or beyond the maximum
    /// range) and no-returns cut at the maximum range.
    #[test]
    fn rays_from_inside_3d(
        (grid, ray, max_range) in grid3().prop_flat_map(|g| {
            let reach = 2.0 * g.bounds().extents().norm();
            (Just(g), ray3_in(g.bounds()), 0.0..reach)
        })
    ) {
        check_ray3(&grid, &ray, max_range)?;
    }

    #[test]
    fn rays_from_inside_2d(
        (grid, ray, max_range) in grid2().prop_flat_map(|g| {
            let reach = 2.0 * g.bounds().extents().norm();
            (Just(g), ray2_in(g.bounds()), 0.0..reach)
        })
    ) {
        check_ray2(&grid, &ray, max_range)?;
    }

    /// Segments from anywhere around the grid, aimed at a point inside it, of any length.
    #[test]
    fn segments_from_outside_3d(
        (grid, origin, target, len) in grid3().prop_flat_map(|g| {
            let reach = 3.0 * g.bounds().extents().norm();
            (Just(g), raypath_geometry::testing::point3_in(around3(&g)),
             raypath_geometry::testing::point3_in(g.bounds()), length(reach))
        })
    ) {
        if let Some(direction) = Unit::try_new(target - origin, 1e-12) {
            check3(&grid, &origin, &direction, len, true)?;
        }
    }

    #[test]
    fn segments_from_outside_2d(
        (grid, origin, target, len) in grid2().prop_flat_map(|g| {
            let reach = 3.0 * g.bounds().extents().norm();
            (Just(g), raypath_geometry::testing::point2_in(around2(&g)),
             raypath_geometry::testing::point2_in(g.bounds()), length(reach))
        })
    ) {
        if let Some(direction) = Unit::try_new(target - origin, 1e-12) {
            check2(&grid, &origin, &direction, len, true)?;
        }
    }

    /// Origins on faces, edges and vertices, with axis-parallel and diagonal directions: rays
    /// along faces and through corners.
    #[test]
    fn lattice_aligned_rays_3d(
        (grid, origin, direction, len) in grid3().prop_flat_map(|g| {
            let reach = 3.0 * g.bounds().extents().norm();
            (Just(g), snapped3(g), direction3(), length(reach))
        })
    ) {
        check3(&grid, &origin, &direction, len, true)?;
    }

    #[test]
    fn lattice_aligned_rays_2d(
        (grid, origin, direction, len) in grid2().prop_flat_map(|g| {
            let reach = 3.0 * g.bounds().extents().norm();
            (Just(g), snapped2(g), direction2(), length(reach))
        })
    ) {
        check2(&grid, &origin, &direction, len, true)?;
    }

    /// Segments between two lattice-snapped points: they end on faces, edges and vertices,
    /// so the endpoint's cell follows the face tie-break.
    #[test]
    fn segments_ending_on_faces_3d(
        (grid, origin, end) in grid3().prop_flat_map(|g| (Just(g), snapped3(g), snapped3(g)))
    ) {
        if let Some(ray) = Ray3::between(origin, end) {
            check_ray3(&grid, &ray, f64::INFINITY)?;
        }
    }

    #[test]
    fn segments_ending_on_faces_2d(
        (grid, origin, end) in grid2().prop_flat_map(|g| (Just(g), snapped2(g), snapped2(g)))
    ) {
        let delta = end - origin;
        if let Some(ray) = Ray2::new(origin, delta, Range::Hit(delta.norm())) {
            check_ray2(&grid, &ray, f64::INFINITY)?;
        }
    }

    /// Zero-length rays yield nothing, wherever they start.
    #[test]
    fn zero_length_rays_yield_nothing(
        (grid, origin, direction) in grid3().prop_flat_map(|g| (Just(g), snapped3(g), direction3()))
    ) {
        prop_assert_eq!(grid.traverse(&origin, &direction, 0.0).count(), 0);
        let ray = Ray3 { origin, direction, range: Range::Hit(0.0) };
        prop_assert_eq!(grid.traverse_ray(&ray, 10.0).count(), 0);
        let no_return = Ray3 { origin, direction, range: Range::NoReturn };
        prop_assert_eq!(grid.traverse_ray(&no_return, 0.0).count(), 0);
    }
}
