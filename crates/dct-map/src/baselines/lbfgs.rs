//! A small L-BFGS minimizer (Nocedal & Wright 2006, Alg. 7.4/7.5) with a backtracking Armijo
//! line search, for the smooth objectives of the baselines (the Hilbert map's regularized
//! logistic loss, the GPOM squashing calibration).

use std::collections::VecDeque;

/// Stopping rules and memory.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LbfgsConfig {
    /// Iteration cap.
    pub max_iterations: usize,
    /// Stored correction pairs.
    pub memory: usize,
    /// Stop when `‖∇f‖_∞` falls below this.
    pub gradient_tolerance: f64,
    /// Stop when an iteration lowers `f` by less than this times `max(|f|, 1)`.
    pub relative_tolerance: f64,
}

/// The minimizer's result.
#[derive(Clone, Debug)]
pub(crate) struct LbfgsResult {
    /// The last accepted point.
    pub x: Vec<f64>,
    /// `f` there.
    pub value: f64,
    /// Accepted iterations.
    pub iterations: usize,
    /// Objective evaluations.
    pub evaluations: usize,
    /// Whether a tolerance (not the iteration cap) stopped it.
    pub converged: bool,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn inf_norm(a: &[f64]) -> f64 {
    a.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// The quasi-Newton direction `−H ∇f` by the two-loop recursion, written into `q`.
fn direction(memory: &VecDeque<(Vec<f64>, Vec<f64>, f64)>, g: &[f64], q: &mut [f64]) {
    q.copy_from_slice(g);
    let mut alphas = Vec::with_capacity(memory.len());
    for (s, y, rho) in memory.iter().rev() {
        let a = rho * dot(s, q);
        q.iter_mut().zip(y).for_each(|(q, y)| *q -= a * y);
        alphas.push(a);
    }
    let gamma = memory
        .back()
        .map_or(1.0 / inf_norm(g).max(1.0), |(s, y, _)| {
            dot(s, y) / dot(y, y)
        });
    q.iter_mut().for_each(|q| *q *= gamma);
    for ((s, y, rho), a) in memory.iter().zip(alphas.iter().rev()) {
        let b = rho * dot(y, q);
        q.iter_mut().zip(s).for_each(|(q, s)| *q += (a - b) * s);
    }
    q.iter_mut().for_each(|q| *q = -*q);
}

/// Minimizes `f` from `x0`; `f(x, grad)` returns `f(x)` and writes `∇f(x)` into `grad`.
pub(crate) fn minimize(
    mut f: impl FnMut(&[f64], &mut [f64]) -> f64,
    x0: Vec<f64>,
    config: &LbfgsConfig,
) -> LbfgsResult {
    let n = x0.len();
    let mut x = x0;
    let mut g = vec![0.0; n];
    let mut value = f(&x, &mut g);
    let mut out = LbfgsResult {
        x: Vec::new(),
        value,
        iterations: 0,
        evaluations: 1,
        converged: false,
    };
    let mut memory: VecDeque<(Vec<f64>, Vec<f64>, f64)> = VecDeque::new();
    let (mut dir, mut trial, mut g_trial) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    while out.iterations < config.max_iterations {
        if inf_norm(&g) <= config.gradient_tolerance {
            out.converged = true;
            break;
        }
        direction(&memory, &g, &mut dir);
        let mut slope = dot(&g, &dir);
        if slope >= 0.0 {
            // Not a descent direction (stale curvature): restart from steepest descent.
            memory.clear();
            direction(&memory, &g, &mut dir);
            slope = dot(&g, &dir);
        }
        let mut step = 1.0;
        let mut accepted = None;
        for _ in 0..50 {
            trial
                .iter_mut()
                .zip(&x)
                .zip(&dir)
                .for_each(|((t, x), d)| *t = x + step * d);
            let v = f(&trial, &mut g_trial);
            out.evaluations += 1;
            if v.is_finite() && v <= value + 1e-4 * step * slope {
                accepted = Some(v);
                break;
            }
            step *= 0.5;
        }
        let Some(v) = accepted else {
            out.converged = true;
            break;
        };
        let s: Vec<f64> = trial.iter().zip(&x).map(|(a, b)| a - b).collect();
        let y: Vec<f64> = g_trial.iter().zip(&g).map(|(a, b)| a - b).collect();
        let sy = dot(&s, &y);
        if sy > 1e-12 * dot(&s, &s).sqrt() * dot(&y, &y).sqrt() {
            if memory.len() == config.memory.max(1) {
                memory.pop_front();
            }
            memory.push_back((s, y, 1.0 / sy));
        }
        std::mem::swap(&mut x, &mut trial);
        std::mem::swap(&mut g, &mut g_trial);
        let old = value;
        value = v;
        out.iterations += 1;
        if old - value <= config.relative_tolerance * value.abs().max(1.0) {
            out.converged = true;
            break;
        }
    }
    out.x = x;
    out.value = value;
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Rosenbrock valley, minimum at (1, 1).
    #[test]
    fn minimizes_rosenbrock() {
        let config = LbfgsConfig {
            max_iterations: 500,
            memory: 8,
            gradient_tolerance: 1e-10,
            relative_tolerance: 0.0,
        };
        let r = minimize(
            |x, g| {
                let (a, b) = (1.0 - x[0], x[1] - x[0] * x[0]);
                g[0] = -2.0 * a - 400.0 * x[0] * b;
                g[1] = 200.0 * b;
                a * a + 100.0 * b * b
            },
            vec![-1.2, 1.0],
            &config,
        );
        assert!(r.converged);
        assert!(
            (r.x[0] - 1.0).abs() < 1e-6 && (r.x[1] - 1.0).abs() < 1e-6,
            "{:?}",
            r.x
        );
    }
}
