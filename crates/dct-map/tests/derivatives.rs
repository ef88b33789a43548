//! Analytic gradients and Hessians (Sec. 9.4.4) against finite differences, per ray and
//! aggregated, including the `sub` erratum.
#![allow(clippy::unwrap_used)]

mod common;

use common::{random_map, random_ray, random_rays, rng};
use raypath_dct_map::derivatives::{SubHessian, ray_derivatives};
use raypath_dct_map::{DctMap, FitProblem, MapRay, Outcome, Shape, product_matrix, reference};

fn shifted(map: &DctMap, i: usize, h: f64) -> DctMap {
    let mut a = map.coefficients().to_vec();
    a[i] += h;
    DctMap::new(map.extent_m(), map.shape(), a).unwrap()
}

fn check_ray(map: &DctMap, ray: &MapRay) {
    let n = map.shape().len();
    let d = ray_derivatives(map, ray, SubHessian::Corrected);
    assert!((d.log_likelihood - map.ray_log_likelihood(ray)).abs() < 1e-10);
    let h = 1e-5;
    for i in 0..n {
        let (up, down) = (shifted(map, i, h), shifted(map, i, -h));
        let fd = (up.ray_log_likelihood(ray) - down.ray_log_likelihood(ray)) / (2.0 * h);
        assert!(
            (fd - d.gradient[i]).abs() < 1e-6 * fd.abs().max(1.0),
            "{:?} grad {i}: fd {fd} vs {}",
            ray.outcome,
            d.gradient[i]
        );
        let (gu, gd) = (
            ray_derivatives(&up, ray, SubHessian::Corrected).gradient,
            ray_derivatives(&down, ray, SubHessian::Corrected).gradient,
        );
        for j in 0..n {
            let fd = (gu[j] - gd[j]) / (2.0 * h);
            let an = d.hessian[j * n + i];
            assert!(
                (fd - an).abs() < 1e-5 * fd.abs().max(1.0),
                "{:?} hess {i},{j}: fd {fd} vs {an}",
                ray.outcome
            );
        }
    }
}

#[test]
fn gradient_and_hessian_match_finite_differences() {
    let extent = [5.0, 4.0];
    let map = random_map(11, extent, Shape { l: 3, m: 4 });
    let mut r = rng(12);
    for outcome in [Outcome::Hit, Outcome::Sub, Outcome::Super] {
        for _ in 0..4 {
            check_ray(&map, &random_ray(&mut r, extent, outcome));
        }
    }
}

#[test]
fn printed_sub_hessian_fails_finite_differences() {
    let extent = [5.0, 4.0];
    let map = random_map(13, extent, Shape { l: 3, m: 3 });
    let mut r = rng(14);
    let ray = random_ray(&mut r, extent, Outcome::Sub);
    let right = ray_derivatives(&map, &ray, SubHessian::Corrected).hessian;
    let printed = ray_derivatives(&map, &ray, SubHessian::AsPrinted).hessian;
    let diff: f64 = right
        .iter()
        .zip(&printed)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let scale: f64 = right.iter().map(|a| a.abs()).fold(0.0, f64::max);
    assert!(
        diff > 1e-3 * scale,
        "printed form should differ: {diff} vs {scale}"
    );
}

#[test]
fn c_ij_of_eq_9_10_is_twice_the_product_matrix() {
    let extent = [5.0, 4.0];
    let map = random_map(15, extent, Shape { l: 3, m: 2 });
    let mut r = rng(16);
    let ray = random_ray(&mut r, extent, Outcome::Super);
    let c = reference::c_matrix(&map, &ray);
    let t = raypath_dct_map::moments::moments(map.shape(), extent, &ray.segment());
    let k = product_matrix(map.shape(), &t);
    for (c, k) in c.iter().zip(&k) {
        assert!((c - 2.0 * k).abs() < 1e-10);
    }
}

