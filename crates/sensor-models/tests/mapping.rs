//! Map building (MAP-DECAY, Schaefer 2020 Sec. 7.4.2): known answers, edge cases, dense vs
//! sparse, and determinism of the parallel build.
#![allow(clippy::unwrap_used)] // test code: a panic is the failure report

use nalgebra::{Point2, Point3, Vector2, Vector3};
use proptest::prelude::*;
use raypath_geometry::testing::{grid3, ray3_in};
use raypath_geometry::{Grid2, Grid3, Range, Ray2, Ray3};
use raypath_sensor_models::{
    CellStats, DenseStats2, DenseStats3, MappingConfig, SensorRange, SparseStats3,
};

/// A row of four 1 m cells from x = 0 to 4, y in [0, 1].
fn row() -> DenseStats2 {
    DenseStats2::new(Grid2::new(Point2::new(0.0, 0.0), 1.0, [4, 1]).unwrap())
}

fn ray_x(x0: f64, range: Range) -> Ray2 {
    Ray2::new(Point2::new(x0, 0.5), Vector2::new(1.0, 0.0), range).unwrap()
}

#[test]
fn known_answer_hit_inside() {
    let mut stats = row();
    stats.insert_ray(&ray_x(0.5, Range::Hit(2.25)), &MappingConfig::default());
    assert_eq!(stats.cell(0), CellStats::new(0, 1, 0.5));
    assert_eq!(stats.cell(1), CellStats::new(0, 1, 1.0));
    assert_eq!(stats.cell(2), CellStats::new(1, 0, 0.75));
    assert_eq!(stats.cell(3), CellStats::EMPTY);
    let summary = stats.summary();
    assert_eq!((summary.rays, summary.hits, summary.crossings), (1, 1, 3));
}

#[test]
fn endpoint_outside_gives_misses_only() {
    let mut stats = row();
    stats.insert_ray(&ray_x(0.5, Range::Hit(10.0)), &MappingConfig::default());
    assert_eq!(stats.cell(0), CellStats::new(0, 1, 0.5));
    for i in 1..4 {
        assert_eq!(stats.cell(i), CellStats::new(0, 1, 1.0));
    }
    assert_eq!(stats.summary().endpoints_outside, 1);
    assert_eq!(stats.summary().hits, 0);
}

#[test]
fn endpoint_on_a_face_hits_the_larger_cell() {
    // The endpoint x = 2.0 is the face between cells 1 and 2: the hit goes to cell 2
    // (Grid::cell_of), with zero length; cell 1 is crossed completely.
    let mut stats = row();
    stats.insert_ray(&ray_x(0.5, Range::Hit(1.5)), &MappingConfig::default());
    assert_eq!(stats.cell(1), CellStats::new(0, 1, 1.0));
    assert_eq!(stats.cell(2), CellStats::new(1, 0, 0.0));
    // Moving towards lower indices, the endpoint x = 2.0 belongs to cell 2, which the ray
    // crossed completely: a hit with full length.
    let mut stats = row();
    let back = Ray2::new(
        Point2::new(3.5, 0.5),
        Vector2::new(-1.0, 0.0),
        Range::Hit(1.5),
    )
    .unwrap();
    stats.insert_ray(&back, &MappingConfig::default());
    assert_eq!(stats.cell(3), CellStats::new(0, 1, 0.5));
    assert_eq!(stats.cell(2), CellStats::new(1, 0, 1.0));
    assert_eq!(stats.cell(1), CellStats::EMPTY);
}

#[test]
fn zero_length_sub_and_no_returns() {
    let mut stats = row();
    let config = MappingConfig::default();
    stats.insert_ray(&ray_x(0.5, Range::Hit(0.0)), &config);
    assert!(stats.cells().iter().all(CellStats::is_empty));
    assert_eq!(stats.summary().empty, 1);

    // No-returns are traced to r_max and add misses and length, no hit.
    let config = MappingConfig {
        range: SensorRange::new(0.0, 2.0).unwrap(),
        ..config
    };
    stats.insert_ray(&ray_x(0.5, Range::NoReturn), &config);
    // A return beyond r_max is a no-return too.
    stats.insert_ray(&ray_x(0.5, Range::Hit(3.0)), &config);
    assert_eq!(stats.cell(0), CellStats::new(0, 2, 1.0));
    assert_eq!(stats.cell(1), CellStats::new(0, 2, 2.0));
    assert_eq!(stats.cell(2), CellStats::new(0, 2, 1.0));
    assert_eq!(stats.summary().no_returns_traced, 2);

    // Without no-returns they are skipped; sub readings are always ignored.
    let config = MappingConfig {
        range: SensorRange::new(0.5, 2.0).unwrap(),
        include_no_returns: false,
    };
    let before = stats.clone();
    stats.insert_ray(&ray_x(0.5, Range::NoReturn), &config);
    stats.insert_ray(&ray_x(0.5, Range::Hit(0.25)), &config);
    assert_eq!(stats.cells(), before.cells());
    assert_eq!(stats.summary().no_returns_skipped, 1);
    assert_eq!(stats.summary().sub_ignored, 1);
}

