//! Known-answer tests of the traversal on small grids with exact (dyadic) coordinates.

use nalgebra::{Point2, Point3, Unit, Vector2, Vector3};

use crate::{CellCrossing2, CellCrossing3, Grid2, Grid3, Range, Ray2, Ray3};

fn grid2() -> Grid2 {
    Grid2::new(Point2::new(0.0, 0.0), 1.0, [4, 3]).unwrap()
}

fn walk2(origin: [f64; 2], direction: [f64; 2], length: f64) -> Vec<CellCrossing2> {
    let direction = Unit::new_normalize(Vector2::new(direction[0], direction[1]));
    grid2()
        .traverse(&Point2::new(origin[0], origin[1]), &direction, length)
        .collect()
}

fn cells2(crossings: &[CellCrossing2]) -> Vec<[usize; 2]> {
    crossings.iter().map(|c| c.cell).collect()
}

fn lengths<const N: usize>(crossings: &[crate::CellCrossing<N>]) -> Vec<f64> {
    crossings.iter().map(|c| c.length()).collect()
}

#[test]
fn straight_ray_has_exact_lengths() {
    let c = walk2([0.5, 0.5], [1.0, 0.0], 2.0);
    assert_eq!(cells2(&c), [[0, 0], [1, 0], [2, 0]]);
    assert_eq!(lengths(&c), [0.5, 1.0, 0.5]);
    assert_eq!(c.iter().map(|c| c.index).collect::<Vec<_>>(), [0, 1, 2]);
}

#[test]
fn diagonal_through_vertices_steps_one_axis_at_a_time() {
    // From the grid corner along (1, 1): every boundary is a vertex. Ties step y first, and
    // the intermediate cell has zero length.
    let c = walk2([0.0, 0.0], [1.0, 1.0], 10.0);
    assert_eq!(
        cells2(&c),
        [[0, 0], [0, 1], [1, 1], [1, 2], [2, 2]],
        "{c:?}"
    );
    let s = std::f64::consts::SQRT_2;
    let l = lengths(&c);
    assert!((l[0] - s).abs() < 1e-15 && l[1] == 0.0 && (l[2] - s).abs() < 1e-15);
    assert!(l[3] == 0.0 && (l[4] - s).abs() < 1e-15);
}

#[test]
fn ray_ending_on_a_face_ends_in_the_larger_cell() {
    // Moving up in x and stopping on the face x = 2: the endpoint belongs to cell 2.
    let c = walk2([0.5, 0.5], [1.0, 0.0], 1.5);
    assert_eq!(cells2(&c), [[0, 0], [1, 0], [2, 0]]);
    assert_eq!(c[2].length(), 0.0);
    assert_eq!(grid2().cell_of(&Point2::new(2.0, 0.5)), Some([2, 0]));
    // Moving down in x onto the face x = 1: the ray is already in cell 1.
    let c = walk2([2.5, 0.5], [-1.0, 0.0], 1.5);
    assert_eq!(cells2(&c), [[2, 0], [1, 0]]);
    assert_eq!(lengths(&c), [0.5, 1.0]);
}

#[test]
fn start_on_a_face_moving_down_begins_in_the_lower_cell() {
    let c = walk2([1.0, 0.5], [-1.0, 0.0], 0.5);
    assert_eq!(cells2(&c), [[0, 0]]);
    assert_eq!(lengths(&c), [0.5]);
    let c = walk2([1.0, 0.5], [1.0, 0.0], 0.5);
    assert_eq!(cells2(&c), [[1, 0]]);
}

#[test]
fn ray_along_a_face_is_reported_on_the_larger_index_side() {
    // Along the face y = 1 between rows 0 and 1: row 1, like `cell_of`.
    let c = walk2([2.5, 1.0], [1.0, 0.0], 5.0);
    assert_eq!(cells2(&c), [[2, 1], [3, 1]]);
    assert_eq!(lengths(&c), [0.5, 1.0]);
    assert_eq!(grid2().cell_of(&Point2::new(2.5, 1.0)), Some([2, 1]));
    // Along the grid's upper face y = 3: the last row.
    let c = walk2([2.5, 3.0], [-1.0, 0.0], 1.0);
    assert_eq!(cells2(&c), [[2, 2], [1, 2]]);
}

#[test]
fn rays_from_outside_are_clipped() {
    let c = walk2([-1.0, 0.5], [1.0, 0.0], 10.0);
    assert_eq!(cells2(&c), [[0, 0], [1, 0], [2, 0], [3, 0]]);
    assert_eq!(c[0].t_enter, 1.0);
    assert_eq!(c[3].t_exit, 5.0);
    // Entering through the upper face, moving down.
    let c = walk2([1.5, 5.0], [0.0, -1.0], 10.0);
    assert_eq!(cells2(&c), [[1, 2], [1, 1], [1, 0]]);
    assert_eq!((c[0].t_enter, c[2].t_exit), (2.0, 5.0));
    // Missing the grid, or ending before it.
    assert!(walk2([-1.0, 5.0], [1.0, 0.0], 10.0).is_empty());
    assert!(walk2([-1.0, 0.5], [1.0, 0.0], 0.5).is_empty());
    // Only touching the grid's corner: zero length inside, nothing.
    assert!(walk2([-1.0, -1.0], [1.0, 1.0], 1.0).is_empty());
    assert!(walk2([-1.0, 1.0], [1.0, -1.0], 10.0).is_empty());
}