#[test]
fn aggregated_objective_equals_the_sum_over_rays() {
    let extent = [6.0, 5.0];
    let map = random_map(17, extent, Shape { l: 4, m: 3 });
    let n = map.shape().len();
    let mut r = rng(18);
    let outcomes = [Outcome::Hit, Outcome::Super, Outcome::Hit, Outcome::Sub];
    let rays = random_rays(&mut r, extent, 30, &outcomes);
    let mut problem = FitProblem::new(extent, map.shape(), &rays).unwrap();
    problem.set_ridge_factor(0.0);
    problem.set_prior_path_density(0.0);
    let e = problem.evaluate(map.coefficients());
    let h = problem.negative_hessian(map.coefficients(), &e.amplitudes);
    let (mut ll, mut grad, mut hess) = (0.0, vec![0.0; n], vec![0.0; n * n]);
    for ray in &rays {
        let d = ray_derivatives(&map, ray, SubHessian::Corrected);
        ll += d.log_likelihood;
        grad.iter_mut().zip(&d.gradient).for_each(|(a, b)| *a += b);
        hess.iter_mut().zip(&d.hessian).for_each(|(a, b)| *a += b);
    }
    assert!((ll - e.log_likelihood).abs() < 1e-9 * ll.abs());
    assert!((ll - map.log_likelihood(&rays)).abs() < 1e-9 * ll.abs());
    assert!((ll - problem.log_likelihood(map.coefficients())).abs() < 1e-9 * ll.abs());
    for (a, b) in grad.iter().zip(&e.gradient) {
        assert!((a - b).abs() < 1e-8 * a.abs().max(1.0), "{a} vs {b}");
    }
    for (a, b) in hess.iter().zip(&h) {
        assert!((a + b).abs() < 1e-8 * a.abs().max(1.0), "{a} vs −{b}");
    }
}

#[test]
fn prior_is_the_integral_of_the_rate_and_enters_the_derivatives() {
    let extent = [6.0, 5.0];
    let map = random_map(19, extent, Shape { l: 4, m: 3 });
    let a = map.coefficients().to_vec();
    let n = a.len();
    let mut r = rng(20);
    let outcomes = [Outcome::Hit, Outcome::Super, Outcome::Sub];
    let rays = random_rays(&mut r, extent, 20, &outcomes);
    let mut problem = FitProblem::new(extent, map.shape(), &rays).unwrap();
    problem.set_ridge_factor(0.0);
    let rho = 0.7;
    problem.set_prior_path_density(rho);
    // −ρ ∬ λ by the midpoint rule (exact for these frequencies) on a 64 × 64 lattice.
    let cell = extent[0] * extent[1] / (64.0 * 64.0);
    let integral: f64 = map.rates_on_lattice(64, 64).iter().sum::<f64>() * cell;
    let prior = problem.log_prior(&a);
    assert!(
        (prior + rho * integral).abs() < 1e-10 * integral,
        "{prior} vs {}",
        -rho * integral
    );
    let plain = map.log_likelihood(&rays);
    assert!((problem.log_likelihood(&a) - (plain + prior)).abs() < 1e-9 * plain.abs());
    // Gradient and Hessian of the whole objective (with the ridge, too) by central differences.
    problem.set_ridge_factor(1e-3);
    let e = problem.evaluate(&a);
    let hess = problem.negative_hessian(&a, &e.amplitudes);
    let h = 1e-5;
    for i in 0..n {
        let (mut up, mut down) = (a.clone(), a.clone());
        up[i] += h;
        down[i] -= h;
        let fd = (problem.log_likelihood(&up) - problem.log_likelihood(&down)) / (2.0 * h);
        assert!(
            (fd - e.gradient[i]).abs() < 1e-6 * fd.abs().max(1.0),
            "grad {i}: fd {fd} vs {}",
            e.gradient[i]
        );
        let (gu, gd) = (
            problem.evaluate(&up).gradient,
            problem.evaluate(&down).gradient,
        );
        for j in 0..n {
            let fd = (gu[j] - gd[j]) / (2.0 * h);
            let an = -hess[j * n + i];
            assert!(
                (fd - an).abs() < 1e-5 * fd.abs().max(1.0),
                "hess {i},{j}: fd {fd} vs {an}"
            );
        }
    }
}