#[test]
fn merge_rejects_other_grids() {
    let mut a = row();
    let b = DenseStats2::new(Grid2::new(Point2::new(0.0, 0.0), 1.0, [5, 1]).unwrap());
    assert!(a.merge(&b).is_err());
    assert!(
        DenseStats2::from_parts(*a.grid(), vec![CellStats::EMPTY; 3], Default::default()).is_err()
    );
}

/// Seeded rays of 20–60 m in a 3-D grid (a small version of the bench workload).
fn random_rays(n: usize, seed: u64) -> Vec<Ray3> {
    let mut state = seed;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|i| {
            let origin = Point3::new(20.0 * next(), 20.0 * next(), 1.0 + 2.0 * next());
            let direction = Vector3::new(next() - 0.5, next() - 0.5, 0.3 * (next() - 0.5));
            let range = if i % 10 == 0 {
                Range::NoReturn
            } else {
                Range::Hit(2.0 + 20.0 * next())
            };
            Ray3::new(origin, direction, range).unwrap()
        })
        .collect()
}

#[test]
fn parallel_dense_and_sparse_agree_for_any_thread_count() {
    let grid = Grid3::new(Point3::new(-5.0, -5.0, -2.0), 0.5, [60, 60, 14]).unwrap();
    let rays = random_rays(20_000, 7);
    let config = MappingConfig {
        range: SensorRange::new(0.0, 25.0).unwrap(),
        ..Default::default()
    };
    let mut sequential = DenseStats3::new(grid);
    for ray in &rays {
        sequential.insert_ray(ray, &config);
    }
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let (dense, sparse) = pool.install(|| {
            let mut dense = DenseStats3::new(grid);
            dense.insert_rays_par(&rays, &config);
            let mut sparse = SparseStats3::new(grid);
            sparse.insert_rays_par(&rays, &config);
            (dense, sparse)
        });
        assert!(
            dense == sequential,
            "dense build with {threads} threads differs"
        );
        assert!(
            sparse.to_dense() == sequential,
            "sparse build with {threads} threads differs"
        );
    }
    // Conservation: the recorded length is the traced length inside the grid.
    let recorded: f64 = sequential
        .cells()
        .iter()
        .map(CellStats::path_length_m)
        .sum();
    let traced: f64 = rays
        .iter()
        .map(|ray| {
            grid.traverse_ray(ray, 25.0)
                .map(|c| c.length())
                .sum::<f64>()
        })
        .sum();
    assert!((recorded - traced).abs() < 1e-6 * traced);
    let hits: u64 = sequential.cells().iter().map(|c| u64::from(c.hits())).sum();
    assert_eq!(hits, sequential.summary().hits);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Sparse and dense storage record the same statistics for arbitrary grids and rays
    /// (including rays starting on faces, axis-parallel and diagonal ones).
    #[test]
    fn sparse_equals_dense(
        (grid, rays) in grid3().prop_flat_map(|g| {
            (Just(g), proptest::collection::vec(ray3_in(g.bounds()), 1..20))
        })
    ) {
        let config = MappingConfig::default();
        let mut dense = DenseStats3::new(grid);
        let mut sparse = SparseStats3::new(grid);
        for ray in &rays {
            dense.insert_ray(ray, &config);
            sparse.insert_ray(ray, &config);
        }
        prop_assert!(sparse.to_dense() == dense);
        // Every hit is in the cell of the endpoint.
        for ray in &rays {
            if let Some(r) = ray.range.hit()
                && r > 0.0
                && let Some(cell) = grid.cell_of(&ray.at(r)) {
                prop_assert!(dense.cell(grid.linear_index(cell)).hits() > 0);
            }
        }
    }
}
