//! Errors of DCT map construction, fitting and export.

use std::path::PathBuf;

/// What can go wrong when building, fitting or writing a DCT map.
#[derive(Debug, thiserror::Error)]
pub enum DctError {
    /// A parameter is out of its valid range (named, with the reason).
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter {
        /// The parameter.
        name: &'static str,
        /// Why it is invalid.
        reason: String,
    },
    /// The fit has no rays to work with, or its data are degenerate.
    #[error("no data: {0}")]
    NoData(String),
    /// Writing an output file failed.
    #[error("{path}: {reason}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What failed.
        reason: String,
    },
}

/// Checks that a float is finite and positive.
pub(crate) fn positive(name: &'static str, value: f64) -> Result<f64, DctError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(DctError::InvalidParameter {
            name,
            reason: format!("must be positive and finite, got {value}"),
        })
    }
}