#[test]
fn degenerate_inputs_yield_nothing() {
    assert!(walk2([0.5, 0.5], [1.0, 0.0], 0.0).is_empty());
    assert!(walk2([0.5, 0.5], [1.0, 0.0], -1.0).is_empty());
    assert!(walk2([0.5, 0.5], [1.0, 0.0], f64::NAN).is_empty());
    assert!(walk2([f64::NAN, 0.5], [1.0, 0.0], 1.0).is_empty());
    let bad = Unit::new_unchecked(Vector2::new(f64::NAN, 0.0));
    assert_eq!(
        grid2().traverse(&Point2::new(0.5, 0.5), &bad, 1.0).count(),
        0
    );
    // Leaving the grid through its upper face immediately.
    assert!(walk2([4.0, 0.5], [1.0, 0.0], 1.0).is_empty());
}

#[test]
fn infinite_length_traces_to_the_grid_boundary() {
    let c = walk2([0.5, 2.5], [1.0, 0.0], f64::INFINITY);
    assert_eq!(c.len(), 4);
    assert_eq!(c[3].t_exit, 3.5);
}

#[test]
fn no_returns_are_cut_at_max_range_and_hits_beyond_it_too() {
    let grid = grid2();
    let origin = Point2::new(0.5, 0.5);
    let no_return = Ray2::new(origin, Vector2::new(1.0, 0.0), Range::NoReturn).unwrap();
    let c: Vec<_> = grid.traverse_ray(&no_return, 2.0).collect();
    assert_eq!(cells2(&c), [[0, 0], [1, 0], [2, 0]]);
    assert_eq!(c[2].t_exit, 2.0);
    let far_hit = Ray2::new(origin, Vector2::new(1.0, 0.0), Range::Hit(3.0)).unwrap();
    assert_eq!(grid.traverse_ray(&far_hit, 2.0).count(), 3);
    let near_hit = Ray2::new(origin, Vector2::new(1.0, 0.0), Range::Hit(0.25)).unwrap();
    assert_eq!(
        cells2(&grid.traverse_ray(&near_hit, 2.0).collect::<Vec<_>>()),
        [[0, 0]]
    );
}

#[test]
fn space_diagonal_through_vertices_in_3d() {
    let grid = Grid3::new(Point3::new(-1.0, -1.0, -1.0), 0.5, [4, 4, 4]).unwrap();
    let direction = Unit::new_normalize(Vector3::new(1.0, 1.0, 1.0));
    let c: Vec<CellCrossing3> = grid
        .traverse(&Point3::new(-1.0, -1.0, -1.0), &direction, 100.0)
        .collect();
    // Four diagonal cells, each followed (except the last) by two zero-length steps z, y.
    let cells: Vec<_> = c.iter().map(|c| c.cell).collect();
    assert_eq!(
        cells,
        [
            [0, 0, 0],
            [0, 0, 1],
            [0, 1, 1],
            [1, 1, 1],
            [1, 1, 2],
            [1, 2, 2],
            [2, 2, 2],
            [2, 2, 3],
            [2, 3, 3],
            [3, 3, 3]
        ]
    );
    let diagonal = 0.5 * 3f64.sqrt();
    for (k, crossing) in c.iter().enumerate() {
        let expected = if k % 3 == 0 { diagonal } else { 0.0 };
        assert!(
            (crossing.length() - expected).abs() < 1e-12,
            "{k}: {crossing:?}"
        );
        assert_eq!(crossing.index, grid.linear_index(crossing.cell));
    }
}

#[test]
fn hit_endpoint_cell_matches_cell_of_in_3d() {
    let grid = Grid3::new(Point3::new(0.0, 0.0, 0.0), 0.25, [8, 8, 8]).unwrap();
    let ray = Ray3::between(Point3::new(0.1, 0.2, 0.3), Point3::new(1.5, 0.75, 1.0)).unwrap();
    let last = grid.traverse_ray(&ray, 10.0).last().unwrap();
    assert_eq!(Some(last.cell), grid.cell_of(&ray.endpoint().unwrap()));
}

#[test]
fn exact_size_and_fused() {
    let grid = Grid3::new(Point3::origin(), 1.0, [5, 5, 5]).unwrap();
    let direction = Unit::new_normalize(Vector3::new(1.0, 0.3, 0.2));
    let mut walk = grid.traverse(&Point3::new(0.5, 0.5, 0.5), &direction, 100.0);
    let n = walk.len();
    assert_eq!(n, walk.clone().count());
    walk.next();
    assert_eq!(walk.len(), n - 1);
    let rest: f64 = walk.by_ref().map(|c| c.length()).sum();
    assert!(rest > 0.0);
    assert_eq!(walk.len(), 0);
    assert!(walk.next().is_none());
}

#[test]
fn degenerate_entry_onto_a_face_keeps_the_endpoint_cell() {
    // Found by the property tests: a segment from outside that ends exactly on the grid's
    // lower x face and on the face y = 2 (between rows 1 and 2), moving down in y. Rounding
    // leaves a ~1e-16 m piece inside the grid; its cell must be `cell_of(endpoint)`.
    let grid = Grid2::new(Point2::new(-2.006482540402752, 1.875), 0.0625, [2, 11]).unwrap();
    let origin = Point2::new(-2.193982540402752, 2.046033747762146);
    let end = Point2::new(-2.006482540402752, 2.0);
    let ray = Ray2::new(origin, end - origin, Range::Hit((end - origin).norm())).unwrap();
    let crossings: Vec<_> = grid.traverse_ray(&ray, f64::INFINITY).collect();
    assert_eq!(crossings.len(), 1, "{crossings:?}");
    assert_eq!(
        Some(crossings[0].cell),
        grid.cell_of(&ray.endpoint().unwrap())
    );
    assert_eq!(crossings[0].cell, [0, 2]);
    assert!(crossings.iter().map(|c| c.length()).sum::<f64>() < 1e-12);
}
