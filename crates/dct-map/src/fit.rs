//! Maximum-likelihood fit of the coefficients (Sec. 9.4.4): trust-region Newton with the
//! analytic Hessian (dense Cholesky by `faer`) or L-BFGS with the analytic gradient.
//!
//! Both stop when the relative change of the log-likelihood between two accepted iterates
//! falls below [`FitConfig::relative_tolerance`] (`1e-3`, Sec. 9.5.3) and both only accept
//! steps that increase the log-likelihood, so its history is monotone. "Log-likelihood"
//! here is the [`FitProblem`]'s objective: the rays' log-likelihood plus the log-prior
//! ([`FitProblem::log_prior`]; the MAP rather than the plain ML map, see the crate docs).

use std::time::Instant;

use faer::linalg::solvers::Solve;
use faer::{Mat, Side};
use serde::{Deserialize, Serialize};

use crate::lbfgs::{LbfgsConfig, Objective, minimize};
use crate::{DctError, DctMap, FitProblem};

/// The optimizer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Solver {
    /// Levenberg–Marquardt-style trust-region Newton on the exact Hessian.
    TrustRegionNewton,
    /// Limited-memory BFGS with an Armijo backtracking line search.
    Lbfgs,
}

/// Fit settings. Defaults: trust-region Newton (measured faster, see the crate docs),
/// relative tolerance `1e-3` (thesis Sec. 9.5.3), at most 200 iterations, L-BFGS memory 10.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FitConfig {
    /// The optimizer.
    pub solver: Solver,
    /// Stop when `|ΔLL| / |LL| <` this between accepted iterates (thesis: `1e-3`).
    pub relative_tolerance: f64,
    /// Iteration cap.
    pub max_iterations: usize,
    /// L-BFGS memory.
    pub lbfgs_memory: usize,
}

impl Default for FitConfig {
    fn default() -> Self {
        Self {
            solver: Solver::TrustRegionNewton,
            relative_tolerance: 1e-3,
            max_iterations: 200,
            lbfgs_memory: 10,
        }
    }
}

/// What a fit did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FitReport {
    /// Accepted iterations.
    pub iterations: usize,
    /// The objective — log-likelihood of the rays plus the log-prior
    /// ([`FitProblem::log_prior`]) — at the start and after each accepted iteration
    /// (non-decreasing).
    pub log_likelihoods: Vec<f64>,
    /// Log-likelihood evaluations (incl. rejected trials).
    pub evaluations: usize,
    /// Whether the tolerance was met (otherwise the iteration cap or a stall stopped it).
    pub converged: bool,
    /// Wall time of the optimization in seconds (without pre-processing).
    pub seconds: f64,
}

