//! Nelder–Mead simplex search as MATLAB `fminsearch` (Lagarias et al. 1998) runs it in the
//! reference implementation: polar vertex coordinates, initial simplex `x0 + 5 %` per
//! non-zero coordinate (0.00025 for zeros), reflection 1, expansion 2, contraction ½,
//! shrink ½; stop when the simplex is within `TolX` and its costs within `TolFun`, or after
//! `200·dim` iterations or evaluations.

use nalgebra::Point2;

use super::Problem;

fn encode(problem: &Problem<'_>) -> Vec<f64> {
    let mut x = Vec::with_capacity(problem.dim());
    for (i, v) in problem.start.iter().enumerate() {
        let rho = v.coords.norm();
        if problem.is_end(i) {
            x.push(rho);
        } else {
            x.push(v.y.atan2(v.x));
            x.push(rho);
        }
    }
    x
}

/// Vertices from parameters; `false` if a radius is not positive.
fn decode(problem: &Problem<'_>, x: &[f64], out: &mut Vec<Point2<f64>>) -> bool {
    out.clear();
    let mut j = 0;
    for i in 0..problem.n() {
        if problem.is_end(i) {
            let rho = x[j];
            j += 1;
            if rho.is_nan() || rho <= 0.0 {
                return false;
            }
            out.push(Point2::from(problem.end_dir(i) * rho));
        } else {
            let (theta, rho) = (x[j], x[j + 1]);
            j += 2;
            if rho.is_nan() || rho <= 0.0 {
                return false;
            }
            out.push(Point2::new(rho * theta.cos(), rho * theta.sin()));
        }
    }
    true
}

/// Runs the search; `None` when it found nothing better than the start.
pub fn run(
    problem: &Problem<'_>,
    tol_x: f64,
    tol_f: f64,
    iterations_per_dim: usize,
    slot_of: &[u32],
) -> Option<Vec<Point2<f64>>> {
    let dim = problem.dim();
    let max_iter = iterations_per_dim.saturating_mul(dim);
    let mut best = vec![(f64::INFINITY, u32::MAX); problem.beams.len()];
    let mut verts = Vec::with_capacity(problem.n());
    let evals = std::cell::Cell::new(0usize);
    let mut f = |x: &[f64]| -> f64 {
        evals.set(evals.get() + 1);
        if decode(problem, x, &mut verts) {
            problem.cost(&verts, slot_of, &mut best)
        } else {
            f64::INFINITY
        }
    };
    let x0 = encode(problem);
    let f0 = f(&x0);
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(dim + 1);
    simplex.push((x0.clone(), f0));
    for i in 0..dim {
        let mut x = x0.clone();
        x[i] = if x[i] != 0.0 { 1.05 * x[i] } else { 0.00025 };
        let fx = f(&x);
        simplex.push((x, fx));
    }
    let mut centroid = vec![0.0; dim];
    let mut trial = vec![0.0; dim];
    let mut trial2 = vec![0.0; dim];
    let mut iterations = 0usize;
    loop {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let f_best = simplex[0].1;
        let spread_f = simplex
            .iter()
            .map(|s| (s.1 - f_best).abs())
            .fold(0.0, f64::max);
        let spread_x = simplex
            .iter()
            .skip(1)
            .flat_map(|s| s.0.iter().zip(&simplex[0].0).map(|(a, b)| (a - b).abs()))
            .fold(0.0, f64::max);
        if (spread_f <= tol_f && spread_x <= tol_x)
            || iterations >= max_iter
            || evals.get() >= max_iter
        {
            break;
        }
        iterations += 1;
        centroid.fill(0.0);
        for s in &simplex[..dim] {
            for (c, v) in centroid.iter_mut().zip(&s.0) {
                *c += v / dim as f64;
            }
        }
        let worst = simplex[dim].0.clone();
        let f_worst = simplex[dim].1;
        let f_second = simplex[dim - 1].1;
        let point = |t: f64, out: &mut Vec<f64>| {
            for ((o, c), w) in out.iter_mut().zip(&centroid).zip(&worst) {
                *o = c + t * (c - w);
            }
        };
        point(1.0, &mut trial);
        let f_r = f(&trial);
        if f_r < f_best {
            point(2.0, &mut trial2);
            let f_e = f(&trial2);
            simplex[dim] = if f_e < f_r {
                (trial2.clone(), f_e)
            } else {
                (trial.clone(), f_r)
            };
            continue;
        }
        if f_r < f_second {
            simplex[dim] = (trial.clone(), f_r);
            continue;
        }
        // Contraction: outside when the reflection beat the worst point, else inside.
        let (t, reference) = if f_r < f_worst {
            (0.5, f_r)
        } else {
            (-0.5, f_worst)
        };
        point(t, &mut trial2);
        let f_c = f(&trial2);
        let accept = if t > 0.0 {
            f_c <= reference
        } else {
            f_c < reference
        };
        if accept {
            simplex[dim] = (trial2.clone(), f_c);
            continue;
        }
        // Shrink towards the best vertex.
        let best_x = simplex[0].0.clone();
        for s in simplex.iter_mut().skip(1) {
            for (v, b) in s.0.iter_mut().zip(&best_x) {
                *v = b + 0.5 * (*v - b);
            }
            s.1 = f(&s.0);
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (x, fx) = &simplex[0];
    let mut out = Vec::with_capacity(problem.n());
    (*fx < f0 && decode(problem, x, &mut out)).then_some(out)
}
