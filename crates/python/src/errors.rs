//! Python exceptions: every error of the Rust side becomes one, with the file and the place
//! when it has them.

use pyo3::exceptions::{PyException, PyFileNotFoundError, PyValueError};
use pyo3::prelude::*;

pyo3::create_exception!(
    raypath,
    RaypathError,
    PyException,
    "Base class of the errors raypath raises (besides ValueError for bad arguments)."
);
pyo3::create_exception!(
    raypath,
    FormatError,
    RaypathError,
    "A file does not follow its format, ends early or is not a format raypath reads. \
     Attributes: `path` (str), `line` and `byte` (int or None): the place in the file."
);
pyo3::create_exception!(
    raypath,
    InputError,
    RaypathError,
    "Data that the algorithm cannot use (for example a log without laser scans)."
);

/// A `raypath_io` error as a Python exception: `FileNotFoundError` for a missing file,
/// `FormatError` (with `path`, `line`, `byte`) otherwise.
pub fn io_error(error: raypath_io::Error) -> PyErr {
    if let raypath_io::Error::Io { source, .. } = &error
        && source.kind() == std::io::ErrorKind::NotFound
    {
        return PyFileNotFoundError::new_err(error.to_string());
    }
    let (line, byte) = match error.location() {
        raypath_io::Location::Line(l) => (Some(l), None),
        raypath_io::Location::Byte(b) => (None, Some(b)),
        raypath_io::Location::File => (None, None),
    };
    let path = error.path().display().to_string();
    let err = FormatError::new_err(error.to_string());
    Python::with_gil(|py| {
        let value = err.value(py);
        // Setting attributes on a fresh exception instance cannot fail in practice; if it
        // does, the message still names the file and the place.
        let _ = value.setattr("path", path);
        let _ = value.setattr("line", line);
        let _ = value.setattr("byte", byte);
    });
    err
}

/// A file that does not follow its format (no place in it known): `FormatError` with
/// `path`, `line = byte = None`.
pub fn format_error(path: &std::path::Path, message: impl std::fmt::Display) -> PyErr {
    let err = FormatError::new_err(format!("{}: {message}", path.display()));
    Python::with_gil(|py| {
        let value = err.value(py);
        // As in `io_error`: the message names the file when this fails.
        let _ = value.setattr("path", path.display().to_string());
        let _ = value.setattr("line", None::<u64>);
        let _ = value.setattr("byte", None::<u64>);
    });
    err
}

/// An error about data the algorithm cannot use.
pub fn input_error(message: impl std::fmt::Display) -> PyErr {
    InputError::new_err(message.to_string())
}

/// A bad argument: `ValueError` naming it.
pub fn value_error(argument: &str, message: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(format!("{argument}: {message}"))
}

/// Registers the exception classes on the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("RaypathError", py.get_type::<RaypathError>())?;
    m.add("FormatError", py.get_type::<FormatError>())?;
    m.add("InputError", py.get_type::<InputError>())?;
    Ok(())
}
