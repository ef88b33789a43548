//! The error type of raypath-registration.

/// Errors of registration and odometry.
#[derive(Debug, thiserror::Error)]
pub enum RegistrationError {
    /// A configuration value is out of its valid range.
    #[error("invalid parameter {name}: {reason}")]
    InvalidParameter {
        /// The parameter's name (the config field).
        name: &'static str,
        /// Why it is invalid.
        reason: String,
    },
    /// A cloud has no point to register (none at all, or none left after the range crop).
    #[error("{what} cloud is empty: {reason}")]
    EmptyCloud {
        /// Which cloud (`source`, `target`, `frame`).
        what: &'static str,
        /// Why (no points, none within the ranges, none with a surface normal).
        reason: String,
    },
    /// An unorganized cloud holds a point with a NaN or infinite coordinate (organized clouds
    /// mark missing pixels that way, and those are skipped).
    #[error("{what} cloud: point {index} has a non-finite coordinate ({x}, {y}, {z})")]
    NonFinitePoint {
        /// Which cloud.
        what: &'static str,
        /// Index of the point in the cloud.
        index: usize,
        /// Its x coordinate.
        x: f32,
        /// Its y coordinate.
        y: f32,
        /// Its z coordinate.
        z: f32,
    },
    /// A cloud is inconsistent (attribute lengths, width × height).
    #[error("{what} cloud: {reason}")]
    InvalidCloud {
        /// Which cloud.
        what: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// A pose (initial guess) has a non-finite component.
    #[error("{what} is not a finite pose")]
    NonFinitePose {
        /// Which pose.
        what: &'static str,
    },
    /// Too few source points found a target point within the correspondence distance: the
    /// clouds do not overlap at the initial guess.
    #[error(
        "only {found} correspondences within {max_distance_m} m at iteration {iteration} \
         (at least {needed} needed): the clouds do not overlap at the initial guess"
    )]
    TooFewCorrespondences {
        /// Correspondences found.
        found: usize,
        /// The configured minimum.
        needed: usize,
        /// Iteration (0 = at the initial guess).
        iteration: usize,
        /// The correspondence gate, metres.
        max_distance_m: f64,
    },
    /// The least-squares system has no finite solution.
    #[error("the point-to-plane system at iteration {iteration} has no finite solution")]
    Degenerate {
        /// Iteration at which it happened.
        iteration: usize,
    },
}

/// Result with [`RegistrationError`].
pub type Result<T> = std::result::Result<T, RegistrationError>;

/// Checks that `value` is finite and positive.
pub(crate) fn require_positive(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(RegistrationError::InvalidParameter {
            name,
            reason: format!("must be finite and positive, got {value}"),
        })
    }
}
