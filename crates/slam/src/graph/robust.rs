//! Robust kernels for iteratively reweighted least squares.
//!
//! Each kernel is a function `ρ(χ²)` of an edge's squared Mahalanobis error `χ² = eᵀΩe`. The
//! solver minimises `Σ ρ(χ²)` by iteratively reweighted least squares: at each linearisation
//! the information matrix of an edge is multiplied by `ρ'(χ²)` evaluated at the current poses
//! (the gradient of `ρ(χ²)` is `ρ'(χ²) · 2JᵀΩe`, so the weighted normal equations have the
//! robust cost's gradient; Kümmerle et al. 2011, g2o, use the same first-order scheme).
//! The *scale* reported by [`PoseGraph::edge_weight`](super::PoseGraph::edge_weight) is
//! `s = √ρ'(χ²)`: the factor on the whitened error, so that the information is scaled by `s²`
//! as in Agarwal et al. 2013.

use serde::{Deserialize, Serialize};

use crate::error::{Result, SlamError, require_positive};

/// A robust kernel `ρ(χ²)` on an edge's squared Mahalanobis error.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum RobustKernel {
    /// Plain least squares: `ρ(χ²) = χ²`.
    None,
    /// Huber: quadratic up to a whitened error of `delta` (√χ² units), linear beyond:
    /// `ρ = χ²` for `χ² ≤ δ²`, `2δ√χ² − δ²` otherwise.
    Huber {
        /// Threshold on `√χ²` (dimensionless, a number of standard deviations).
        delta: f64,
    },
    /// Cauchy (Lorentzian): `ρ = c² · ln(1 + χ²/c²)`, weight `1 / (1 + χ²/c²)`.
    Cauchy {
        /// Scale on `√χ²` (dimensionless).
        c: f64,
    },
    /// Dynamic covariance scaling (Agarwal et al., ICRA 2013): the information is scaled by
    /// `s²` with `s = min(1, 2Φ/(Φ + χ²))`, the closed form of their
    /// switch variable at its optimum.
    Dcs {
        /// Φ, on the scale of χ² (dimensionless).
        phi: f64,
    },
}

impl RobustKernel {
    /// Checks that the kernel's parameter is finite and positive.
    pub fn validate(&self) -> Result<()> {
        match *self {
            Self::None => Ok(()),
            Self::Huber { delta } => require_positive("RobustKernel::Huber::delta", delta),
            Self::Cauchy { c } => require_positive("RobustKernel::Cauchy::c", c),
            Self::Dcs { phi } => require_positive("RobustKernel::Dcs::phi", phi),
        }
    }

    /// The kernel's width on the χ² scale: Φ for DCS, `c²` for Cauchy, `δ²` for Huber;
    /// `None` for plain least squares.
    pub fn chi2_scale(&self) -> Option<f64> {
        match *self {
            Self::None => None,
            Self::Huber { delta } => Some(delta * delta),
            Self::Cauchy { c } => Some(c * c),
            Self::Dcs { phi } => Some(phi),
        }
    }

    /// The kernel made `mu` times wider on the χ² scale (`mu ≥ 1`), the surrogate of
    /// graduated non-convexity: `weight_mu(χ²) = weight(χ²/mu)`.
    pub fn widened(&self, mu: f64) -> Self {
        match *self {
            Self::None => Self::None,
            Self::Huber { delta } => Self::Huber {
                delta: delta * mu.sqrt(),
            },
            Self::Cauchy { c } => Self::Cauchy { c: c * mu.sqrt() },
            Self::Dcs { phi } => Self::Dcs { phi: phi * mu },
        }
    }

