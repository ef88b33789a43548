//! The slab walk against `Grid3::traverse`: the same voxels.

use nalgebra::{Point3, Unit};
use proptest::prelude::*;

use super::{SlabWalk, SlabWalkEnd};
use crate::Grid3;

/// The reference: the voxels `Grid3::traverse` yields, in order, and where it ended (the
/// last voxel, and whether it is `cell_of(endpoint)`).
fn reference(
    grid: &Grid3,
    origin: &Point3<f64>,
    endpoint: &Point3<f64>,
) -> (Vec<usize>, Option<SlabWalkEnd>) {
    let delta = endpoint - origin;
    let length = delta.norm();
    if !(length > 0.0 && length.is_finite()) {
        return (Vec::new(), None);
    }
    let direction = Unit::new_unchecked(delta / length);
    let path: Vec<usize> = grid
        .traverse(origin, &direction, length)
        .map(|c| c.index)
        .collect();
    let end = path.last().map(|&last| SlabWalkEnd {
        last,
        contains_endpoint: grid
            .cell_of(endpoint)
            .is_some_and(|cell| grid.linear_index(cell) == last),
    });
    (path, end)
}

/// Whether the voxels form one face-connected chain.
fn connected(grid: &Grid3, voxels: &[usize]) -> bool {
    let [nx, ny, _] = grid.dims();
    let coords = |i: usize| [i % nx, (i / nx) % ny, i / (nx * ny)];
    let mut reached = vec![false; voxels.len()];
    let mut stack = vec![0];
    while let Some(k) = stack.pop() {
        if std::mem::replace(&mut reached[k], true) {
            continue;
        }
        let a = coords(voxels[k]);
        for (j, &v) in voxels.iter().enumerate() {
            let b = coords(v);
            let distance: usize = (0..3).map(|d| a[d].abs_diff(b[d])).sum();
            if distance == 1 && !reached[j] {
                stack.push(j);
            }
        }
    }
    reached.iter().all(|&r| r)
}

/// Counts one segment with the walk and compares with the reference on an empty grid: the
/// same end (last voxel and endpoint test), and either the same voxels (`exact`) or, where
/// ties may pick other neighbours, as many voxels, each once, in a face-connected chain
/// from the reference's first voxel to its last.
fn compare(
    grid: &Grid3,
    origin: &Point3<f64>,
    endpoint: &Point3<f64>,
    exact: bool,
) -> Result<(), String> {
    let n = grid.num_cells();
    let mut counts = vec![0u16; n];
    let end = SlabWalk::new(grid).count(&mut counts, origin, endpoint);
    let (path, ref_end) = reference(grid, origin, endpoint);
    let context = format!("{origin:?} -> {endpoint:?} in {grid:?}");
    let (first, last) = (path.first().copied(), path.last().copied());
    let ends_agree = match (end, ref_end) {
        // In a tie the walk may end in the same voxel from another neighbour: the last
        // voxel and the endpoint test must agree either way.
        (Some(a), Some(b)) => a == b,
        (None, None) => true,
        _ => false,
    };
    if !ends_agree {
        return Err(format!("ends differ ({end:?} vs {ref_end:?}): {context}"));
    }
    let mut ref_counts = vec![0u16; n];
    for &index in &path {
        ref_counts[index] = ref_counts[index].saturating_add(1);
    }
    if exact {
        return if counts == ref_counts {
            Ok(())
        } else {
            Err(format!("voxels differ: {context}"))
        };
    }
    let visited: Vec<usize> = (0..n).filter(|&i| counts[i] > 0).collect();
    let once = visited.iter().all(|&i| counts[i] == 1);
    let ends = first.into_iter().chain(last).all(|v| visited.contains(&v));
    if !(once
        && visited.len() == path.len()
        && ends
        && (path.is_empty() || connected(grid, &visited)))
    {
        return Err(format!("not an equivalent chain: {context}"));
    }
    Ok(())
}

/// A coordinate: anywhere around the grid, or (when `lattice`) also exactly on a voxel face
/// (`k` cells from the grid origin, `k` from −2 past the far end), or a random coordinate
/// (which other coordinates may copy to make axis-parallel rays).
fn coordinate(origin: f64, cell: f64, dim: usize, lattice: bool) -> BoxedStrategy<f64> {
    let span = dim as f64 * cell;
    let anywhere = (-0.5f64..1.5).prop_map(move |u| origin + u * span);
    if !lattice {
        return anywhere.boxed();
    }
    prop_oneof![
        anywhere,
        (-2i64..dim as i64 + 3).prop_map(move |k| origin + k as f64 * cell),
        (-2i64..dim as i64 + 3, 0.0f64..1.0).prop_map(move |(k, f)| origin + (k as f64 + f) * cell),
    ]
    .boxed()
}

fn point(grid: Grid3, lattice: bool) -> impl Strategy<Value = Point3<f64>> {
    let (o, c, d) = (grid.origin(), grid.cell_size(), grid.dims());
    (
        coordinate(o.x, c, d[0], lattice),
        coordinate(o.y, c, d[1], lattice),
        coordinate(o.z, c, d[2], lattice),
    )
        .prop_map(|(x, y, z)| Point3::new(x, y, z))
}

