//! The error type of raypath-reflectivity.

/// Errors of calibration, matching and log handling.
#[derive(Debug, thiserror::Error)]
pub enum ReflectivityError {
    /// A parameter is out of its valid range.
    #[error("invalid parameter {name}: {reason}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// Why it is invalid.
        reason: String,
    },
    /// Input data cannot be used (too few samples, non-finite values, …).
    #[error("{0}")]
    BadInput(String),
    /// An error of the log reader.
    #[error(transparent)]
    Io(#[from] raypath_io::Error),
}

/// Result with [`ReflectivityError`].
pub type Result<T> = std::result::Result<T, ReflectivityError>;

/// Checks that `value` is finite and positive.
pub(crate) fn require_positive(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ReflectivityError::InvalidParameter {
            name,
            reason: format!("must be finite and positive, got {value}"),
        })
    }
}
