//! Atomic file output: write to a temporary file in the destination folder,
//! then rename it over the destination. A failed or interrupted write leaves
//! the destination untouched (old contents or absent) and no temporary file.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// Deletes the temporary file unless the write was committed.
struct TempGuard {
    path: PathBuf,
    armed: bool,
}

impl Drop for TempGuard {
    fn drop(&mut self) {
        if self.armed {
            let _ = fs::remove_file(&self.path);
        }
    }
}

/// Write `path` atomically: `write` gets a buffered writer to a temporary file
/// next to `path`; when it returns `Ok` the data is flushed, synced and renamed
/// to `path`. On any error (or a panic in `write`) the temporary file is
/// removed and `path` is left as it was.
pub fn write_atomic<F>(path: &Path, write: F) -> io::Result<()>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    write_atomic_file(
        path,
        |w| write(w).map_err(|e| with_path(e, path)),
        |e| with_path(e, path),
    )
}

/// [`write_atomic`] for writers that must also seek (TIFF encoders, say):
/// `write` gets the buffered temporary file itself and may fail with its own
/// error type `E`; the I/O errors of opening, syncing and renaming are turned
/// into `E` by `io_error`.
pub fn write_atomic_file<E>(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<(), E>,
    io_error: impl Fn(io::Error) -> E,
) -> Result<(), E> {
    let name = path.file_name().ok_or_else(|| {
        io_error(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{}: not a file path", path.display()),
        ))
    })?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let (file, tmp) = loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let mut tmp_name = std::ffi::OsString::from(".");
        tmp_name.push(name);
        tmp_name.push(format!(".{}.{n}.tmp", std::process::id()));
        let tmp = dir.join(tmp_name);
        match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => break (f, tmp),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(io_error(e)),
        }
    };
    let mut guard = TempGuard {
        path: tmp,
        armed: true,
    };
    let mut w = BufWriter::with_capacity(1 << 20, file);
    write(&mut w)?;
    let file: File = w.into_inner().map_err(|e| io_error(e.into_error()))?;
    file.sync_all().map_err(&io_error)?;
    drop(file);
    fs::rename(&guard.path, path).map_err(&io_error)?;
    guard.armed = false;
    Ok(())
}

fn with_path(e: io::Error, path: &Path) -> io::Error {
    io::Error::new(e.kind(), format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn success_replaces_failure_keeps_old_contents() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.bin");
        write_atomic(&p, |w| w.write_all(b"first")).unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"first");
        let e = write_atomic(&p, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("boom"))
        })
        .unwrap_err();
        assert!(e.to_string().contains("out.bin") && e.to_string().contains("boom"));
        assert_eq!(fs::read(&p).unwrap(), b"first");
        assert_eq!(entries(dir.path()), vec!["out.bin"]);
        let q = dir.path().join("never.bin");
        let _ = write_atomic(&q, |_| Err(io::Error::other("x")));
        assert!(!q.exists());
        assert_eq!(entries(dir.path()), vec!["out.bin"]);
    }

    #[test]
    fn panic_in_writer_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("p.bin");
        let r = std::panic::catch_unwind(|| {
            let _ = write_atomic(&p, |w| {
                w.write_all(b"x")?;
                panic!("writer panicked");
            });
        });
        assert!(r.is_err());
        assert!(entries(dir.path()).is_empty());
    }

    #[test]
    fn missing_directory_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("no/such/dir/x.bin");
        assert!(write_atomic(&p, |w| w.write_all(b"x")).is_err());
    }
}
