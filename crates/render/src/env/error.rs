//! The error of loading or building an environment map: which file, what went wrong.

use std::error::Error;
use std::fmt;
use std::io;
use std::path::{Path, PathBuf};

/// A failure to load or build an [`EquirectMap`](super::EquirectMap).
///
/// Displayed as `path: message`; maps built in memory use `<memory>` as the path.
#[derive(Debug)]
pub enum EnvError {
    /// The file could not be opened or read.
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: io::Error,
    },
    /// The file name does not end in `.exr` or `.hdr`.
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// The contents could not be decoded (truncated, corrupt, unsupported).
    Decode {
        /// The file.
        path: PathBuf,
        /// What the decoder reported.
        message: String,
    },
    /// The image decoded but cannot be an environment map (no RGB channels,
    /// zero size, texel count not `width × height`, …).
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

impl EnvError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            EnvError::Io { path, .. }
            | EnvError::UnknownFormat { path }
            | EnvError::Decode { path, .. }
            | EnvError::Invalid { path, .. } => path,
        }
    }
}

impl fmt::Display for EnvError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = self.path().display();
        match self {
            EnvError::Io { source, .. } => write!(f, "{p}: cannot read: {source}"),
            EnvError::UnknownFormat { .. } => write!(
                f,
                "{p}: unknown environment map format (expected a .exr or .hdr file)"
            ),
            EnvError::Decode { message, .. } => write!(f, "{p}: cannot decode: {message}"),
            EnvError::Invalid { message, .. } => write!(f, "{p}: {message}"),
        }
    }
}

impl Error for EnvError {
    fn source(&self) -> Option<&(dyn Error + 'static)> {
        match self {
            EnvError::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}
