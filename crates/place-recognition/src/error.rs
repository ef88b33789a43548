//! The error type of raypath-place-recognition.

/// Errors of description, search and evaluation.
#[derive(Debug, thiserror::Error)]
pub enum PlaceError {
    /// A parameter is out of its valid range.
    #[error("invalid parameter {name}: {reason}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// Why it is invalid.
        reason: String,
    },
    /// A method was handed a kind of frame it cannot describe (for example Scan Context and a
    /// planar scan).
    #[error("{method} cannot describe a {frame} frame")]
    UnsupportedFrame {
        /// The method's name.
        method: &'static str,
        /// The kind of frame (`planar scan`, `point cloud`, `image`).
        frame: &'static str,
    },
    /// Input data cannot be used (non-finite values, mismatched lengths, empty input …).
    #[error("{0}")]
    BadInput(String),
}

/// Result with [`PlaceError`].
pub type Result<T> = std::result::Result<T, PlaceError>;

/// Checks that `value` is finite and positive.
pub(crate) fn require_positive(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(PlaceError::InvalidParameter {
            name,
            reason: format!("must be finite and positive, got {value}"),
        })
    }
}
