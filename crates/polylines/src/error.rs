//! Errors of polyline extraction.

/// Why an extraction could not run. Bad scan values (NaN, infinite or negative ranges) are not
/// errors: such beams are no-returns.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PolylineError {
    /// A configuration parameter is out of its domain.
    #[error("invalid parameter {name}: {reason}")]
    InvalidParameter {
        /// The parameter's field name in [`crate::PolylineConfig`].
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// The scan's beam layout cannot be used (non-finite angles, zero increment).
    #[error("invalid scan: {reason}")]
    InvalidScan {
        /// What is wrong with it.
        reason: String,
    },
    /// The ground-truth polygon of an area metric is unusable.
    #[error("invalid ground-truth polygon: {reason}")]
    InvalidGroundTruth {
        /// What is wrong with it.
        reason: String,
    },
}
