//! Property tests of the sensor models (Schaefer 2020, ch. 7 and 8).
#![allow(clippy::unwrap_used, clippy::too_many_arguments)] // test code: a panic is the failure report

mod common;

use common::{gauss_legendre, ln_gamma, simpson};
use nalgebra::{Point2, Vector2};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use raypath_geometry::{Grid2, Range, Ray2};
use raypath_sensor_models::{
    BetaPosteriorConfig, BetaPrior, CellStats, DecayRateConfig, DecayRateModel2,
    DecayRatePosteriorModel2, DenseStats2, GammaPosteriorConfig, GammaPrior, LikelihoodFieldConfig,
    LikelihoodFieldModel2, LogOddsConfig, LogOddsModel2, MappingConfig, OpticalDepthConfig, Planar,
    ReflectionConfig, ReflectionModel2, SensorModel, SensorRange, Tabulated,
};
use std::f64::consts::{FRAC_PI_2, PI};

/// A 12 m × 12 m grid of 0.5 m cells at the origin.
fn grid() -> Grid2 {
    Grid2::new(Point2::new(0.0, 0.0), 0.5, [24, 24]).unwrap()
}

/// Seeded rays from the central region, ending inside the grid.
fn rays(seed: u64, n: usize) -> Vec<Ray2> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let origin = Point2::new(rng.random_range(5.0..7.0), rng.random_range(5.0..7.0));
            let angle = rng.random_range(0.0..std::f64::consts::TAU);
            Ray2::from_angle(origin, angle, Range::Hit(rng.random_range(0.2..4.5)))
        })
        .collect()
}

/// Random per-cell statistics (some cells empty).
fn random_stats(seed: u64) -> DenseStats2 {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let grid = grid();
    let cells = (0..grid.num_cells())
        .map(|_| {
            if rng.random_bool(0.2) {
                CellStats::EMPTY
            } else {
                CellStats::new(
                    rng.random_range(0..6),
                    rng.random_range(0..30),
                    rng.random_range(0.01..12.0),
                )
            }
        })
        .collect();
    DenseStats2::from_parts(grid, cells, Default::default()).unwrap()
}

/// `f(m) = Σ_j ln λ_k(j) − Σ_i λ_i d_i(j)` (Eq. 7.17) for per-cell rates `rates`.
fn data_log_likelihood(grid: &Grid2, rays: &[Ray2], rates: &[f64]) -> f64 {
    rays.iter()
        .map(|ray| {
            let r = ray.range.hit().unwrap();
            let k = grid.linear_index(grid.cell_of(&ray.at(r)).unwrap());
            let depth: f64 = grid
                .traverse_ray(ray, 100.0)
                .map(|c| rates[c.index] * c.length())
                .sum();
            rates[k].ln() - depth
        })
        .sum()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// Eq. 7.17–7.21: the ML decay-rate map maximizes the data likelihood; perturbing any
    /// λ_i lowers it (cells without hits sit at the boundary maximum λ_i = 0). The model's
    /// ray likelihoods sum to the same f(m).
    #[test]
    fn decay_rate_ml_map_maximizes_the_likelihood(seed in any::<u64>(), pick in any::<usize>()) {
        let grid = grid();
        let rays = rays(seed, 300);
        let mut stats = DenseStats2::new(grid);
        for ray in &rays {
            stats.insert_ray(ray, &MappingConfig::default());
        }
        let ml: Vec<f64> = stats
            .cells()
            .iter()
            .map(|c| if c.path_length_m() > 0.0 { c.h() / c.path_length_m() } else { 0.0 })
            .collect();
        let best = data_log_likelihood(&grid, &rays, &ml);
        prop_assert!(best.is_finite());
        let observed: Vec<usize> = (0..ml.len()).filter(|&i| stats.cell(i).path_length_m() > 0.0).collect();
        for offset in 0..10 {
            let i = observed[(pick + offset * 7919) % observed.len()];
            for factor in [0.9, 0.99, 1.01, 1.1] {
                let mut perturbed = ml.clone();
                perturbed[i] = if ml[i] > 0.0 { ml[i] * factor } else { (factor - 0.9) * 0.1 + 1e-6 };
                prop_assert!(data_log_likelihood(&grid, &rays, &perturbed) < best);
            }
        }
        let config = DecayRateConfig { min_rate_per_m: 1e-300, unknown_rate_per_m: Some(1.0), ..Default::default() };
        let model = DecayRateModel2::new(&stats, config).unwrap();
        let sum: f64 = rays.iter().map(|r| model.ray_log_likelihood(r)).sum();
        prop_assert!((sum - best).abs() < 1e-9 * best.abs().max(1.0), "{sum} vs {best}");
    }
}

