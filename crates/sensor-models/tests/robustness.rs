//! No NaN or infinity from any model: empty maps, zero-length rays, rays ending on cell
//! faces, rays outside the grid, odd readings.
#![allow(clippy::unwrap_used)] // test code: a panic is the failure report

use nalgebra::{Point2, Vector2};
use proptest::prelude::*;
use raypath_geometry::testing::{grid2, grid3, ray2_in, ray3_in};
use raypath_geometry::{Grid2, Range, Ray2};
use raypath_sensor_models::{
    BetaPosteriorConfig, DecayRateConfig, DecayRateModel, DecayRateModel2, DecayRatePosteriorModel,
    DecayRatePosteriorModel2, DenseStats, DenseStats2, Dimension, GammaPosteriorConfig,
    LikelihoodFieldConfig, LikelihoodFieldModel, LikelihoodFieldModel2, LogOddsConfig,
    LogOddsModel, LogOddsModel2, MappingConfig, OpticalDepthConfig, ReflectionConfig,
    ReflectionModel, ReflectionModel2, SensorModel, Tabulated,
};

/// Every model of `stats`, boxed.
fn all_models<D: Dimension>(stats: &DenseStats<D>) -> Vec<(&'static str, Box<dyn SensorModel<D>>)> {
    vec![
        (
            "decay-rate",
            Box::new(DecayRateModel::new(stats, DecayRateConfig::default()).unwrap()),
        ),
        (
            "decay-rate posterior",
            Box::new(DecayRatePosteriorModel::new(stats, GammaPosteriorConfig::default()).unwrap()),
        ),
        (
            "reflection",
            Box::new(
                ReflectionModel::maximum_likelihood(stats, ReflectionConfig::default()).unwrap(),
            ),
        ),
        (
            "reflection posterior",
            Box::new(ReflectionModel::posterior(stats, BetaPosteriorConfig::default()).unwrap()),
        ),
        (
            "log-odds",
            Box::new(LogOddsModel::new(stats, LogOddsConfig::default()).unwrap()),
        ),
        (
            "likelihood field",
            Box::new(LikelihoodFieldModel::new(stats, LikelihoodFieldConfig::default()).unwrap()),
        ),
    ]
}

fn tabulated_models(
    stats: &DenseStats2,
) -> Vec<(
    &'static str,
    Box<dyn SensorModel<raypath_sensor_models::Planar>>,
)> {
    let config = OpticalDepthConfig {
        directions: 24,
        ..Default::default()
    };
    vec![
        (
            "decay-rate table",
            Box::new(
                Tabulated::<DecayRateModel2>::new(
                    DecayRateModel2::new(stats, DecayRateConfig::default()).unwrap(),
                    config,
                )
                .unwrap(),
            ),
        ),
        (
            "reflection table",
            Box::new(
                Tabulated::<ReflectionModel2>::new(
                    ReflectionModel2::maximum_likelihood(stats, ReflectionConfig::default())
                        .unwrap(),
                    config,
                )
                .unwrap(),
            ),
        ),
        (
            "decay-rate posterior table",
            Box::new(
                Tabulated::<DecayRatePosteriorModel2>::new(
                    DecayRatePosteriorModel2::new(stats, GammaPosteriorConfig::default()).unwrap(),
                    config,
                )
                .unwrap(),
            ),
        ),
        (
            "log-odds table",
            Box::new(
                Tabulated::<LogOddsModel2>::new(
                    LogOddsModel2::new(stats, LogOddsConfig::default()).unwrap(),
                    config,
                )
                .unwrap(),
            ),
        ),
        (
            "likelihood-field table",
            Box::new(
                Tabulated::<LikelihoodFieldModel2>::new(
                    LikelihoodFieldModel2::new(stats, LikelihoodFieldConfig::default()).unwrap(),
                    config,
                )
                .unwrap(),
            ),
        ),
    ]
}

/// Rays that stress the edge cases on `grid`: zero length, ending on faces and corners,
/// starting on faces, outside the grid, NaN and infinite ranges.
fn special_rays(grid: &Grid2) -> Vec<Ray2> {
    let c = grid.cell_size();
    let o = grid.origin();
    let centre = Point2::new(o.x + 0.5 * c, o.y + 0.5 * c);
    let corner = o;
    let mut rays = Vec::new();
    for (dx, dy) in [
        (1.0, 0.0),
        (-1.0, 0.0),
        (0.0, 1.0),
        (1.0, 1.0),
        (-1.0, -1.0),
        (0.3, 0.7),
    ] {
        let direction = Vector2::new(dx, dy);
        for origin in [centre, corner, Point2::new(o.x - 3.0, o.y + 0.5 * c)] {
            for range in [
                Range::Hit(0.0),
                Range::Hit(0.5 * c),
                Range::Hit(1.5 * c),
                Range::Hit(2.0 * c),
                Range::Hit(1e-300),
                Range::Hit(f64::NAN),
                Range::Hit(f64::INFINITY),
                Range::Hit(1e6),
                Range::NoReturn,
            ] {
                rays.extend(Ray2::new(origin, direction, range));
            }
        }
    }
    rays
}

