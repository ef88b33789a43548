//! The crate's one L-BFGS minimizer (Nocedal & Wright 2006, Alg. 7.4/7.5) with a backtracking
//! Armijo line search. It serves the DCT map's fit ([`Solver::Lbfgs`](crate::Solver::Lbfgs),
//! which maximizes the log-likelihood, i.e. minimizes its negative) and the baselines' smooth
//! objectives (the Hilbert map's regularized logistic loss, the GPOM squashing calibration).
//!
//! Only steps that lower `f` are accepted, so the recorded values are non-increasing.

use std::collections::VecDeque;

/// A smooth objective to minimize.
pub(crate) trait Objective {
    /// Whether [`value`](Self::value) is much cheaper than
    /// [`value_gradient`](Self::value_gradient): then line-search trials evaluate the value
    /// alone and the gradient only at the accepted point.
    const CHEAP_VALUE: bool = false;

    /// `f(x)`, writing `∇f(x)` into `grad`.
    fn value_gradient(&mut self, x: &[f64], grad: &mut [f64]) -> f64;

    /// `f(x)` alone (used only when [`CHEAP_VALUE`](Self::CHEAP_VALUE) is set).
    fn value(&mut self, x: &[f64], scratch: &mut [f64]) -> f64 {
        self.value_gradient(x, scratch)
    }
}

impl<F: FnMut(&[f64], &mut [f64]) -> f64> Objective for F {
    fn value_gradient(&mut self, x: &[f64], grad: &mut [f64]) -> f64 {
        self(x, grad)
    }
}

/// Stopping rules, memory and the first step.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LbfgsConfig {
    /// Iteration cap.
    pub max_iterations: usize,
    /// Stored correction pairs.
    pub memory: usize,
    /// Stop when `‖∇f‖_∞` falls to this (0: never on the gradient alone).
    pub gradient_tolerance: f64,
    /// Stop when an iteration lowers `f` by no more than this times `|f|` before it.
    pub relative_tolerance: f64,
    /// The first (steepest-descent) step's length: `None` scales the gradient to unit
    /// `∞`-norm (at most), `Some(r)` moves `x` by `r · max(‖x‖, 10⁻³)` — for objectives whose
    /// natural step is relative to the size of `x`, as the DCT coefficients'.
    pub first_step_relative: Option<f64>,
}

/// The minimizer's result.
#[derive(Clone, Debug)]
pub(crate) struct LbfgsResult {
    /// The last accepted point.
    pub x: Vec<f64>,
    /// `f` at the start and after each accepted iteration (non-increasing).
    pub values: Vec<f64>,
    /// Objective evaluations (value alone or with the gradient).
    pub evaluations: usize,
    /// Whether a tolerance, a zero step or a failed line search (not the iteration cap)
    /// stopped it.
    pub converged: bool,
}

impl LbfgsResult {
    /// `f` at [`x`](Self::x).
    pub fn value(&self) -> f64 {
        self.values.last().copied().unwrap_or(f64::NAN)
    }