impl FitReport {
    /// The final objective (log-likelihood plus log-prior, see
    /// [`log_likelihoods`](Self::log_likelihoods)).
    pub fn log_likelihood(&self) -> f64 {
        self.log_likelihoods
            .last()
            .copied()
            .unwrap_or(f64::NEG_INFINITY)
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}

fn relative_change(old: f64, new: f64) -> f64 {
    (new - old).abs() / old.abs().max(1e-300)
}

/// Fits the coefficients starting from `init` (never all zero: `𝒜 = 0` is a saddle with a
/// zero gradient). Fails when `init` has the wrong length or zero likelihood.
pub fn fit(
    problem: &FitProblem,
    init: &[f64],
    config: &FitConfig,
) -> Result<(DctMap, FitReport), DctError> {
    if init.len() != problem.shape().len() {
        return Err(DctError::InvalidParameter {
            name: "init",
            reason: format!(
                "{} values for {} coefficients",
                init.len(),
                problem.shape().len()
            ),
        });
    }
    if init.iter().all(|a| *a == 0.0) {
        return Err(DctError::InvalidParameter {
            name: "init",
            reason: "all-zero coefficients are a saddle of the likelihood".into(),
        });
    }
    let start = Instant::now();
    let (a, mut report) = match config.solver {
        Solver::TrustRegionNewton => newton(problem, init, config)?,
        Solver::Lbfgs => lbfgs(problem, init, config)?,
    };
    report.seconds = start.elapsed().as_secs_f64();
    Ok((DctMap::new(problem.extent_m(), problem.shape(), a)?, report))
}

fn check_start(ll: f64) -> Result<(), DctError> {
    if ll.is_finite() {
        Ok(())
    } else {
        Err(DctError::NoData(
            "the initial map gives a ray zero probability (λ = 0 at a hit)".into(),
        ))
    }
}

fn newton(
    p: &FitProblem,
    init: &[f64],
    config: &FitConfig,
) -> Result<(Vec<f64>, FitReport), DctError> {
    let n = init.len();
    let mut a = init.to_vec();
    let mut eval = p.evaluate(&a);
    check_start(eval.log_likelihood)?;
    let mut report = FitReport {
        iterations: 0,
        log_likelihoods: vec![eval.log_likelihood],
        evaluations: 1,
        converged: false,
        seconds: 0.0,
    };
    let mut mu = f64::NAN;
    'outer: while report.iterations < config.max_iterations {
        let h = p.negative_hessian(&a, &eval.amplitudes);
        let diag: Vec<f64> = (0..n).map(|i| h[i * n + i].abs()).collect();
        let dmax = diag.iter().copied().fold(0.0, f64::max).max(1e-300);
        if mu.is_nan() {
            mu = 1e-9;
        }
        // Gradient of f = −LL.
        let gf: Vec<f64> = eval.gradient.iter().map(|g| -g).collect();
        for _ in 0..30 {
            let m = Mat::<f64>::from_fn(n, n, |i, j| {
                let v = h[i * n + j];
                if i == j {
                    v + mu * (diag[i] + 1e-9 * dmax)
                } else {
                    v
                }
            });
            let Ok(llt) = m.llt(Side::Lower) else {
                mu *= 8.0;
                continue;
            };
            let mut rhs = Mat::<f64>::from_fn(n, 1, |i, _| -gf[i]);
            llt.solve_in_place(rhs.as_mut());
            let step: Vec<f64> = (0..n).map(|i| rhs[(i, 0)]).collect();
            let hs: Vec<f64> = h.chunks_exact(n).map(|row| dot(row, &step)).collect();
            let predicted = -(dot(&gf, &step) + 0.5 * dot(&step, &hs));
            let trial: Vec<f64> = a.iter().zip(&step).map(|(a, s)| a + s).collect();
            let ll = p.log_likelihood(&trial);
            report.evaluations += 1;
            let actual = ll - eval.log_likelihood;
            let rho = actual / predicted.max(1e-300);
            if ll.is_finite() && actual > 0.0 && rho > 1e-4 {
                mu *= if rho > 0.75 {
                    0.1
                } else if rho < 0.25 {
                    2.0
                } else {
                    1.0
                };
                mu = mu.max(1e-15);
                let old = eval.log_likelihood;
                // The barrier terms ln g_k² curve away faster than the quadratic model: when
                // the model was accurate, try longer steps along the same direction.
                let (mut trial, mut ll) = (trial, ll);
                if rho > 0.9 {
                    let mut scale = 1.0;
                    while scale < 16.0 {
                        scale *= 2.0;
                        let longer: Vec<f64> =
                            a.iter().zip(&step).map(|(a, s)| a + scale * s).collect();
                        let l2 = p.log_likelihood(&longer);
                        report.evaluations += 1;
                        if !(l2.is_finite() && l2 > ll) {
                            break;
                        }
                        (trial, ll) = (longer, l2);
                    }
                }
                a = trial;
                eval = p.evaluate(&a);
                report.evaluations += 1;
                report.iterations += 1;
                report.log_likelihoods.push(eval.log_likelihood);
                if relative_change(old, eval.log_likelihood) < config.relative_tolerance {
                    report.converged = true;
                    break 'outer;
                }
                continue 'outer;
            }
            mu *= 4.0;
        }
        // No acceptable step: a (numerical) stationary point.
        report.converged = true;
        break;
    }
    Ok((a, report))
}

/// `−LL` of a [`FitProblem`] for the crate's L-BFGS minimizer: trials evaluate the
/// log-likelihood alone, the gradient only at accepted points.
struct NegativeLogLikelihood<'a>(&'a FitProblem);

impl Objective for NegativeLogLikelihood<'_> {
    const CHEAP_VALUE: bool = true;

    fn value_gradient(&mut self, a: &[f64], grad: &mut [f64]) -> f64 {
        let eval = self.0.evaluate(a);
        grad.iter_mut()
            .zip(&eval.gradient)
            .for_each(|(g, e)| *g = -e);
        -eval.log_likelihood
    }

    fn value(&mut self, a: &[f64], _scratch: &mut [f64]) -> f64 {
        -self.0.log_likelihood(a)
    }
}

fn lbfgs(
    p: &FitProblem,
    init: &[f64],
    config: &FitConfig,
) -> Result<(Vec<f64>, FitReport), DctError> {
    let settings = LbfgsConfig {
        max_iterations: config.max_iterations,
        memory: config.lbfgs_memory,
        gradient_tolerance: 0.0,
        relative_tolerance: config.relative_tolerance,
        // The first step moves the coefficients by 0.1 % of their norm.
        first_step_relative: Some(1e-3),
    };
    let result = minimize(&mut NegativeLogLikelihood(p), init.to_vec(), &settings);
    check_start(-result.values[0])?;
    let report = FitReport {
        iterations: result.iterations(),
        log_likelihoods: result.values.iter().map(|v| -v).collect(),
        evaluations: result.evaluations,
        converged: result.converged,
        seconds: 0.0,
    };
    Ok((result.x, report))
}
