//! Parameters of the extractors, with the thesis defaults.

use serde::Serialize;

use crate::PolylineError;

/// Which extractor [`crate::extract`] runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
pub enum Method {
    /// Visvalingam line simplification of the Algorithm 1 polylines (baseline).
    Vvl,
    /// Iterative end-point fit (Douglas–Peucker style splitting; baseline).
    Ief,
    /// Split-and-merge with least-squares line fits (Pavlidis & Horowitz; baseline).
    Sam,
    /// PLE: maximum-likelihood greedy vertex removal (Algorithm 1).
    #[default]
    Ple,
    /// PLE+: PLE followed by the vertex optimization of Eq. (10.4).
    PlePlus,
}

impl Method {
    /// All methods in the order of the thesis figures.
    pub const ALL: [Method; 5] = [
        Method::Vvl,
        Method::Ief,
        Method::Sam,
        Method::Ple,
        Method::PlePlus,
    ];

    /// The short name used in the thesis (`VVL`, `IEF`, `SAM`, `PLE`, `PLE+`).
    pub fn name(self) -> &'static str {
        match self {
            Method::Vvl => "VVL",
            Method::Ief => "IEF",
            Method::Sam => "SAM",
            Method::Ple => "PLE",
            Method::PlePlus => "PLE+",
        }
    }
}

/// The solver of the PLE+ vertex optimization.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum Optimizer {
    /// Nelder–Mead simplex on polar vertex coordinates, as MATLAB `fminsearch` in the
    /// reference implementation (initial simplex: +5 % per non-zero coordinate).
    NelderMead {
        /// Termination tolerance on the simplex size (`TolX`, thesis 1e-2).
        tol_x: f64,
        /// Termination tolerance on the objective spread (`TolFun`, thesis 1e-2, m²).
        tol_f: f64,
        /// Iteration and evaluation limit per parameter (`200·dim` in MATLAB).
        iterations_per_dim: usize,
    },
    /// Levenberg–Marquardt on the radial residuals with the analytic Jacobian (interior
    /// vertices in Cartesian coordinates, end vertices by their radius along their beam).
    LevenbergMarquardt {
        /// Maximum number of iterations.
        max_iterations: usize,
        /// Stop when a step lowers the squared error by less than this fraction.
        rel_tolerance: f64,
    },
}

impl Optimizer {
    /// Nelder–Mead with the reference implementation's options.
    pub const NELDER_MEAD: Optimizer = Optimizer::NelderMead {
        tol_x: 1e-2,
        tol_f: 1e-2,
        iterations_per_dim: 200,
    };
    /// Levenberg–Marquardt with this crate's defaults.
    pub const LEVENBERG_MARQUARDT: Optimizer = Optimizer::LevenbergMarquardt {
        max_iterations: 50,
        rel_tolerance: 1e-9,
    };

    /// Short name (`nelder-mead`, `levenberg-marquardt`).
    pub fn name(self) -> &'static str {
        match self {
            Optimizer::NelderMead { .. } => "nelder-mead",
            Optimizer::LevenbergMarquardt { .. } => "levenberg-marquardt",
        }
    }
}

impl Default for Optimizer {
    fn default() -> Self {
        Optimizer::LEVENBERG_MARQUARDT
    }
}

/// Parameters of polyline extraction (Schaefer 2020, Algorithm 1 in §10.4.2 and the
/// experiments of §10.5).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PolylineConfig {
    /// The extractor.
    pub method: Method,
    /// `J_max`: the largest number of vertices of the result (thesis grid 10…50; the
    /// reference implementation's default is 10).
    pub max_vertices: usize,
    /// `l_max` in metres: the longest edge between neighbouring endpoints that Algorithm 1
    /// connects (thesis: 1 m throughout; use `f64::INFINITY` to connect all).
    pub max_edge_m: f64,
    /// `d_rm` in metres: the residual charged to a beam that a removed end segment no longer
    /// explains (thesis experiments: 0.5 m).
    pub removed_residual_m: f64,
    /// `Σ` in m²: the constant radial noise variance. It scales every error term alike, so
    /// it does not change the result (kept for the invariance oracle and `max_error_increase`).
    pub radial_variance_m2: f64,
    /// `e_max`: stop removing vertices when the cheapest removal costs more than this
    /// (in units of `d²/Σ`; default ∞ = stop at `J_max` only).
    pub max_error_increase: f64,
    /// IEF/SAM: stop splitting when no point is farther than this from its line, metres
    /// (reference implementation: 0.01 m).
    pub split_threshold_m: f64,
    /// The PLE+ solver.
    pub optimizer: Optimizer,
}

impl Default for PolylineConfig {
    fn default() -> Self {
        Self {
            method: Method::Ple,
            max_vertices: 10,
            max_edge_m: 1.0,
            removed_residual_m: 0.5,
            radial_variance_m2: 1.0,
            max_error_increase: f64::INFINITY,
            split_threshold_m: 0.01,
            optimizer: Optimizer::default(),
        }
    }
}

impl PolylineConfig {
    /// The default configuration for `method` with at most `max_vertices` vertices.
    pub fn new(method: Method, max_vertices: usize) -> Self {
        Self {
            method,
            max_vertices,
            ..Self::default()
        }
    }

    /// Checks every parameter's domain.
    pub fn validate(&self) -> Result<(), PolylineError> {
        let bad = |name: &'static str, reason: String| {
            Err(PolylineError::InvalidParameter { name, reason })
        };
        if self.max_vertices < 2 {
            return bad(
                "max_vertices",
                format!("need at least 2 vertices, got {}", self.max_vertices),
            );
        }
        if self.max_edge_m.is_nan() || self.max_edge_m <= 0.0 {
            return bad(
                "max_edge_m",
                format!("must be positive, got {}", self.max_edge_m),
            );
        }
        if !(self.removed_residual_m.is_finite() && self.removed_residual_m >= 0.0) {
            return bad(
                "removed_residual_m",
                format!("must be finite and ≥ 0, got {}", self.removed_residual_m),
            );
        }
        if !(self.radial_variance_m2.is_finite() && self.radial_variance_m2 > 0.0) {
            return bad(
                "radial_variance_m2",
                format!("must be finite and > 0, got {}", self.radial_variance_m2),
            );
        }
        if self.max_error_increase.is_nan() {
            return bad("max_error_increase", "must not be NaN".into());
        }
        if !(self.split_threshold_m.is_finite() && self.split_threshold_m >= 0.0) {
            return bad(
                "split_threshold_m",
                format!("must be finite and ≥ 0, got {}", self.split_threshold_m),
            );
        }
        match self.optimizer {
            Optimizer::NelderMead {
                tol_x,
                tol_f,
                iterations_per_dim,
            } => {
                if !(tol_x.is_finite() && tol_x > 0.0 && tol_f.is_finite() && tol_f > 0.0) {
                    return bad("optimizer", "Nelder–Mead tolerances must be > 0".into());
                }
                if iterations_per_dim == 0 {
                    return bad("optimizer", "Nelder–Mead needs iterations".into());
                }
            }
            Optimizer::LevenbergMarquardt {
                max_iterations,
                rel_tolerance,
            } => {
                if max_iterations == 0 || !(rel_tolerance.is_finite() && rel_tolerance >= 0.0) {
                    return bad(
                        "optimizer",
                        "Levenberg–Marquardt needs iterations and a finite tolerance ≥ 0".into(),
                    );
                }
            }
        }
        Ok(())
    }
}