/// Sec. 7.5.2: with equal in-cell lengths d (Assumption 1), λ_i = q_i / d (Eq. 7.25), and the
/// decay-rate probability of reflecting in v_k tends to the reflection model's q_k Π (1 − q_i)
/// (Eq. 7.26) as the q_i shrink; the gap is first order in q_k only (the in-cell decay that
/// Eq. 7.26 ignores: it treats the integrand as constant across v_k) and second order in the
/// others.
#[test]
fn reflection_model_is_the_equal_length_limit() {
    let d = 0.5;
    let grid = Grid2::new(Point2::new(0.0, 0.0), d, [20, 1]).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut stats = DenseStats2::new(grid);
    // Rays along −x from the upper face of cell 19, ending exactly on a lower cell face:
    // every traversed cell, including the reflecting one, is crossed for d.
    for _ in 0..4000 {
        let k = rng.random_range(0..19usize);
        let length = (19 - k) as f64 * d + d;
        let ray = Ray2::new(
            Point2::new(10.0, 0.25),
            Vector2::new(-1.0, 0.0),
            Range::Hit(length),
        )
        .unwrap();
        stats.insert_ray(&ray, &MappingConfig::default());
    }
    for (i, cell) in stats.cells().iter().enumerate() {
        if cell.hits() + cell.misses() == 0 {
            continue;
        }
        let q = cell.h() / (cell.h() + cell.m());
        let lambda = cell.h() / cell.path_length_m();
        assert!(
            (lambda * d - q).abs() < 1e-12,
            "cell {i}: λd = {} vs q = {q}",
            lambda * d
        ); // Eq. (7.25)
    }
    // Eq. (7.26) in the limit: scale all q down.
    for scale in [0.1, 0.01, 0.001] {
        let q: Vec<f64> = (0..10).map(|i| scale * (0.2 + 0.07 * i as f64)).collect();
        let k = 9;
        let ln_ref = q[k].ln() + q[..k].iter().map(|qi| (-qi).ln_1p()).sum::<f64>();
        let ln_dec = -q[..k].iter().sum::<f64>() + (-(-q[k]).exp_m1()).ln();
        let gap = (ln_ref - ln_dec).abs();
        let bound = q[k] / 2.0 + q[..k].iter().map(|qi| qi * qi).sum::<f64>();
        assert!(gap <= bound * 1.01, "scale {scale}: gap {gap} > {bound}");
        assert!(
            gap < 0.6 * scale,
            "scale {scale}: gap {gap} does not vanish"
        );
    }
}

/// ∫ λ^δ e^{−λ r} Gamma(λ; a, b) dλ by adaptive Simpson.
fn gamma_factor(a: f64, b: f64, r: f64, hit: bool) -> f64 {
    let delta = f64::from(u8::from(hit));
    let norm = a * b.ln() - ln_gamma(a);
    let f = |lambda: f64| {
        if lambda <= 0.0 {
            return if a - 1.0 + delta == 0.0 {
                norm.exp()
            } else {
                0.0
            };
        }
        (norm + (a - 1.0 + delta) * lambda.ln() - (b + r) * lambda).exp()
    };
    let scale = (a + delta) / (b + r);
    let upper = scale + 40.0 * (a + delta).sqrt() / (b + r) + 40.0 / (b + r);
    simpson(&f, 0.0, upper, 1e-15)
}

