//! The error type of the crate.

use std::path::PathBuf;

/// Errors of pole extraction, mapping and localization.
#[derive(Debug, thiserror::Error)]
pub enum PoleError {
    /// A parameter is out of range.
    #[error("invalid parameter {name}: {reason}")]
    InvalidParameter {
        /// The parameter.
        name: &'static str,
        /// Why it is invalid.
        reason: String,
    },
    /// Reading a sequence failed (the error names the file and the place).
    #[error(transparent)]
    Read(#[from] raypath_io::Error),
    /// A sequence lacks what the operation needs.
    #[error("{}: {reason}", path.display())]
    Sequence {
        /// The sequence directory.
        path: PathBuf,
        /// What is missing.
        reason: String,
    },
    /// The localizer failed: a particle-filter step or the trajectory evaluation.
    #[error(transparent)]
    Localizer(#[from] raypath_localizer::LocalizerError),
}

/// The result type of the crate.
pub type Result<T> = std::result::Result<T, PoleError>;

/// Fails with [`PoleError::InvalidParameter`] unless `ok`.
pub(crate) fn require(ok: bool, name: &'static str, reason: impl FnOnce() -> String) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(PoleError::InvalidParameter {
            name,
            reason: reason(),
        })
    }
}
