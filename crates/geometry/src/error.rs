//! The crate's error type.

/// Errors of `raypath-geometry`: invalid parameters given to constructors.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GeometryError {
    /// A grid was given a bad cell size, origin or dimensions.
    #[error("invalid grid: {reason}")]
    InvalidGrid {
        /// What is wrong.
        reason: String,
    },
    /// A point cloud's parts disagree (lengths, organized shape).
    #[error("invalid point cloud: {reason}")]
    InvalidCloud {
        /// What is wrong.
        reason: String,
    },
    /// A scan's parameters are out of range.
    #[error("invalid scan: {reason}")]
    InvalidScan {
        /// What is wrong.
        reason: String,
    },
    /// A range image's parts disagree, or a projection has bad parameters.
    #[error("invalid range image: {reason}")]
    InvalidRangeImage {
        /// What is wrong.
        reason: String,
    },
}
