//! The ML fit on synthetic data: monotone, converging, both solvers, and the grid
//! conversion; ray clipping to a patch.
#![allow(clippy::unwrap_used)]

mod common;

use common::rng;
use nalgebra::Point2;
use rand::Rng;
use raypath_dct_map::{
    FitConfig, FitProblem, GridRateMap, MapRay, Outcome, PRIOR_PATH_DENSITY, Patch, RangeLimits,
    Shape, Solver, fit, initial_map,
};
use raypath_geometry::{Range, Ray2};

/// Rays in a 8 m × 8 m room with a wall segment at x = 6 m, y ∈ [2, 6]: rays from the left
/// half hit the wall (a little spread along the ray), the others leave the room (`super`).
fn room_rays(n: usize, seed: u64) -> Vec<MapRay> {
    let mut r = rng(seed);
    let patch = Patch::square([0.0, 0.0], 8.0);
    let mut rays = Vec::new();
    while rays.len() < n {
        let o = Point2::new(r.random_range(0.5..3.0), r.random_range(0.5..7.5));
        let angle: f64 = r.random_range(-1.2..1.2);
        let (c, s) = (angle.cos(), angle.sin());
        let t_wall = (6.0 - o.x) / c;
        let y = o.y + s * t_wall;
        let range = if (2.0..=6.0).contains(&y) {
            Range::Hit(t_wall + r.random_range(0.0..0.15))
        } else {
            Range::NoReturn
        };
        if let Some(ray) =
            patch.clip_ray(&Ray2::from_angle(o, angle, range), &RangeLimits::default())
        {
            rays.push(ray);
        }
    }
    rays
}

#[test]
fn both_solvers_increase_the_likelihood_monotonically() {
    let extent = [8.0, 8.0];
    let rays = room_rays(600, 21);
    let shape = Shape { l: 8, m: 8 };
    let init = initial_map(extent, shape, &rays).unwrap();
    let problem = FitProblem::new(extent, shape, &rays).unwrap();
    let mut finals = Vec::new();
    for solver in [Solver::TrustRegionNewton, Solver::Lbfgs] {
        let config = FitConfig {
            solver,
            ..FitConfig::default()
        };
        let (map, report) = fit(&problem, init.coefficients(), &config).unwrap();
        assert!(report.converged, "{solver:?} did not converge: {report:?}");
        assert!(report.iterations >= 1);
        for w in report.log_likelihoods.windows(2) {
            assert!(
                w[1] >= w[0],
                "{solver:?} decreased: {:?}",
                report.log_likelihoods
            );
        }
        let last = report.log_likelihoods.len() - 1;
        // The report holds the objective: the rays' log-likelihood plus the log-prior.
        let ll = map.log_likelihood(&rays) + problem.log_prior(map.coefficients());
        assert!((ll - report.log_likelihoods[last]).abs() < 1e-6 * ll.abs());
        // The wall is denser than the free space in front of it.
        assert!(
            map.rate_at([6.05, 4.0]) > 10.0 * map.rate_at([4.5, 4.0]),
            "{solver:?}"
        );
        finals.push(ll);
    }
    // The ML fit beats the grid map it started from on its own data.
    assert!(finals.iter().all(|f| *f > init.log_likelihood(&rays)));
}

#[test]
fn newton_with_a_tight_tolerance_reaches_a_stationary_point() {
    let extent = [8.0, 8.0];
    let rays = room_rays(400, 22);
    let shape = Shape { l: 5, m: 6 };
    let init = initial_map(extent, shape, &rays).unwrap();
    let problem = FitProblem::new(extent, shape, &rays).unwrap();
    let config = FitConfig {
        relative_tolerance: 1e-12,
        ..FitConfig::default()
    };
    let (map, _) = fit(&problem, init.coefficients(), &config).unwrap();
    let e = problem.evaluate(map.coefficients());
    let norm = e.gradient.iter().map(|g| g * g).sum::<f64>().sqrt();
    assert!(norm < 1e-3, "gradient norm {norm}");
}

#[test]
fn zero_start_and_wrong_lengths_are_rejected() {
    let extent = [8.0, 8.0];
    let rays = room_rays(50, 23);
    let shape = Shape { l: 3, m: 3 };
    let problem = FitProblem::new(extent, shape, &rays).unwrap();
    assert!(fit(&problem, &[0.0; 9], &FitConfig::default()).is_err());
    assert!(fit(&problem, &[1.0; 8], &FitConfig::default()).is_err());
    assert!(FitProblem::new(extent, shape, &[]).is_err());
    let bad = MapRay {
        length_m: f64::NAN,
        ..rays[0]
    };
    assert!(FitProblem::new(extent, shape, &[bad]).is_err());
}

#[test]
fn grid_conversion_round_trips_at_cell_centres() {
    let rays = room_rays(500, 24);
    let grid = GridRateMap::square(8.0, 8, &rays).unwrap();
    let map = raypath_dct_map::DctMap::from_grid([8.0, 8.0], Shape { l: 8, m: 8 }, &grid).unwrap();
    let (g2, rates) = map.to_rate_grid(1.0, [8, 8]).unwrap();
    for (i, r) in rates.iter().enumerate() {
        let c = g2.cell_center(g2.cell_from_linear(i));
        let want = grid.rate_at([c.x, c.y]);
        assert!(
            (r - want).abs() < 1e-9 * want.max(1.0),
            "cell {i}: {r} vs {want}"
        );
    }
    // The grid's wall cells reflect: H / R there is large.
    assert!(grid.rate_at([6.05, 4.0]) > 1.0);
    assert!(grid.ray_log_likelihood(&rays[0]).is_finite());
}

