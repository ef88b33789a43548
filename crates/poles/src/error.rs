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
    /// A pole-map file is malformed.
    #[error("{}:{line}: {reason}", path.display())]
    Malformed {
        /// The file.
        path: PathBuf,
        /// One-based line number.
        line: u64,
        /// What is wrong.
        reason: String,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
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