    /// Accepted iterations.
    pub fn iterations(&self) -> usize {
        self.values.len().saturating_sub(1)
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn inf_norm(a: &[f64]) -> f64 {
    a.iter().fold(0.0, |m, v| m.max(v.abs()))
}

type Memory = VecDeque<(Vec<f64>, Vec<f64>, f64)>;

/// The quasi-Newton direction `−H ∇f` by the two-loop recursion, written into `q`
/// (Alg. 7.4); `first_gamma` scales the gradient while the memory is empty.
fn direction(memory: &Memory, g: &[f64], first_gamma: f64, q: &mut [f64], alphas: &mut Vec<f64>) {
    q.copy_from_slice(g);
    alphas.clear();
    for (s, y, rho) in memory.iter().rev() {
        let a = rho * dot(s, q);
        q.iter_mut().zip(y).for_each(|(q, y)| *q -= a * y);
        alphas.push(a);
    }
    let gamma = memory
        .back()
        .map_or(first_gamma, |(s, y, _)| dot(s, y) / dot(y, y));
    q.iter_mut().for_each(|q| *q *= gamma);
    for ((s, y, rho), a) in memory.iter().zip(alphas.iter().rev()) {
        let b = rho * dot(y, q);
        q.iter_mut().zip(s).for_each(|(q, s)| *q += (a - b) * s);
    }
    q.iter_mut().for_each(|q| *q = -*q);
}

/// The scale of the first, steepest-descent step.
fn first_gamma(config: &LbfgsConfig, x: &[f64], g: &[f64]) -> f64 {
    match config.first_step_relative {
        None => 1.0 / inf_norm(g).max(1.0),
        Some(r) => r * dot(x, x).sqrt().max(1e-3) / dot(g, g).sqrt().max(1e-300),
    }
}

/// Backtracking from a unit step until the Armijo condition holds with a strict decrease;
/// returns the step's value, if one was found, and the number of trials. The trial point is
/// left in `trial`, and its gradient in `g_trial` unless the objective has a cheap value.
fn line_search<O: Objective>(
    f: &mut O,
    x: &[f64],
    dir: &[f64],
    (value, slope): (f64, f64),
    trial: &mut [f64],
    g_trial: &mut [f64],
) -> (Option<f64>, usize) {
    let mut step = 1.0;
    for trials in 1..=50 {
        trial
            .iter_mut()
            .zip(x)
            .zip(dir)
            .for_each(|((t, x), d)| *t = x + step * d);
        let v = if O::CHEAP_VALUE {
            f.value(trial, g_trial)
        } else {
            f.value_gradient(trial, g_trial)
        };
        if v.is_finite() && v < value && v <= value + 1e-4 * step * slope {
            return (Some(v), trials);
        }
        step *= 0.5;
    }
    (None, 50)
}

/// Minimizes `f` from `x0`. A start where `f` is not finite returns at once with
/// `converged == false` and that value recorded.
pub(crate) fn minimize<O: Objective>(f: &mut O, x0: Vec<f64>, config: &LbfgsConfig) -> LbfgsResult {
    let n = x0.len();
    let mut x = x0;
    let mut g = vec![0.0; n];
    let mut out = LbfgsResult {
        x: Vec::new(),
        values: vec![f.value_gradient(&x, &mut g)],
        evaluations: 1,
        converged: false,
    };
    let mut value = out.values[0];
    let mut memory = Memory::new();
    let (mut dir, mut trial, mut g_trial) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut alphas = Vec::with_capacity(config.memory);
    while value.is_finite() && out.iterations() < config.max_iterations {
        if inf_norm(&g) <= config.gradient_tolerance {
            out.converged = true;
            break;
        }
        let gamma = first_gamma(config, &x, &g);
        direction(&memory, &g, gamma, &mut dir, &mut alphas);
        let mut slope = dot(&g, &dir);
        if slope >= 0.0 {
            // Not a descent direction (stale curvature): restart from steepest descent.
            memory.clear();
            direction(&memory, &g, gamma, &mut dir, &mut alphas);
            slope = dot(&g, &dir);
        }
        let (accepted, trials) = line_search(f, &x, &dir, (value, slope), &mut trial, &mut g_trial);
        out.evaluations += trials;
        let Some(v) = accepted else {
            out.converged = true;
            break;
        };
        if O::CHEAP_VALUE {
            f.value_gradient(&trial, &mut g_trial);
            out.evaluations += 1;
        }
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
        out.values.push(value);
        if old - value <= config.relative_tolerance * old.abs() {
            out.converged = true;
            break;
        }
    }
    out.x = x;
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rosenbrock(x: &[f64], g: &mut [f64]) -> f64 {
        let (a, b) = (1.0 - x[0], x[1] - x[0] * x[0]);
        g[0] = -2.0 * a - 400.0 * x[0] * b;
        g[1] = 200.0 * b;
        a * a + 100.0 * b * b
    }

    fn config(first_step_relative: Option<f64>) -> LbfgsConfig {
        LbfgsConfig {
            max_iterations: 500,
            memory: 8,
            gradient_tolerance: 1e-10,
            relative_tolerance: 0.0,
            first_step_relative,
        }
    }

    /// The Rosenbrock valley, minimum at (1, 1), from either first step.
    #[test]
    fn minimizes_rosenbrock() {
        for first in [None, Some(1e-3)] {
            let r = minimize(&mut rosenbrock, vec![-1.2, 1.0], &config(first));
            assert!(r.converged);
            assert!(
                (r.x[0] - 1.0).abs() < 1e-6 && (r.x[1] - 1.0).abs() < 1e-6,
                "{first:?}: {:?}",
                r.x
            );
            assert!(r.values.windows(2).all(|w| w[1] < w[0]), "{:?}", r.values);
        }
    }

    /// An objective with a cheap value is evaluated with its gradient only at accepted
    /// points, and reaches the same minimum.
    #[test]
    fn cheap_value_trials_reach_the_same_minimum() {
        struct Counted(usize, usize);
        impl Objective for Counted {
            const CHEAP_VALUE: bool = true;
            fn value_gradient(&mut self, x: &[f64], g: &mut [f64]) -> f64 {
                self.0 += 1;
                rosenbrock(x, g)
            }
            fn value(&mut self, x: &[f64], scratch: &mut [f64]) -> f64 {
                self.1 += 1;
                rosenbrock(x, scratch)
            }
        }
        let mut counted = Counted(0, 0);
        let r = minimize(&mut counted, vec![-1.2, 1.0], &config(None));
        assert!((r.x[0] - 1.0).abs() < 1e-6 && (r.x[1] - 1.0).abs() < 1e-6);
        assert_eq!(counted.0, r.iterations() + 1);
        assert_eq!(counted.0 + counted.1, r.evaluations);
    }

    /// A start with an infinite value returns at once, unconverged.
    #[test]
    fn non_finite_start_returns_at_once() {
        let r = minimize(
            &mut |_: &[f64], _: &mut [f64]| f64::INFINITY,
            vec![0.0],
            &config(None),
        );
        assert_eq!(r.iterations(), 0);
        assert!(!r.converged);
    }
}
