//! Rust errors as Python exceptions, with the command line's messages:
//! a file that cannot be read is an `OSError` (`FileNotFoundError` when it
//! does not exist), content or arguments that are wrong a `ValueError`.

use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyPermissionError, PyValueError};
use pyo3::PyErr;
use raykit_core::accel::PersistError;
use raykit_io::{ErrorKind, LoadError};
use raykit_terrain::io::DemError;
use std::error::Error;
use std::io;
use std::path::Path;

/// The exception for an I/O failure of `kind` with `message`.
fn io_error(kind: io::ErrorKind, message: String) -> PyErr {
    match kind {
        io::ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
        io::ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
        _ => PyOSError::new_err(message),
    }
}

/// A mesh loader's error.
pub fn load_error(e: LoadError) -> PyErr {
    let message = e.to_string();
    match e.kind() {
        ErrorKind::Io => {
            let kind = e
                .source()
                .and_then(|s| s.downcast_ref::<io::Error>())
                .map_or(io::ErrorKind::Other, io::Error::kind);
            io_error(kind, message)
        }
        _ => PyValueError::new_err(message),
    }
}

/// A DEM reader's error. The reader names the step (`open`) where the
/// file could not be read; whether it exists decides the exception.
pub fn dem_error(e: DemError) -> PyErr {
    let message = e.to_string();
    if e.at == "open" {
        let kind = match Path::new(&e.path).try_exists() {
            Ok(false) => io::ErrorKind::NotFound,
            _ => io::ErrorKind::Other,
        };
        io_error(kind, message)
    } else {
        PyValueError::new_err(message)
    }
}

/// A `ValueError` with `message`.
pub fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

/// A saved structure's error: the file could not be read or written
/// (`OSError`), or it is damaged, saved for another mesh, or the
/// structure has no saved form (`ValueError`).
pub fn persist_error(e: PersistError) -> PyErr {
    let message = e.to_string();
    match e {
        PersistError::Io { source, .. } => io_error(source.kind(), message),
        _ => PyValueError::new_err(message),
    }
}
