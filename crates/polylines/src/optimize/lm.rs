//! Levenberg–Marquardt on the radial residuals `e_k = r_k − r̂_k`.
//!
//! With the origin at the sensor, the distance along unit beam `u` to segment `(p, q)` is
//! `t = (p × q) / (u × (q − p))`; its derivatives by `p` and `q` are closed-form, and each
//! residual depends on the two vertices of the segment it hits only, so `JᵀJ` is assembled
//! from 4×4 blocks and solved densely (a few dozen parameters). Interior vertices are
//! Cartesian `(x, y)`; the ends of an open polyline are their radius along their beam. The
//! hit segment of every beam is re-determined at every evaluation (the cost is piecewise
//! smooth, with kinks where a beam's hit moves to the next segment); a step is accepted only
//! if the true cost drops.

use nalgebra::{DMatrix, DVector, Point2, Vector2};

use super::Problem;

/// Largest change of one coordinate in one iteration, metres.
const MAX_STEP_M: f64 = 0.1;

/// Where vertex `i`'s parameters start and how many there are.
fn layout(problem: &Problem<'_>) -> Vec<(usize, usize)> {
    let mut offset = 0;
    (0..problem.n())
        .map(|i| {
            let dof = if problem.is_end(i) { 1 } else { 2 };
            let entry = (offset, dof);
            offset += dof;
            entry
        })
        .collect()
}

fn encode(problem: &Problem<'_>) -> DVector<f64> {
    let mut x = Vec::with_capacity(problem.dim());
    for (i, v) in problem.start.iter().enumerate() {
        if problem.is_end(i) {
            x.push(v.coords.dot(&problem.end_dir(i)));
        } else {
            x.push(v.x);
            x.push(v.y);
        }
    }
    DVector::from_vec(x)
}

fn decode(problem: &Problem<'_>, x: &DVector<f64>, out: &mut Vec<Point2<f64>>) -> bool {
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
            out.push(Point2::new(x[j], x[j + 1]));
            j += 2;
        }
    }
    out.iter().all(|p| p.x.is_finite() && p.y.is_finite())
}

/// `∂t/∂p` and `∂t/∂q` of the hit distance along `u` on segment `(p, q)`.
fn hit_gradient(
    u: &Vector2<f64>,
    p: &Point2<f64>,
    q: &Point2<f64>,
) -> (Vector2<f64>, Vector2<f64>) {
    let num = p.x * q.y - p.y * q.x;
    let d = q - p;
    let den = u.x * d.y - u.y * d.x;
    let den2 = den * den;
    let dnum_p = Vector2::new(q.y, -q.x);
    let dnum_q = Vector2::new(-p.y, p.x);
    let dden_p = Vector2::new(u.y, -u.x);
    let dden_q = Vector2::new(-u.y, u.x);
    (
        (dnum_p * den - dden_p * num) / den2,
        (dnum_q * den - dden_q * num) / den2,
    )
}

/// Runs the solver; `None` when no step improved the start.
pub fn run(
    problem: &Problem<'_>,
    max_iterations: usize,
    rel_tolerance: f64,
    slot_of: &[u32],
) -> Option<Vec<Point2<f64>>> {
    let dim = problem.dim();
    let lay = layout(problem);
    let m = problem.beams.len();
    let mut best = vec![(f64::INFINITY, u32::MAX); m];
    let mut verts = Vec::with_capacity(problem.n());
    let mut x = encode(problem);
    if !decode(problem, &x, &mut verts) {
        return None;
    }
    let cost0 = problem.cost(&verts, slot_of, &mut best);
    let mut cost = cost0;
    let mut h = DMatrix::<f64>::zeros(dim, dim);
    let mut g = DVector::<f64>::zeros(dim);
    let mut lambda = 1e-3;
    let mut improved = false;
    let n = problem.n();
    for _ in 0..max_iterations {
        // Normal equations at x (best holds the hits of `verts`).
        h.fill(0.0);
        g.fill(0.0);
        for (&(k, r), &(t, s)) in problem.beams.iter().zip(&best) {
            if !t.is_finite() {
                continue;
            }
            let s = s as usize;
            let (a, b) = (s, (s + 1) % n);
            let u = problem.rays.dir(k);
            let (gp, gq) = hit_gradient(&u, &verts[a], &verts[b]);
            // Residual e = r − t, de = −dt.
            let e = r - t;
            let mut idx = [0usize; 4];
            let mut val = [0.0f64; 4];
            let mut len = 0;
            for (vertex, grad) in [(a, gp), (b, gq)] {
                let (offset, dof) = lay[vertex];
                if dof == 1 {
                    idx[len] = offset;
                    val[len] = -grad.dot(&problem.end_dir(vertex));
                    len += 1;
                } else {
                    idx[len] = offset;
                    val[len] = -grad.x;
                    idx[len + 1] = offset + 1;
                    val[len + 1] = -grad.y;
                    len += 2;
                }
            }
            for i in 0..len {
                g[idx[i]] += val[i] * e;
                for j in 0..len {
                    h[(idx[i], idx[j])] += val[i] * val[j];
                }
            }
        }
        let mut accepted = false;
        // Damping floor: a vertex that few beams see (a tiny segment between two beams)
        // must not be thrown far by a nearly singular column.
        let floor = 1e-3 * (0..dim).map(|i| h[(i, i)]).sum::<f64>() / dim.max(1) as f64 + 1e-12;
        while lambda < 1e12 {
            let mut a = h.clone();
            for i in 0..dim {
                a[(i, i)] += lambda * h[(i, i)].max(floor);
            }
            let Some(chol) = a.cholesky() else {
                lambda *= 10.0;
                continue;
            };
            let mut step = chol.solve(&(-&g));
            // Trust region: no coordinate moves more than MAX_STEP_M per iteration.
            let largest = step.amax();
            if largest > MAX_STEP_M {
                step *= MAX_STEP_M / largest;
            }
            let candidate = &x + &step;
            let mut trial_verts = Vec::with_capacity(n);
            if !decode(problem, &candidate, &mut trial_verts) {
                lambda *= 10.0;
                continue;
            }
            let trial_cost = problem.cost(&trial_verts, slot_of, &mut best);
            if trial_cost < cost {
                let gain = cost - trial_cost;
                x = candidate;
                verts = trial_verts;
                cost = trial_cost;
                lambda = (lambda * 0.3).max(1e-9);
                accepted = true;
                improved = true;
                if gain <= rel_tolerance * cost.max(1e-300) {
                    return Some(verts);
                }
                break;
            }
            lambda *= 10.0;
        }
        if !accepted {
            break;
        }
        // `best` holds the hits of the accepted vertices.
    }
    // On a rejected last trial `best` is stale, but it is not used any more.
    (improved && cost < cost0).then_some(verts)
}
