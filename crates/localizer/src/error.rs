//! The crate's error type.

use thiserror::Error;

/// Everything that can go wrong in the localizer: invalid parameters, bad pose tracks and
/// degenerate filter updates. Nothing in this crate panics on user data.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum LocalizerError {
    /// A configuration value or argument is out of its valid range.
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// Why it is rejected.
        reason: String,
    },
    /// A particle set, track or sample list is empty where at least one element is needed.
    #[error("{what} is empty")]
    Empty {
        /// What is empty.
        what: &'static str,
    },
    /// A value (pose component, time stamp, weight) is NaN or infinite.
    #[error("{what} at index {index} is not finite")]
    NonFinite {
        /// What is not finite.
        what: &'static str,
        /// The index of the offending element.
        index: usize,
    },
    /// Time stamps of a pose track do not increase strictly.
    #[error("{what}: time stamp at index {index} ({stamp_secs} s) does not increase strictly")]
    UnsortedStamps {
        /// Which track.
        what: &'static str,
        /// The index of the first offending stamp.
        index: usize,
        /// Its value in seconds.
        stamp_secs: f64,
    },
    /// A time lies outside the span of a pose track.
    #[error(
        "{what}: time {stamp_secs} s lies outside the track's span [{start_secs}, {end_secs}] s"
    )]
    OutOfSpan {
        /// Which track.
        what: &'static str,
        /// The requested time in seconds.
        stamp_secs: f64,
        /// The first stamp of the track.
        start_secs: f64,
        /// The last stamp of the track.
        end_secs: f64,
    },
    /// A measurement model returned NaN for a particle (−∞ is allowed, NaN never).
    #[error("measurement model returned NaN for particle {particle}")]
    NanLikelihood {
        /// The particle's index.
        particle: usize,
    },
    /// Every particle received log-likelihood −∞: the observation is impossible under all
    /// hypotheses. The weights are left as they were before the update.
    #[error("all {particles} particles have zero likelihood; weights left unchanged")]
    AllParticlesImpossible {
        /// The number of particles.
        particles: usize,
    },
    /// A covariance matrix is not symmetric positive (semi-)definite.
    #[error("covariance `{name}` is not symmetric positive definite")]
    NotPositiveDefinite {
        /// The matrix's name.
        name: &'static str,
    },
}

/// Returns an [`LocalizerError::InvalidParameter`] unless `value` is finite and `> 0`.
pub(crate) fn require_positive(name: &'static str, value: f64) -> Result<(), LocalizerError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(LocalizerError::InvalidParameter {
            name,
            reason: format!("must be finite and > 0, got {value}"),
        })
    }
}

/// Returns an [`LocalizerError::InvalidParameter`] unless `value` is finite and `>= 0`.
pub(crate) fn require_non_negative(name: &'static str, value: f64) -> Result<(), LocalizerError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(LocalizerError::InvalidParameter {
            name,
            reason: format!("must be finite and >= 0, got {value}"),
        })
    }
}

/// Returns an [`LocalizerError::InvalidParameter`] unless `lo < value < hi` (open interval).
pub(crate) fn require_open_interval(
    name: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
) -> Result<(), LocalizerError> {
    if value > lo && value < hi {
        Ok(())
    } else {
        Err(LocalizerError::InvalidParameter {
            name,
            reason: format!("must lie in ({lo}, {hi}), got {value}"),
        })
    }
}