/// ∫ μ^δ (1 − μ)^{1−δ} Beta(μ; a, b) dμ by adaptive Simpson.
fn beta_factor(a: f64, b: f64, hit: bool) -> f64 {
    let (p, q) = if hit { (a, b - 1.0) } else { (a - 1.0, b) };
    let norm = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b);
    let f = |mu: f64| {
        let term = |power: f64, x: f64| if power == 0.0 { 0.0 } else { power * x.ln() };
        (norm + term(p, mu) + term(q, 1.0 - mu)).exp()
    };
    simpson(&f, 0.0, 1.0, 1e-15)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(30))]

    /// Eq. 8.21–8.22 and the decay-rate closed form (Sec. 8.4.5): the model's ray
    /// likelihood equals the product over cells of numerically integrated
    /// likelihood × posterior, to 1e-6 relative.
    #[test]
    fn posterior_likelihoods_equal_numerical_integration(
        seed in any::<u64>(),
        alpha in 1.0..4.0f64,
        beta in 1.0..4.0f64,
    ) {
        let stats = random_stats(seed);
        let grid = *stats.grid();
        let range = SensorRange::new(0.0, 4.8).unwrap();
        let dec = DecayRatePosteriorModel2::new(&stats, GammaPosteriorConfig { range, prior: Some(GammaPrior::new(alpha, beta).unwrap()) }).unwrap();
        let refl = ReflectionModel2::posterior(&stats, BetaPosteriorConfig { range, prior: Some(BetaPrior::new(alpha, beta).unwrap()) }).unwrap();
        for ray in rays(seed ^ 0x5eed, 4) {
            let r = ray.range.hit().unwrap();
            let crossings: Vec<_> = grid.traverse_ray(&ray, 100.0).collect();
            let last = crossings.len() - 1;
            let (mut ln_dec, mut ln_ref) = (0.0, 0.0);
            for (j, c) in crossings.iter().enumerate() {
                let cell = stats.cell(c.index);
                let hit = j == last;
                ln_dec += gamma_factor(cell.h() + alpha, cell.path_length_m() + beta, c.length(), hit).ln();
                if hit || c.length() > 0.0 {
                    ln_ref += beta_factor(cell.h() + alpha, cell.m() + beta, hit).ln();
                }
            }
            let model_dec = dec.ray_log_likelihood(&ray);
            prop_assert!((model_dec - ln_dec).abs() < 1e-6, "decay: {model_dec} vs {ln_dec}");
            // The reflection model's density divides by the endpoint cell's chord (Eq. 7.32).
            let k = crossings[last];
            // Returns at or beyond r_max are `sup`, so the chord is clipped to r_max.
            let chord = crossing_chord(&grid, &ray, k.cell, range.max_range_m);
            let model_ref = refl.ray_log_likelihood(&ray) + chord.ln();
            prop_assert!((model_ref - ln_ref).abs() < 1e-6, "reflection: {model_ref} vs {ln_ref}");
            // No-returns: the miss factors up to r_max.
            let sup = Ray2 { range: Range::NoReturn, ..ray };
            let ln_sup: f64 = grid
                .traverse_ray(&sup, range.max_range_m)
                .map(|c| {
                    let cell = stats.cell(c.index);
                    gamma_factor(cell.h() + alpha, cell.path_length_m() + beta, c.length(), false).ln()
                })
                .sum();
            prop_assert!((dec.ray_log_likelihood(&sup) - ln_sup).abs() < 1e-6);
            let _ = r;
        }
    }
}

/// The chord of the ray's line through a cell, clipped to `0 ≤ t ≤ max_range_m`.
fn crossing_chord(grid: &Grid2, ray: &Ray2, cell: [usize; 2], max_range_m: f64) -> f64 {
    let bounds = grid.cell_bounds(cell);
    let (t0, t1) = bounds
        .clip_segment(
            &ray.origin,
            ray.direction.as_ref(),
            f64::NEG_INFINITY,
            f64::INFINITY,
        )
        .unwrap();
    t1.min(max_range_m) - t0.max(0.0)
}