fn grid() -> impl Strategy<Value = Grid3> {
    (
        (-3.0f64..3.0, -3.0f64..3.0, -3.0f64..3.0),
        prop_oneof![Just(0.1), Just(0.25), Just(1.0), 0.05f64..0.7],
        (1usize..30, 1usize..30, 1usize..8),
    )
        .prop_map(|((x, y, z), cell, (nx, ny, nz))| {
            Grid3::new(Point3::new(x, y, z), cell, [nx, ny, nz]).expect("valid grid")
        })
}

/// Segments in a grid.
type Segments = Vec<(Point3<f64>, Point3<f64>)>;

/// A grid and segments: with `lattice`, also axis-parallel ones (endpoint sharing one or two
/// coordinates of the origin) and ones on or ending on faces, edges and corners.
fn case(lattice: bool) -> impl Strategy<Value = (Grid3, Segments)> {
    grid().prop_flat_map(move |grid| {
        let parallel = if lattice { 0u8..4 } else { 0u8..1 };
        let segment = (point(grid, lattice), point(grid, lattice), parallel).prop_map(
            |(a, mut b, parallel)| {
                match parallel {
                    1 => b.x = a.x,
                    2 => {
                        b.y = a.y;
                        b.z = a.z;
                    }
                    3 => b.z = a.z,
                    _ => {}
                }
                (a, b)
            },
        );
        (Just(grid), proptest::collection::vec(segment, 1..20))
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1500))]

    /// Random segments (in general position, many from outside the grid): the same voxels
    /// and the same end as the exact traversal.
    #[test]
    fn random_segments_cross_the_voxels_of_the_exact_traversal((grid, segments) in case(false)) {
        for (a, b) in &segments {
            let result = compare(&grid, a, b, true);
            prop_assert!(result.is_ok(), "{:?}", result);
        }
    }

    /// Axis-parallel segments and ones on or ending on faces, edges and corners: the same
    /// number of voxels in a face-connected chain with the same ends.
    #[test]
    fn segments_through_ties_cross_an_equivalent_chain((grid, segments) in case(true)) {
        for (a, b) in &segments {
            let result = compare(&grid, a, b, false);
            prop_assert!(result.is_ok(), "{:?}", result);
        }
    }
}

#[test]
fn known_cases_match_the_exact_traversal() {
    let grid = Grid3::new(Point3::new(-1.0, -1.0, -0.5), 0.25, [8, 8, 4]).expect("grid");
    let segments = [
        // General position: inside, from outside through the grid, both sides crossing in
        // one slab (a shallow diagonal).
        ([-0.93, -0.81, -0.44], [0.77, 0.52, 0.31], true),
        ([-3.1, 0.37, -0.21], [2.2, -0.61, 0.43], true),
        ([-0.9, -0.95, -0.45], [0.95, 0.21, 0.37], true),
        // From outside along x, ending on a face; space diagonal through vertices.
        ([-3.0, 0.1, 0.1], [0.5, 0.1, 0.1], false),
        ([-1.0, -1.0, -0.5], [1.0, 1.0, 0.5], false),
        // Along a face, along an edge, on the grid's upper face, ending on a corner.
        ([-1.5, 0.0, 0.1], [2.0, 0.0, 0.1], false),
        ([-1.5, 0.0, 0.0], [2.0, 0.0, 0.0], false),
        ([0.1, 1.0, 0.1], [0.1, -2.0, 0.1], false),
        ([0.3, 0.3, 0.3], [0.5, 0.5, 0.25], false),
        // Degenerate: zero length, missing the grid, touching only a corner.
        ([0.1, 0.1, 0.1], [0.1, 0.1, 0.1], true),
        ([5.0, 5.0, 5.0], [6.0, 5.0, 5.0], true),
        ([-2.0, -2.0, -0.5], [-1.0, -1.0, -0.5], true),
    ];
    for (a, b, exact) in segments {
        let (a, b) = (Point3::from(a), Point3::from(b));
        if let Err(e) = compare(&grid, &a, &b, exact) {
            panic!("{e}");
        }
    }
}

#[test]
fn counts_saturate_and_skip_indices_past_the_slice() {
    let grid = Grid3::new(Point3::origin(), 1.0, [10, 1, 1]).expect("grid");
    let (origin, endpoint) = (Point3::new(0.5, 0.5, 0.5), Point3::new(4.5, 0.5, 0.5));
    let walk = SlabWalk::new(&grid);
    let mut counts = vec![u16::MAX - 1; 10];
    for _ in 0..3 {
        let end = walk.count(&mut counts, &origin, &endpoint);
        assert_eq!(
            end,
            Some(SlabWalkEnd {
                last: 4,
                contains_endpoint: true
            })
        );
    }
    assert_eq!(
        &counts[..6],
        &[
            u16::MAX,
            u16::MAX,
            u16::MAX,
            u16::MAX,
            u16::MAX,
            u16::MAX - 1
        ]
    );
    // A short slice: the voxels past its end are not counted.
    let mut short = vec![0u16; 2];
    let end = walk.count(&mut short, &origin, &Point3::new(20.0, 0.5, 0.5));
    assert_eq!(
        end,
        Some(SlabWalkEnd {
            last: 9,
            contains_endpoint: false
        })
    );
    assert_eq!(short, [1, 1]);
}
