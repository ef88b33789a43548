//! Solver settings and the report of one optimisation.

use serde::{Deserialize, Serialize};

use super::robust::{Annealing, RobustKernel};
use crate::error::{Result, SlamError, require_positive};

/// The non-linear least-squares method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Method {
    /// Gauss–Newton: every step `H Δ = −b` is taken.
    GaussNewton,
    /// Levenberg–Marquardt: `(H + λI) Δ = −b`, a step is kept only when the robust cost falls,
    /// and λ follows Nielsen's rule (Madsen, Nielsen & Tingleff 2004, "Methods for non-linear
    /// least squares problems", Sec. 3.2).
    LevenbergMarquardt,
}

/// Settings of [`PoseGraph::optimize`](super::PoseGraph::optimize).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SolverConfig {
    /// The method. Default: Levenberg–Marquardt, which is safe far from the optimum (g2o's
    /// default solver for 2-D SLAM, Kümmerle et al. 2011).
    pub method: Method,
    /// Maximum number of iterations (linearisations). Default 20: the annealing schedule
    /// takes at most 17, and the M3500-style graph of the benchmark converges in 11 from the
    /// chained-odometry guess.
    pub max_iterations: usize,
    /// Kernel on [`EdgeKind::Loop`](super::EdgeKind::Loop) edges. Default
    /// `Dcs { phi: 10.0 }`. Dynamic covariance scaling rejects wrong loop closures without
    /// extra variables (Agarwal et al., ICRA 2013, who use Φ = 1). Φ is on the χ² scale of a
    /// 3-dof error: a correct edge's χ² follows χ²(3) (mean 3, 99th percentile 11.3), and DCS
    /// gives full weight only up to χ² = Φ. With Φ = 1 the M3500-style benchmark graph (every
    /// loop correct, information true to the noise) ends with 10 % of its loop closures at
    /// weight < 0.1 and poses up to 0.3 m from the least-squares optimum; with Φ = 10 it
    /// reaches that optimum, and a loop closure 30 cm off at σ = 1 cm (χ² ≈ 900) still gets
    /// scale 0.02 (the tests).
    pub loop_kernel: RobustKernel,
    /// Kernel on [`EdgeKind::Sequential`](super::EdgeKind::Sequential) edges. Default `None`:
    /// odometry / scan-matching chains are trusted, as in Agarwal et al. 2013, where only loop
    /// closures can be outliers.
    pub sequential_kernel: RobustKernel,
    /// Graduated non-convexity of the kernels; `None` applies them at their width from the
    /// first iteration. Default [`Annealing::default`]: without it a correct loop closure
    /// that meets a drifted initial guess (χ² ≫ Φ) is rejected along with the wrong ones.
    pub annealing: Option<Annealing>,
    /// Stop when an iteration lowers the robust cost by less than this fraction of it.
    /// Default 1e-6.
    pub tolerance: f64,
    /// Levenberg–Marquardt's initial damping relative to the largest diagonal entry of `H`
    /// (τ of Madsen, Nielsen & Tingleff 2004, Sec. 3.2, who suggest 1e-6 … 1e-3 from a good
    /// start). Default 1e-5, g2o's value.
    pub lm_tau: f64,
    /// Levenberg–Marquardt's number of damped retries within one iteration before it stops
    /// (no step lowers the cost). Default 10, g2o's figure.
    pub lm_max_retries: usize,
}

impl Default for SolverConfig {
    fn default() -> Self {
        Self {
            method: Method::LevenbergMarquardt,
            max_iterations: 20,
            loop_kernel: RobustKernel::Dcs { phi: 10.0 },
            sequential_kernel: RobustKernel::None,
            annealing: Some(Annealing::default()),
            tolerance: 1e-6,
            lm_tau: 1e-5,
            lm_max_retries: 10,
        }
    }
}

impl SolverConfig {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<()> {
        self.loop_kernel.validate()?;
        self.sequential_kernel.validate()?;
        if let Some(annealing) = &self.annealing {
            annealing.validate()?;
        }
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            return Err(SlamError::InvalidParameter {
                name: "SolverConfig::tolerance",
                reason: format!("must be finite and ≥ 0, got {}", self.tolerance),
            });
        }
        require_positive("SolverConfig::lm_tau", self.lm_tau)
    }
}

/// What one call of [`PoseGraph::optimize`](super::PoseGraph::optimize) did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SolveReport {
    /// Linearisations performed (at most [`SolverConfig::max_iterations`]).
    pub iterations: usize,
    /// `Σ eᵀΩe` over all edges before (plain, without kernels).
    pub initial_chi2: f64,
    /// `Σ eᵀΩe` over all edges after (plain, without kernels).
    pub final_chi2: f64,
    /// The robust cost `Σ ρ(eᵀΩe)` that the solver minimises, before.
    pub initial_cost: f64,
    /// The robust cost after.
    pub final_cost: f64,
    /// True when, with the kernels at their final width, the stopping test on
    /// [`SolverConfig::tolerance`] was met, the last step moved no pose by more than 1e-10 (m,
    /// rad), or no step could lower the cost further; false
    /// when the iteration limit came first.
    pub converged: bool,
    /// Wall-clock time of the call in seconds.
    pub seconds: f64,
}