    /// The IRLS weight `ρ'(χ²)` that multiplies the information matrix (1 = full trust).
    #[inline]
    pub fn weight(&self, chi2: f64) -> f64 {
        match *self {
            Self::None => 1.0,
            Self::Huber { delta } => {
                if chi2 <= delta * delta {
                    1.0
                } else {
                    delta / chi2.sqrt()
                }
            }
            Self::Cauchy { c } => 1.0 / (1.0 + chi2 / (c * c)),
            Self::Dcs { phi } => {
                let s = (2.0 * phi / (phi + chi2)).min(1.0); // s of Agarwal et al. 2013
                s * s
            }
        }
    }

    /// The robust cost `ρ(χ²)`, whose derivative is [`weight`](Self::weight).
    ///
    /// For DCS the cost is the integral of `s²`: `χ²` up to `χ² = Φ` and
    /// `3Φ − 4Φ²/(Φ + χ²)` beyond (continuous with continuous derivative at `Φ`, bounded by
    /// `3Φ`), so that the solver's step acceptance tests the function whose IRLS weights are
    /// DCS's `s²`.
    #[inline]
    pub fn cost(&self, chi2: f64) -> f64 {
        match *self {
            Self::None => chi2,
            Self::Huber { delta } => {
                if chi2 <= delta * delta {
                    chi2
                } else {
                    2.0 * delta * chi2.sqrt() - delta * delta
                }
            }
            Self::Cauchy { c } => c * c * (chi2 / (c * c)).ln_1p(),
            Self::Dcs { phi } => {
                if chi2 <= phi {
                    chi2
                } else {
                    3.0 * phi - 4.0 * phi * phi / (phi + chi2)
                }
            }
        }
    }
}

/// Graduated non-convexity of the robust kernels (Yang et al. 2020, "Graduated non-convexity
/// for robust spatial perception", RA-L; Agarwal et al. 2014 analyse DCS under bad initial
/// guesses): a bounded kernel such as DCS gives an edge whose error is far beyond its width
/// almost no weight, so a *correct* loop closure that meets a drifted initial guess would be
/// ignored as well as a wrong one. Optimisation therefore starts with every kernel widened by
/// `μ₀` on the χ² scale, `μ₀` the largest `χ²/width` among the edges with a kernel (at most
/// [`max_start`](Self::max_start)), so that those edges start in the quadratic region; `μ`
/// is divided by [`factor`](Self::factor) after every iteration down to 1, and convergence is
/// tested only from then on. Consistent edges pull the poses together while `μ` falls; an
/// edge that stays inconsistent with the rest ends up far beyond the final width.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Annealing {
    /// Upper bound of `μ₀`. Edges with `χ² > max_start · width` at the start are already
    /// down-weighted in the first iteration. Default 1e5 (ours; an error of ≈ 300 widths in
    /// √χ²: about 9 m for a loop edge of σ = 5 cm under DCS with Φ = 10), which bounds the
    /// schedule to 17 iterations with the default factor. The first loops that close a long
    /// excursion meet a guess metres off (the raw MIT Killian Court log's, in
    /// `docs/results/slam.md`); with a bound of 1e3 they started down-weighted, never pulled,
    /// and were rejected at the end, leaving the map doubled.
    pub max_start: f64,
    /// Division of `μ` per iteration (> 1). Default 2: on the M3500-style graph of the
    /// benchmark (from the chained-odometry guess) it reaches the same optimum as the 1.4 of
    /// Yang et al. 2020 in half the iterations (11 against 22), because the problem is
    /// re-linearised at every width.
    pub factor: f64,
}

impl Default for Annealing {
    fn default() -> Self {
        Self {
            max_start: 1e5,
            factor: 2.0,
        }
    }
}

impl Annealing {
    /// Checks both parameters.
    pub fn validate(&self) -> Result<()> {
        require_positive("Annealing::max_start", self.max_start)?;
        if !(self.factor.is_finite() && self.factor > 1.0) {
            return Err(SlamError::InvalidParameter {
                name: "Annealing::factor",
                reason: format!("must be finite and > 1, got {}", self.factor),
            });
        }
        Ok(())
    }
}
