//! Rust errors as Python exceptions: bad input or settings are `ValueError`
//! with the library's one-line message; a file that cannot be read or
//! written is `FileNotFoundError`, `PermissionError` or `OSError` naming it.

use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyPermissionError, PyValueError};
use pyo3::PyErr;

/// A `ballpass` error as the matching Python exception.
pub fn domain(e: ballpass::Error) -> PyErr {
    if let ballpass::Error::Io { source, .. } = &e {
        let msg = e.to_string();
        return match source.kind() {
            std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(msg),
            std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(msg),
            _ => PyOSError::new_err(msg),
        };
    }
    PyValueError::new_err(e.to_string())
}

/// A `ballpass-dsp` error (bad samples or settings) as `ValueError`.
pub fn dsp(e: ballpass_dsp::DspError) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// Any other message as `ValueError`.
pub fn value(msg: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(msg.to_string())
}
