//! Atomic file output: write a temporary file in the destination folder,
//! then rename it over the destination, so a failed write leaves the
//! destination as it was and no temporary file behind.

use std::fs::{self, File, OpenOptions};
use std::io::{BufWriter, ErrorKind};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::DemError;

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

/// Writes `path` atomically: `write` gets a buffered writer on a temporary
/// file `.NAME.PID.N.tmp` next to `path`; when it returns `Ok` the file is
/// flushed, synced and renamed to `path`. On error the temporary file is
/// removed. (Overwriting an input is the caller's concern.)
pub fn write_atomic<F>(path: &Path, write: F) -> Result<(), DemError>
where
    F: FnOnce(&mut BufWriter<File>) -> Result<(), DemError>,
{
    let fail = |e: std::io::Error| DemError::new(path, "write", e.to_string());
    let name = path
        .file_name()
        .ok_or_else(|| DemError::new(path, "file name", "not a file path"))?;
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
            Err(e) if e.kind() == ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(fail(e)),
        }
    };
    let mut guard = TempGuard {
        path: tmp,
        armed: true,
    };
    let mut w = BufWriter::with_capacity(1 << 20, file);
    write(&mut w)?;
    let file = w.into_inner().map_err(|e| fail(e.into_error()))?;
    file.sync_all().map_err(fail)?;
    drop(file);
    fs::rename(&guard.path, path).map_err(fail)?;
    guard.armed = false;
    Ok(())
}