fn check<D: Dimension>(
    name: &str,
    model: &dyn SensorModel<D>,
    ray: &D::Ray,
) -> Result<(), TestCaseError> {
    let value = model.ray_log_likelihood(ray);
    prop_assert!(value.is_finite(), "{name}: {value} for {ray:?}");
    Ok(())
}

#[test]
fn empty_maps_and_special_rays() {
    let grid = Grid2::new(Point2::new(-1.0, -0.5), 0.25, [8, 6]).unwrap();
    let empty = DenseStats2::new(grid);
    let mut observed = DenseStats2::new(grid);
    for ray in special_rays(&grid) {
        observed.insert_ray(&ray, &MappingConfig::default());
    }
    for stats in [&empty, &observed] {
        let mut models = all_models(stats);
        models.extend(tabulated_models(stats));
        for (name, model) in &models {
            for ray in special_rays(&grid) {
                check(name, model.as_ref(), &ray).unwrap();
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn never_nan_or_infinite_2d(
        (grid, map_rays, test_rays) in grid2().prop_flat_map(|g| (
            Just(g),
            proptest::collection::vec(ray2_in(g.bounds()), 0..30),
            proptest::collection::vec(ray2_in(g.bounds()), 1..30),
        ))
    ) {
        let mut stats = DenseStats2::new(grid);
        for ray in &map_rays {
            stats.insert_ray(ray, &MappingConfig::default());
        }
        let mut models = all_models(&stats);
        models.extend(tabulated_models(&stats));
        for (name, model) in &models {
            for ray in test_rays.iter().chain(&special_rays(&grid)) {
                check(name, model.as_ref(), ray)?;
            }
        }
    }

    #[test]
    fn never_nan_or_infinite_3d(
        (grid, map_rays, test_rays) in grid3().prop_flat_map(|g| (
            Just(g),
            proptest::collection::vec(ray3_in(g.bounds()), 0..30),
            proptest::collection::vec(ray3_in(g.bounds()), 1..30),
        ))
    ) {
        let mut stats = raypath_sensor_models::DenseStats3::new(grid);
        for ray in &map_rays {
            stats.insert_ray(ray, &MappingConfig::default());
        }
        for (name, model) in &all_models(&stats) {
            for ray in &test_rays {
                check(name, model.as_ref(), ray)?;
                let zero = raypath_geometry::Ray3 { range: Range::Hit(0.0), ..*ray };
                check(name, model.as_ref(), &zero)?;
            }
        }
    }
}

/// Found by `never_nan_or_infinite_2d`: every observed cell is all hits or all misses, so the
/// method-of-moments Beta prior sits at the edge of the family (α + β ≈ 2e-16), a hit-only
/// cell's posterior μ rounds to 1 and a ray crossing it scored ln 0.
#[test]
fn posterior_with_edge_prior_stays_finite() {
    let grid = Grid2::new(Point2::new(1.0, -7.375), 1.615_223_108_502_324_8, [22, 2]).unwrap();
    let mut stats = DenseStats2::new(grid);
    let map_rays = [
        (
            3.644_991_970_100_494,
            -5.827_569_308_576_28,
            0.0,
            -1.0,
            0.537_291_451_869_976_1,
        ),
        (
            1.783_002_911_625_136_2,
            -7.253_607_801_517_596,
            1.0,
            0.0,
            1.228_852_288_162_532,
        ),
        (
            15.190_740_724_777_216,
            -7.375,
            1.0,
            0.0,
            63.169_238_223_437_3,
        ),
    ];
    for (x, y, dx, dy, r) in map_rays {
        let ray = Ray2::new(Point2::new(x, y), Vector2::new(dx, dy), Range::Hit(r)).unwrap();
        stats.insert_ray(&ray, &MappingConfig::default());
    }
    let model = ReflectionModel::posterior(&stats, BetaPosteriorConfig::default()).unwrap();
    let prior = model.prior().unwrap();
    assert!(
        prior.alpha + prior.beta < 1e-10,
        "the case needs an edge prior: {prior:?}"
    );
    let across_hit_cell = Ray2::new(
        Point2::new(1.807_611_554_251_162_4, -6.567_388_445_748_838),
        Vector2::new(1.0, 0.0),
        Range::Hit(2.422_834_662_753_487),
    )
    .unwrap();
    check("reflection posterior", &model, &across_hit_cell).unwrap();
}
