//! Errors of plane extraction and evaluation.

/// Why an extraction or evaluation was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlaneError {
    /// The cloud is not organized (`width × height` must equal the number of points, both > 0).
    #[error("the point cloud is not organized: width {width} × height {height} != {len} points")]
    NotOrganized {
        /// Cloud width (second grid index).
        width: usize,
        /// Cloud height (first grid index).
        height: usize,
        /// Number of points.
        len: usize,
    },
    /// A parameter is out of its domain.
    #[error("invalid parameter {name}: {reason}")]
    Parameter {
        /// Parameter name.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// Two label vectors that must describe the same cloud differ in length.
    #[error(
        "label length mismatch: ground truth has {ground_truth} entries, segmentation {segmentation}"
    )]
    LengthMismatch {
        /// Number of ground-truth labels.
        ground_truth: usize,
        /// Number of segmentation labels.
        segmentation: usize,
    },
}

impl PlaneError {
    /// `Ok` when `width × height` equals `len` and both are positive (an organized grid),
    /// else [`PlaneError::NotOrganized`].
    pub(crate) fn check_organized(width: usize, height: usize, len: usize) -> Result<(), Self> {
        if width == 0 || height == 0 || width.checked_mul(height) != Some(len) {
            return Err(Self::NotOrganized { width, height, len });
        }
        Ok(())
    }
}
