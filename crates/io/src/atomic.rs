//! Atomic file output: write to a temporary file in the destination folder,
//! then rename it over the destination. A failed or interrupted write leaves
//! the destination untouched (old contents or absent) and no temporary file.
//! A destination that is a link has the file it names replaced, and keeps
//! being a link; a file the old one's permissions. A destination that is no
//! regular file (a device such as `/dev/null`, a pipe) is written in place:
//! renaming over it would replace it.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard};

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// The temporary files being written, for [`remove_unfinished_outputs`].
static UNFINISHED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn unfinished() -> MutexGuard<'static, Vec<PathBuf>> {
    UNFINISHED.lock().unwrap_or_else(|e| e.into_inner())
}

/// Remove the temporary files of the writes under way, for a program that is
/// about to end without unwinding (on Ctrl-C, say), and keep the lock on them
/// while it ends, so that no new one is started. The destinations are left
/// as they were. Call it last: the returned guard blocks every later write.
pub fn remove_unfinished_outputs() -> impl Drop {
    remove_unfinished_under(Path::new(""))
}

/// [`remove_unfinished_outputs`] for the temporary files under `folder`
/// only (every one for an empty path).
fn remove_unfinished_under(folder: &Path) -> MutexGuard<'static, Vec<PathBuf>> {
    let mut files = unfinished();
    files.retain(|path| {
        let under = path.starts_with(folder);
        if under {
            let _ = fs::remove_file(path);
        }
        !under
    });
    files
}

/// Deletes the temporary file unless the write was committed.
struct TempGuard {
    path: PathBuf,
    armed: bool,
}

impl TempGuard {
    fn new(path: PathBuf) -> Self {
        unfinished().push(path.clone());
        TempGuard { path, armed: true }
    }
}

impl Drop for TempGuard {
    fn drop(&mut self) {
        let mut files = unfinished();
        if self.armed {
            let _ = fs::remove_file(&self.path);
        }
        if let Some(i) = files.iter().position(|p| *p == self.path) {
            files.swap_remove(i);
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
    match stage(path, write, &io_error)? {
        Some(staged) => staged.commit().map_err(io_error),
        None => Ok(()),
    }
}

/// A file written and synced under a temporary name beside its destination,
/// waiting for [`StagedFile::commit`] to rename it there; dropped
/// uncommitted, it is removed.
struct StagedFile {
    guard: TempGuard,
    target: PathBuf,
}

impl StagedFile {
    fn commit(mut self) -> io::Result<()> {
        fs::rename(&self.guard.path, &self.target)?;
        self.guard.armed = false;
        Ok(())
    }
}

/// Several outputs of one run, written in turn and put in place together:
/// each [`OutputSet::write`] goes to a temporary file beside its
/// destination, and [`OutputSet::commit`] renames them all, in the order
/// written, once every one has been written. A run that fails before the
/// commit (or drops the set) leaves every destination as it was and no
/// temporary file. Destinations that are no regular file (a pipe) are
/// written when their turn comes, as [`write_atomic`] writes them.
#[derive(Default)]
pub struct OutputSet {
    staged: Vec<StagedFile>,
}

impl OutputSet {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Write `path`'s contents into the set (see [`write_atomic`]).
    pub fn write<F>(&mut self, path: &Path, write: F) -> io::Result<()>
    where
        F: FnOnce(&mut dyn Write) -> io::Result<()>,
    {
        let staged = stage(path, |w| write(w).map_err(|e| with_path(e, path)), &|e| {
            with_path(e, path)
        })?;
        self.staged.extend(staged);
        Ok(())
    }

    /// Put every output written in place. A rename that fails (rare: the
    /// files are already written and synced in their folders) leaves the
    /// outputs before it in place and the others as they were.
    pub fn commit(self) -> io::Result<()> {
        for staged in self.staged {
            let target = staged.target.clone();
            staged.commit().map_err(|e| with_path(e, &target))?;
        }
        Ok(())
    }
}

/// Write `path`'s contents to a temporary file beside it, synced, and
/// return it for renaming; a destination that is no regular file is written
/// in place (`None`).
fn stage<E>(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<(), E>,
    io_error: &impl Fn(io::Error) -> E,
) -> Result<Option<StagedFile>, E> {
    // Opened through `path` itself, so that links the kernel resolves
    // (`/dev/stdout` to a pipe) still work.
    let existing = fs::metadata(path).ok();
    if existing
        .as_ref()
        .is_some_and(|m| !m.is_file() && !m.is_dir())
    {
        let file = OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(&io_error)?;
        let mut w = BufWriter::with_capacity(1 << 20, file);
        write(&mut w)?;
        return w.flush().map(|()| None).map_err(io_error);
    }
    let target = resolve_links(path).map_err(io_error)?;
    let path = target.as_path();
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
    // Each name is listed before its file is made, so that a stop between
    // the two cannot leave the file behind; a name already taken is unlisted
    // without touching the file that holds it.
    let (file, guard) = loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let mut tmp_name = std::ffi::OsString::from(".");
        tmp_name.push(name);
        tmp_name.push(format!(".{}.{n}.tmp", std::process::id()));
        let mut guard = TempGuard::new(dir.join(tmp_name));
        match OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&guard.path)
        {
            Ok(f) => break (f, guard),
            Err(e) => {
                guard.armed = false;
                if e.kind() != io::ErrorKind::AlreadyExists {
                    return Err(io_error(e));
                }
            }
        }
    };
    if let Some(m) = existing.filter(|m| m.is_file()) {
        fs::set_permissions(&guard.path, m.permissions()).map_err(&io_error)?;
    }
    let mut w = BufWriter::with_capacity(1 << 20, file);
    write(&mut w)?;
    let file: File = w.into_inner().map_err(|e| io_error(e.into_error()))?;
    file.sync_all().map_err(io_error)?;
    drop(file);
    Ok(Some(StagedFile {
        guard,
        target: path.to_path_buf(),
    }))
}

