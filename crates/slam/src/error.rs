//! The error type of raypath-slam.

/// Errors of the SLAM pipeline, its pose graph and its outputs.
#[derive(Debug, thiserror::Error)]
pub enum SlamError {
    /// A parameter is out of its valid range.
    #[error("invalid parameter {name}: {reason}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// Why it is invalid.
        reason: String,
    },
    /// Input data cannot be used (non-finite values, an edge to a missing node, …).
    #[error("{0}")]
    BadInput(String),
    /// The pose-graph solver failed (for example a singular system).
    #[error("pose graph: {0}")]
    Solver(String),
    /// An error of the matcher or its grids.
    #[error(transparent)]
    Reflectivity(#[from] raypath_reflectivity::ReflectivityError),
    /// An error of place recognition.
    #[error(transparent)]
    PlaceRecognition(#[from] raypath_place_recognition::PlaceError),
    /// An error of a reader or writer.
    #[error(transparent)]
    Io(#[from] raypath_io::Error),
}

/// Result with [`SlamError`].
pub type Result<T> = std::result::Result<T, SlamError>;

/// Checks that `value` is finite and positive.
pub(crate) fn require_positive(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SlamError::InvalidParameter {
            name,
            reason: format!("must be finite and positive, got {value}"),
        })
    }
}