#[test]
fn clipping_follows_the_table() {
    let patch = Patch {
        min: [10.0, 20.0],
        extent_m: [4.0, 2.0],
    };
    let lim = RangeLimits::default();
    let o = Point2::new(8.0, 21.0);
    // Hit inside: origin moves to the entry, length shrinks by 2 m.
    let r = patch
        .clip_ray(&Ray2::from_angle(o, 0.0, Range::Hit(3.0)), &lim)
        .unwrap();
    assert_eq!(r.outcome, Outcome::Hit);
    assert!((r.origin[0] - 0.0).abs() < 1e-12 && (r.origin[1] - 1.0).abs() < 1e-12);
    assert!((r.length_m - 1.0).abs() < 1e-12);
    // Hit beyond the patch: super through the whole 4 m.
    let r = patch
        .clip_ray(&Ray2::from_angle(o, 0.0, Range::Hit(30.0)), &lim)
        .unwrap();
    assert_eq!(r.outcome, Outcome::Super);
    assert!((r.length_m - 4.0).abs() < 1e-12);
    // No return: super too; a return before the patch: dropped; a miss: dropped.
    let r = patch
        .clip_ray(&Ray2::from_angle(o, 0.0, Range::NoReturn), &lim)
        .unwrap();
    assert_eq!(r.outcome, Outcome::Super);
    assert!(
        patch
            .clip_ray(&Ray2::from_angle(o, 0.0, Range::Hit(1.0)), &lim)
            .is_none()
    );
    assert!(
        patch
            .clip_ray(&Ray2::from_angle(o, 3.0, Range::Hit(1.0)), &lim)
            .is_none()
    );
    assert!(
        patch
            .clip_ray(&Ray2::from_angle(o, 0.0, Range::Hit(f64::NAN)), &lim)
            .is_none()
    );
    // r_max inside the patch: super up to r_max; returns beyond r_max are no-returns.
    let lim = RangeLimits {
        min_range_m: 0.5,
        max_range_m: 4.0,
    };
    let r = patch
        .clip_ray(&Ray2::from_angle(o, 0.0, Range::Hit(5.0)), &lim)
        .unwrap();
    assert_eq!(r.outcome, Outcome::Super);
    assert!((r.length_m - 2.0).abs() < 1e-12);
    // sub: only from inside the patch.
    let inside = Point2::new(11.0, 21.0);
    let r = patch
        .clip_ray(&Ray2::from_angle(inside, 0.0, Range::Hit(0.1)), &lim)
        .unwrap();
    assert_eq!((r.outcome, r.length_m), (Outcome::Sub, 0.5));
    assert!(
        patch
            .clip_ray(&Ray2::from_angle(o, 0.0, Range::Hit(0.1)), &lim)
            .is_none()
    );
}

/// A vertical no-return ray at `x` through the whole 8 m room.
fn crossing(x: f64) -> MapRay {
    MapRay::from_angle([x, 0.0], std::f64::consts::FRAC_PI_2, 8.0, Outcome::Super)
}

#[test]
fn the_prior_keeps_the_shadow_behind_a_wall_free_of_rate_spikes() {
    // No mapping ray reaches x > 6.15 m for y ∈ [2, 6] (the wall's shadow). Without a prior
    // the ML map parks rates of 10⁵–10⁶ /m there, and a new ray crossing the shadow gets a
    // log-likelihood of about −10⁵ (the csail 40² failure of `cargo xtask eval dct`, small).
    let extent = [8.0, 8.0];
    let rays = room_rays(2000, 100);
    let shape = Shape { l: 16, m: 16 };
    let init = initial_map(extent, shape, &rays).unwrap();
    let grid = GridRateMap::square(8.0, 16, &rays).unwrap();
    let probes = [crossing(7.0), crossing(7.5), crossing(7.9)];
    let worst = |ll: &dyn Fn(&MapRay) -> f64| probes.iter().map(ll).fold(f64::INFINITY, f64::min);
    let grid_worst = worst(&|r| grid.ray_log_likelihood(r));
    assert!(grid_worst > -5.0, "grid {grid_worst}");

    let mut plain = FitProblem::new(extent, shape, &rays).unwrap();
    plain.set_prior_path_density(0.0);
    let (ml, _) = fit(&plain, init.coefficients(), &FitConfig::default()).unwrap();
    let ml_worst = worst(&|r| ml.ray_log_likelihood(r));
    assert!(ml_worst < -1e4, "plain ML fit: {ml_worst}");

    let problem = FitProblem::new(extent, shape, &rays).unwrap();
    assert_eq!(problem.prior_path_density(), PRIOR_PATH_DENSITY);
    let (map, _) = fit(&problem, init.coefficients(), &FitConfig::default()).unwrap();
    let map_worst = worst(&|r| map.ray_log_likelihood(r));
    assert!(map_worst > grid_worst - 40.0, "with the prior: {map_worst}");
    let max_rate = map
        .rates_on_lattice(160, 160)
        .into_iter()
        .fold(0.0, f64::max);
    assert!(max_rate < 1e3, "max λ {max_rate}");
    // The data are still fitted: the wall stands out from the free space in front of it.
    assert!(map.rate_at([6.05, 4.0]) > 100.0 * map.rate_at([4.5, 4.0]));
    assert!(map.log_likelihood(&rays) > init.log_likelihood(&rays));
}