/// `path` with its links followed: the file a chain of links names, which
/// need not exist yet (a dangling link's target is created). A loop of
/// links is an error.
fn resolve_links(path: &Path) -> io::Result<PathBuf> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let to = fs::read_link(&p)?;
                p = match p.parent() {
                    Some(dir) if to.is_relative() => dir.join(to),
                    _ => to,
                };
            }
            _ => return Ok(p),
        }
    }
    Err(io::Error::new(
        io::ErrorKind::InvalidInput,
        format!("{}: too many levels of links", path.display()),
    ))
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

    /// What a stopped program removes: the temporary file of the write under
    /// way, not the destination's old contents nor a finished output.
    #[test]
    fn unfinished_outputs_are_removed_on_request() {
        let dir = tempfile::tempdir().unwrap();
        let done = dir.path().join("done.bin");
        write_atomic(&done, |w| w.write_all(b"done")).unwrap();
        let p = dir.path().join("p.bin");
        fs::write(&p, b"old").unwrap();
        let r = write_atomic(&p, |w| {
            w.write_all(b"new")?;
            assert_eq!(entries(dir.path()).len(), 3, "the temporary file exists");
            drop(remove_unfinished_under(dir.path()));
            assert_eq!(entries(dir.path()), vec!["done.bin", "p.bin"]);
            Ok(())
        });
        assert!(r.is_err(), "a removed temporary file cannot be renamed");
        assert_eq!(fs::read(&p).unwrap(), b"old");
        assert_eq!(fs::read(&done).unwrap(), b"done");
        assert_eq!(entries(dir.path()), vec!["done.bin", "p.bin"]);
    }

    /// A set whose second output fails leaves the first destination's old
    /// contents and no temporary file; committed, it puts both in place.
    #[test]
    fn an_output_set_puts_nothing_in_place_until_every_output_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.obj"), dir.path().join("b.json"));
        fs::write(&a, b"old a").unwrap();
        let mut set = OutputSet::new();
        set.write(&a, |w| w.write_all(b"new a")).unwrap();
        assert_eq!(fs::read(&a).unwrap(), b"old a", "written before the commit");
        let e = set
            .write(&b, |w| {
                w.write_all(b"partial")?;
                Err(io::Error::other("disk full"))
            })
            .unwrap_err();
        assert!(e.to_string().contains("b.json"), "{e}");
        drop(set);
        assert_eq!(fs::read(&a).unwrap(), b"old a");
        assert_eq!(entries(dir.path()), vec!["a.obj"]);
        let mut set = OutputSet::new();
        set.write(&a, |w| w.write_all(b"new a")).unwrap();
        set.write(&b, |w| w.write_all(b"new b")).unwrap();
        set.commit().unwrap();
        assert_eq!(fs::read(&a).unwrap(), b"new a");
        assert_eq!(fs::read(&b).unwrap(), b"new b");
        assert_eq!(entries(dir.path()), vec!["a.obj", "b.json"]);
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

    /// A link keeps being a link, the file it names gets the contents; a
    /// file keeps its permissions; a pipe is written into, not replaced.
    #[cfg(unix)]
    #[test]
    fn links_permissions_and_pipes_survive() {
        use std::os::unix::fs::{FileTypeExt, PermissionsExt};
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("target.bin");
        fs::write(&target, b"old").unwrap();
        fs::set_permissions(&target, fs::Permissions::from_mode(0o640)).unwrap();
        let link = dir.path().join("link.bin");
        std::os::unix::fs::symlink("target.bin", &link).unwrap();
        write_atomic(&link, |w| w.write_all(b"new")).unwrap();
        assert!(fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(fs::read(&target).unwrap(), b"new");
        let mode = fs::metadata(&target).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o640);
        assert_eq!(entries(dir.path()), vec!["link.bin", "target.bin"]);

        let fifo = dir.path().join("fifo");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(made.success(), "mkfifo failed");
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || fs::read(fifo).unwrap())
        };
        write_atomic(&fifo, |w| w.write_all(b"through the pipe")).unwrap();
        assert_eq!(reader.join().unwrap(), b"through the pipe");
        assert!(fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
        assert_eq!(entries(dir.path()), vec!["fifo", "link.bin", "target.bin"]);
    }

    #[test]
    fn missing_directory_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("no/such/dir/x.bin");
        assert!(write_atomic(&p, |w| w.write_all(b"x")).is_err());
    }
}
