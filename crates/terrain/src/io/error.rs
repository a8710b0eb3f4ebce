//! The error type of every DEM reader and writer: which file, where in it,
//! and what was expected there.

use std::error::Error;
use std::fmt;
use std::path::{Path, PathBuf};

/// A failure to read or write a DEM file.
///
/// Displayed as `FILE: at AT: MESSAGE`, for example
/// `N57E011.hgt: at byte 2884800: file is 2884800 bytes; …`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DemError {
    /// The file being read or written.
    pub path: PathBuf,
    /// Where in the file: `"byte 1234"`, `"tag 33550"`, `"file name"`,
    /// `"open"`, `"image data"`, …
    pub at: String,
    /// What was found and what was expected.
    pub message: String,
}

impl DemError {
    /// An error in `path` at `at`.
    pub fn new(path: impl AsRef<Path>, at: impl Into<String>, message: impl Into<String>) -> Self {
        DemError {
            path: path.as_ref().to_path_buf(),
            at: at.into(),
            message: message.into(),
        }
    }

    /// An error at byte offset `offset` of `path`.
    pub fn at_byte(path: impl AsRef<Path>, offset: u64, message: impl Into<String>) -> Self {
        Self::new(path, format!("byte {offset}"), message)
    }

    /// The file could not be opened or its size read.
    pub(crate) fn open(path: &Path, err: &std::io::Error) -> Self {
        Self::new(path, "open", format!("cannot open: {err}"))
    }
}

impl fmt::Display for DemError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: at {}: {}",
            self.path.display(),
            self.at,
            self.message
        )
    }
}

impl Error for DemError {}
