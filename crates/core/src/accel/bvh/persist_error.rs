//! Why a saved structure could not be written or read.

use std::fmt;
use std::path::PathBuf;

/// Why a structure could not be saved or loaded.
#[derive(Debug)]
pub enum PersistError {
    /// The file could not be opened, read, written or renamed.
    Io {
        /// The file.
        path: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// The file (or the mesh given with it) is not what it should be.
    Invalid {
        /// The file.
        path: PathBuf,
        /// Byte offset in the file of the field at fault (the file's length
        /// when it ends too early).
        offset: u64,
        /// The field at fault.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// The structure has no saved form (only the wide BVHs have).
    Unsupported {
        /// The file it was to be saved to or loaded from.
        path: PathBuf,
    },
}

impl fmt::Display for PersistError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PersistError::Io { path, source } => write!(f, "{}: {source}", path.display()),
            PersistError::Invalid {
                path,
                offset,
                field,
                reason,
            } => write!(f, "{}: offset {offset} ({field}): {reason}", path.display()),
            PersistError::Unsupported { path } => write!(
                f,
                "{}: this structure has no saved form (bvh4 and bvh8 have)",
                path.display()
            ),
        }
    }
}

impl std::error::Error for PersistError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            PersistError::Io { source, .. } => Some(source),
            PersistError::Invalid { .. } | PersistError::Unsupported { .. } => None,
        }
    }
}