/// `∫ f` over `[a, b]` on pieces that shrink geometrically towards `a` (where the
/// posterior decay-rate density of a cell with a small prior rate is sharply peaked), each
/// with 10-point Gauss–Legendre (an open rule: the cell faces are never evaluated).
fn graded(f: &impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    let mut total = 0.0;
    let mut hi = b;
    for _ in 0..40 {
        let lo = a + 0.5 * (hi - a);
        total += gauss_legendre(f, lo, hi, 1);
        hi = lo;
    }
    total + gauss_legendre(f, a, hi, 1)
}

/// `P(sub) + ∫_{r_min}^{r_max} p(r) dr + P(sup)` along `ray` (origin and `r_max` inside
/// the grid), integrating the density cell by cell.
fn total_probability(model: &impl SensorModel<Planar>, grid: &Grid2, ray: &Ray2) -> f64 {
    let range = model.sensor_range();
    let at = |r: f64| Ray2 {
        range: Range::Hit(r),
        ..*ray
    };
    let density = |r: f64| model.ray_log_likelihood(&at(r)).exp();
    let no_return = Ray2 {
        range: Range::NoReturn,
        ..*ray
    };
    let mut cuts: Vec<f64> = grid
        .traverse_ray(&no_return, range.max_range_m)
        .map(|c| c.t_exit)
        .collect();
    cuts.push(range.min_range_m);
    cuts.push(0.0);
    cuts.retain(|t| *t >= range.min_range_m && *t <= range.max_range_m);
    cuts.sort_by(f64::total_cmp);
    let integral: f64 = cuts
        .windows(2)
        .filter(|w| w[1] > w[0])
        .map(|w| graded(&density, w[0], w[1]))
        .sum();
    let sup = model
        .ray_log_likelihood(&Ray2 {
            range: Range::NoReturn,
            ..*ray
        })
        .exp();
    let sub = if range.min_range_m > 0.0 {
        model.ray_log_likelihood(&at(0.5 * range.min_range_m)).exp()
    } else {
        0.0
    };
    sub + integral + sup
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(25))]

    /// `P(sub) + ∫ p + P(sup) = 1` (Sec. 7.4.4) for random maps, for every model.
    #[test]
    fn probabilities_sum_to_one(seed in any::<u64>(), with_min in any::<bool>()) {
        let stats = random_stats(seed);
        let grid = *stats.grid();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let min = if with_min { rng.random_range(0.05..1.0) } else { 0.0 };
        let range = SensorRange::new(min, 4.5).unwrap();
        let ray = rays(seed, 1)[0];
        let check = |name: &str, total: f64| {
            assert!((total - 1.0).abs() < 1e-6, "{name}: total probability {total}");
        };
        let dec = DecayRateModel2::new(&stats, DecayRateConfig { range, ..Default::default() }).unwrap();
        check("decay-rate", total_probability(&dec, &grid, &ray));
        let dec_post = DecayRatePosteriorModel2::new(&stats, GammaPosteriorConfig { range, prior: None }).unwrap();
        check("decay-rate posterior", total_probability(&dec_post, &grid, &ray));
        let refl = ReflectionModel2::maximum_likelihood(&stats, ReflectionConfig { range, ..Default::default() }).unwrap();
        check("reflection", total_probability(&refl, &grid, &ray));
        let refl_post = ReflectionModel2::posterior(&stats, BetaPosteriorConfig { range, prior: None }).unwrap();
        check("reflection posterior", total_probability(&refl_post, &grid, &ray));
        let occupancy = LogOddsModel2::new(&stats, LogOddsConfig { range, ..Default::default() }).unwrap();
        check("log-odds", total_probability(&occupancy, &grid, &ray));
        let field = LikelihoodFieldModel2::new(&stats, LikelihoodFieldConfig { range, ..Default::default() }).unwrap();
        check("likelihood field", total_probability(&field, &grid, &ray));
    }
}

