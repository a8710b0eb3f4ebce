//! The error type of every loader: which file, where in it, and what was expected.

use std::error::Error;
use std::fmt;
use std::io;
use std::path::{Path, PathBuf};

/// Where in a file an error was found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Location {
    /// The file as a whole (it cannot be read, its name is not understood, …).
    File,
    /// A 1-based line of a text file.
    Line(usize),
    /// A 0-based byte offset in a binary file.
    Byte(u64),
    /// A 0-based byte offset in the data decompressed from a `.gz` file.
    DecompressedByte(u64),
    /// A glTF JSON element (for example `meshes[2].primitives[0].indices`).
    Json(String),
}

/// The broad class of a [`LoadError`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// The file (or a file it refers to) could not be read.
    Io,
    /// The file name does not end in a known mesh extension.
    UnknownFormat,
    /// The contents do not follow the format.
    Malformed,
    /// The contents use a feature this crate does not read.
    Unsupported,
    /// The file is well formed but has no triangles.
    Empty,
}

/// A failure to load a file, naming the file, the location in it and what was
/// expected there.
///
/// Displayed as `path:line: message` for text formats,
/// `path: byte N: message` for binary ones, `path: json.element: message` for
/// glTF and `path: message` when no finer location applies.
#[derive(Debug)]
pub struct LoadError {
    path: PathBuf,
    location: Location,
    kind: ErrorKind,
    message: String,
    source: Option<io::Error>,
}

impl LoadError {
    /// An error of `kind` at `location` in `path`.
    pub fn new(
        path: &Path,
        kind: ErrorKind,
        location: Location,
        message: impl Into<String>,
    ) -> Self {
        LoadError {
            path: path.to_path_buf(),
            location,
            kind,
            message: message.into(),
            source: None,
        }
    }

    /// A malformed-content error at a 1-based line.
    pub fn at_line(path: &Path, line: usize, message: impl Into<String>) -> Self {
        Self::new(path, ErrorKind::Malformed, Location::Line(line), message)
    }

    /// A malformed-content error at a 0-based byte offset.
    pub fn at_byte(path: &Path, byte: u64, message: impl Into<String>) -> Self {
        Self::new(path, ErrorKind::Malformed, Location::Byte(byte), message)
    }

    /// A malformed-content error at a glTF JSON element.
    pub fn at_json(path: &Path, element: impl Into<String>, message: impl Into<String>) -> Self {
        Self::new(
            path,
            ErrorKind::Malformed,
            Location::Json(element.into()),
            message,
        )
    }

    /// An I/O failure while reading `path`; `what` says what was being done.
    pub fn io(path: &Path, what: &str, err: io::Error) -> Self {
        let mut e = Self::new(
            path,
            ErrorKind::Io,
            Location::File,
            format!("{what}: {err}"),
        );
        e.source = Some(err);
        e
    }

    /// The same error with another kind.
    pub fn with_kind(mut self, kind: ErrorKind) -> Self {
        self.kind = kind;
        self
    }

    /// The same error with its byte location marked as counted in decompressed data.
    pub(crate) fn in_decompressed(mut self, path: &Path) -> Self {
        if let Location::Byte(b) = self.location {
            self.location = Location::DecompressedByte(b);
        }
        self.path = path.to_path_buf();
        self
    }

    /// The file the error is about.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Where in the file.
    pub fn location(&self) -> &Location {
        &self.location
    }

    /// The class of the error.
    pub fn kind(&self) -> ErrorKind {
        self.kind
    }

    /// What was wrong, without the file and location.
    pub fn message(&self) -> &str {
        &self.message
    }
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = self.path.display();
        match &self.location {
            Location::File => write!(f, "{p}: {}", self.message),
            Location::Line(l) => write!(f, "{p}:{l}: {}", self.message),
            Location::Byte(b) => write!(f, "{p}: byte {b}: {}", self.message),
            Location::DecompressedByte(b) => {
                write!(f, "{p}: byte {b} (decompressed): {}", self.message)
            }
            Location::Json(e) => write!(f, "{p}: {e}: {}", self.message),
        }
    }
}

impl Error for LoadError {
    fn source(&self) -> Option<&(dyn Error + 'static)> {
        self.source.as_ref().map(|e| e as &(dyn Error + 'static))
    }
}

/// A short, printable rendering of a token for error messages.
pub(crate) fn show(token: Option<&[u8]>) -> String {
    match token {
        None => "end of line".to_string(),
        Some(t) => {
            let s = String::from_utf8_lossy(&t[..t.len().min(40)]);
            let more = if t.len() > 40 { "…" } else { "" };
            format!("'{}{more}'", s.escape_debug())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_names_file_and_location() {
        let p = Path::new("bunny.obj");
        let e = LoadError::at_line(p, 12, "expected 3 numbers after 'v', found 'abc'");
        assert_eq!(
            e.to_string(),
            "bunny.obj:12: expected 3 numbers after 'v', found 'abc'"
        );
        let e = LoadError::at_byte(Path::new("x.ply"), 1234, "file ends");
        assert_eq!(e.to_string(), "x.ply: byte 1234: file ends");
        let e = LoadError::at_json(Path::new("a.glb"), "accessors[3]", "bad");
        assert_eq!(e.to_string(), "a.glb: accessors[3]: bad");
        assert_eq!(e.kind(), ErrorKind::Malformed);
    }

    #[test]
    fn show_quotes_and_truncates() {
        assert_eq!(show(None), "end of line");
        assert_eq!(show(Some(b"abc")), "'abc'");
        assert_eq!(show(Some(&[b'x'; 50])).chars().count(), 43);
    }
}
