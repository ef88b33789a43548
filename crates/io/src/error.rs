//! The crate's error type: every error names the file and the place in it.

use std::fmt;
use std::path::PathBuf;

/// Where in a file an error was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// The file as a whole (it could not be opened, or a whole-file check failed).
    File,
    /// A 1-based line number of a text file (after decompression).
    Line(u64),
    /// A 0-based byte offset of a binary file (after decompression).
    Byte(u64),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::File => Ok(()),
            Location::Line(line) => write!(f, ":{line}"),
            Location::Byte(offset) => write!(f, ": byte {offset}"),
        }
    }
}

/// Errors of `raypath-io`.
///
/// Displayed as `path:line: reason` or `path: byte N: reason`, so a user can open the file at
/// the place that is wrong.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The operating system could not open or read the file.
    #[error("{}{location}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Where reading failed.
        location: Location,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The content does not follow the format.
    #[error("{}{location}: {reason}", path.display())]
    Malformed {
        /// The file.
        path: PathBuf,
        /// Where the problem is.
        location: Location,
        /// What is wrong, in words.
        reason: String,
    },
    /// The file ends before a record is complete.
    #[error("{}{location}: unexpected end of file while reading {what}", path.display())]
    Truncated {
        /// The file.
        path: PathBuf,
        /// Where the incomplete record starts.
        location: Location,
        /// The record or field that was being read.
        what: String,
    },
    /// The format could not be recognized, or is not the one the caller asked for.
    #[error("{}: {reason}", path.display())]
    UnknownFormat {
        /// The file or directory.
        path: PathBuf,
        /// Why it was not recognized, and what is supported.
        reason: String,
    },
    /// A writer was given data it cannot represent.
    #[error("{}: cannot write: {reason}", path.display())]
    Unwritable {
        /// The destination.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}

impl Error {
    /// A [`Error::Malformed`] error.
    pub fn malformed(
        path: impl Into<PathBuf>,
        location: Location,
        reason: impl Into<String>,
    ) -> Self {
        Error::Malformed {
            path: path.into(),
            location,
            reason: reason.into(),
        }
    }

    /// A [`Error::Truncated`] error.
    pub fn truncated(
        path: impl Into<PathBuf>,
        location: Location,
        what: impl Into<String>,
    ) -> Self {
        Error::Truncated {
            path: path.into(),
            location,
            what: what.into(),
        }
    }

    /// An [`Error::Io`] error.
    pub fn io(path: impl Into<PathBuf>, location: Location, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            location,
            source,
        }
    }

    /// The file the error is about.
    pub fn path(&self) -> &std::path::Path {
        match self {
            Error::Io { path, .. }
            | Error::Malformed { path, .. }
            | Error::Truncated { path, .. }
            | Error::UnknownFormat { path, .. }
            | Error::Unwritable { path, .. } => path,
        }
    }

    /// Where in the file, if known.
    pub fn location(&self) -> Location {
        match self {
            Error::Io { location, .. }
            | Error::Malformed { location, .. }
            | Error::Truncated { location, .. } => *location,
            Error::UnknownFormat { .. } | Error::Unwritable { .. } => Location::File,
        }
    }
}

/// `Result` with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