/// Rays in a homogeneous medium with decay rate λ (ranges drawn from
/// Exp(λ), no-returns beyond r_max) give back λ.
#[test]
fn constant_medium_recovers_the_decay_rate() {
    let lambda = 0.8;
    let grid = Grid2::new(Point2::new(0.0, 0.0), 0.1, [100, 1]).unwrap();
    let config = MappingConfig {
        range: SensorRange::new(0.0, 9.5).unwrap(),
        ..Default::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(2017);
    let mut stats = DenseStats2::new(grid);
    for _ in 0..20_000 {
        let u: f64 = rng.random_range(f64::EPSILON..1.0);
        let r = -u.ln() / lambda;
        let ray = Ray2::new(
            Point2::new(0.0, 0.05),
            Vector2::new(1.0, 0.0),
            Range::Hit(r),
        )
        .unwrap();
        stats.insert_ray(&ray, &config);
    }
    let hits: f64 = stats.cells().iter().map(CellStats::h).sum();
    let length: f64 = stats.cells().iter().map(CellStats::path_length_m).sum();
    let pooled = hits / length;
    assert!(
        (pooled / lambda - 1.0).abs() < 0.03,
        "pooled estimate {pooled}"
    );
    let model = DecayRateModel2::new(&stats, DecayRateConfig::default()).unwrap();
    for (i, rate) in model.rates().iter().take(20).enumerate() {
        assert!((rate / lambda - 1.0).abs() < 0.25, "cell {i}: λ = {rate}");
    }
}

/// Per-cell statistics with every cell hit (so the ML rate `H/R` is positive) scaled by `n`:
/// `n` times the observations of the same map.
fn observed_stats_times(n: u32) -> DenseStats2 {
    let grid = grid();
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let cells = (0..grid.num_cells())
        .map(|_| {
            let (h, m, r) = (
                rng.random_range(1..6u32),
                rng.random_range(0..30u32),
                rng.random_range(0.5..12.0),
            );
            CellStats::new(h * n, m * n, r * f64::from(n))
        })
        .collect();
    DenseStats2::from_parts(grid, cells, Default::default()).unwrap()
}

/// Sec. 8.4.3–8.4.5: with `n` times the observations per cell the Gamma posterior
/// Gamma(nH + α, nR + β) concentrates on the ML rate H/R (the prior, a function of the ML
/// rates, stays the same), so the FMP likelihood L(z, x) tends to the MLM likelihood: per
/// ray the gap shrinks like 1/n and the ratio of summed log-likelihoods (the thesis's
/// Table 8.2 ratio) tends to 1.
#[test]
fn posterior_tends_to_the_ml_map_with_many_observations() {
    let range = SensorRange::new(0.0, 4.8).unwrap();
    let mut test_rays = rays(23, 60);
    test_rays.extend(rays(29, 20).into_iter().map(|ray| Ray2 {
        range: Range::NoReturn,
        ..ray
    }));
    let mut previous: Option<(f64, f64)> = None;
    for n in [1u32, 10, 100, 1000, 10_000] {
        let stats = observed_stats_times(n);
        let ml = DecayRateModel2::new(
            &stats,
            DecayRateConfig {
                range,
                ..Default::default()
            },
        )
        .unwrap();
        let fmp =
            DecayRatePosteriorModel2::new(&stats, GammaPosteriorConfig { range, prior: None })
                .unwrap();
        let prior_n1 = GammaPrior::estimate(observed_stats_times(1).cells());
        assert!((fmp.prior().alpha / prior_n1.alpha - 1.0).abs() < 1e-9);
        let (mut sum_ml, mut sum_fmp, mut max_gap) = (0.0, 0.0, 0.0f64);
        for ray in &test_rays {
            let (a, b) = (ml.ray_log_likelihood(ray), fmp.ray_log_likelihood(ray));
            assert!(a.is_finite() && b.is_finite());
            sum_ml += a;
            sum_fmp += b;
            max_gap = max_gap.max((a - b).abs());
        }
        assert!(sum_ml < -10.0, "sum {sum_ml}");
        let ratio = sum_ml / sum_fmp;
        eprintln!("n = {n}: ratio MLM/FMP {ratio:.6}, largest per-ray gap {max_gap:.2e} nats");
        if let Some((previous_gap, previous_ratio)) = previous {
            assert!(max_gap < 0.5 * previous_gap, "n = {n}: gap {max_gap}");
            assert!((ratio - 1.0).abs() <= (previous_ratio - 1.0).abs() + 1e-12);
        }
        previous = Some((max_gap, ratio));
    }
    let (gap, ratio) = previous.unwrap();
    assert!(gap < 2e-3 && (ratio - 1.0).abs() < 1e-4, "{gap} {ratio}");
}

/// The tabulated posterior (every crossed cell counted at the mean chord of its direction):
/// on a uniform map, along a grid axis from a cell face to a cell face (no-returns end on one
/// at r_max), every chord is the cell edge, so it
/// equals the exact Sec. 8.4.5 likelihood up to the table's f32 rounding; on a random map
/// in any direction it stays close.
#[test]
fn tabulated_posterior_follows_the_exact_model() {
    let range = SensorRange::new(0.0, 4.5).unwrap();
    let build = |stats: &DenseStats2, prior: Option<GammaPrior>| {
        let exact =
            DecayRatePosteriorModel2::new(stats, GammaPosteriorConfig { range, prior }).unwrap();
        let table = Tabulated::<DecayRatePosteriorModel2>::new(
            exact.clone(),
            OpticalDepthConfig::default(),
        )
        .unwrap();
        (exact, table)
    };
    // Uniform cells with a small posterior rate b = R + β, where ln(1 + d/b) is far from
    // linear in d.
    let grid = grid();
    let uniform = DenseStats2::from_parts(
        grid,
        vec![CellStats::new(2, 10, 0.4); grid.num_cells()],
        Default::default(),
    )
    .unwrap();
    let (exact, table) = build(&uniform, Some(GammaPrior::new(0.5, 0.1).unwrap()));
    for (k, angle) in [0.0, FRAC_PI_2, PI, -FRAC_PI_2].into_iter().enumerate() {
        for range in [
            Range::Hit(0.3),
            Range::Hit(2.0),
            Range::Hit(3.77),
            Range::NoReturn,
        ] {
            // Origin on a cell face (x = 6 or y = 6), in the middle of a cell across.
            let origin = if k % 2 == 0 {
                Point2::new(6.0, 6.25)
            } else {
                Point2::new(5.75, 6.0)
            };
            let ray = Ray2::from_angle(origin, angle, range);
            let (e, t) = (
                exact.ray_log_likelihood(&ray),
                table.ray_log_likelihood(&ray),
            );
            assert!(
                (e - t).abs() < 1e-4 * (1.0 + e.abs()),
                "{angle} {range:?}: {e} vs {t}"
            );
        }
    }
    // A random map of 0.5 m cells (rates jumping by orders of magnitude from cell to cell)
    // is hard for any table; the posterior's mean-chord table errs no more than the ML
    // decay-rate table (exact chords times a fixed rate) on the same map.
    let stats = random_stats(5);
    let (exact, table) = build(&stats, None);
    let ml = DecayRateModel2::new(
        &stats,
        DecayRateConfig {
            range,
            ..Default::default()
        },
    )
    .unwrap();
    let ml_table =
        Tabulated::<DecayRateModel2>::new(ml.clone(), OpticalDepthConfig::default()).unwrap();
    let quantiles = |exact: &dyn SensorModel<Planar>, table: &dyn SensorModel<Planar>| {
        let mut gaps: Vec<f64> = rays(41, 400)
            .iter()
            .map(|ray| (exact.ray_log_likelihood(ray) - table.ray_log_likelihood(ray)).abs())
            .collect();
        gaps.sort_by(f64::total_cmp);
        (gaps[gaps.len() / 2], gaps[gaps.len() * 95 / 100])
    };
    let (median, p95) = quantiles(&exact, &table);
    let (ml_median, ml_p95) = quantiles(&ml, &ml_table);
    eprintln!(
        "|Δ| per ray, table vs exact: posterior median {median:.4}, p95 {p95:.4} nats; \
         ML median {ml_median:.4}, p95 {ml_p95:.4} nats"
    );
    assert!(median <= 1.25 * ml_median && p95 <= 1.25 * ml_p95);
    assert!(median < 0.5 && p95 < 3.0, "median {median}, p95 {p95}");
}
