//! The crate's error type.

/// Errors of `raypath-sim`.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A generator or sensor was given a parameter outside its range.
    #[error("invalid parameter {name}: {reason}")]
    InvalidParameter {
        /// The parameter.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// Scene geometry could not be built (degenerate triangles, empty scene, …).
    #[error("invalid scene: {reason}")]
    InvalidScene {
        /// What is wrong.
        reason: String,
    },
    /// Reading inputs or writing a data set failed.
    #[error(transparent)]
    Io(#[from] raypath_io::Error),
    /// Creating a directory or file failed.
    #[error("{path}: {source}")]
    File {
        /// The path.
        path: std::path::PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
}

/// `Result` with this crate's [`SimError`].
pub type Result<T, E = SimError> = std::result::Result<T, E>;
