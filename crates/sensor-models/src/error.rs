//! The crate's error type.

/// Errors of `raypath-sensor-models`: bad parameters, mismatched maps, and malformed map
/// files (with the byte offset where reading failed).
#[derive(Debug, thiserror::Error)]
pub enum SensorModelError {
    /// A configuration value or constructor argument is out of range.
    #[error("invalid {name}: {reason}")]
    InvalidParameter {
        /// Which parameter.
        name: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// Two maps that must share a grid do not.
    #[error("grid mismatch: {reason}")]
    GridMismatch {
        /// What differs.
        reason: String,
    },
    /// A binary map file is malformed or truncated.
    #[error("{name}: byte {offset}: {reason}")]
    Format {
        /// The file (or the name given to an in-memory reader).
        name: String,
        /// Byte offset where the problem was found.
        offset: u64,
        /// What is wrong.
        reason: String,
    },
    /// Reading or writing a file failed.
    #[error("{name}: {source}")]
    Io {
        /// The file.
        name: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// Encoding a picture failed.
    #[error("{name}: {reason}")]
    Image {
        /// The file.
        name: String,
        /// What failed.
        reason: String,
    },
}

impl SensorModelError {
    /// An [`SensorModelError::Io`] error for `path`.
    pub(crate) fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        Self::Io {
            name: path.display().to_string(),
            source,
        }
    }
}
