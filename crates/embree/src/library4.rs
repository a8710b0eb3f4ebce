//! Embree 4 found and loaded at run time ([`Embree4::load`]), so a raykit
//! built anywhere can compare against whichever `libembree4.so.4` the
//! machine has, e.g. the one in the PyPI wheel `embreex`: where it is
//! looked for, the loaded library and its version.

use crate::ffi4 as ffi;
use anyhow::{anyhow, bail, Context, Result};
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

/// Environment variable naming the Embree 4 library file.
pub const LIBRARY_ENV: &str = "RAYKIT_EMBREE4";

/// Environment variable naming the Python whose `embreex` wheel carries
/// the library (else `python3` on the PATH).
pub const PYTHON_ENV: &str = "RAYKIT_PYTHON";

/// The library the process loaded first, returned by every later load.
static LOADED: OnceLock<Arc<Embree4>> = OnceLock::new();

/// A loaded Embree 4 library and its function table.
pub struct Embree4 {
    pub(crate) api: ffi::Api,
    /// The file loaded, for reports.
    pub path: PathBuf,
    /// The library's version, e.g. `4.4.0`.
    pub version: String,
}

impl Embree4 {
    /// Find and load Embree 4: the file `$RAYKIT_EMBREE4` ([`LIBRARY_ENV`])
    /// names, else the `libembree4*.so*` of the `embreex` wheel that
    /// `python3` (the one `$RAYKIT_PYTHON`, [`PYTHON_ENV`], names, else
    /// `python3` on the PATH) imports. The error names every place tried.
    /// Loaded once per process: after a success, every call returns that
    /// library. A library opened here is never closed: the TBB worker
    /// threads Embree 4 starts outlive its devices, and would run unmapped
    /// code once the library was unloaded.
    pub fn load() -> Result<Arc<Embree4>> {
        if let Some(lib) = LOADED.get() {
            return Ok(Arc::clone(lib));
        }
        let lib = Self::open(find_library()?)?;
        // Where two threads opened it at once, the second one's handle is
        // left open and unused.
        Ok(Arc::clone(LOADED.get_or_init(|| lib)))
    }

    /// Load the Embree 4 library at `path` and check its version.
    fn open(path: PathBuf) -> Result<Arc<Embree4>> {
        // SAFETY: loading runs the library's initialisers; Embree's and
        // TBB's have no preconditions.
        let lib = unsafe { libloading::Library::new(&path) }
            .with_context(|| format!("loading Embree 4 from {}", path.display()))?;
        // Never closed (see `load`), so the table below stays valid.
        let lib: &'static libloading::Library = Box::leak(Box::new(lib));
        // SAFETY: the file is an Embree 4 library (its name, and the
        // version check below); `lib` is never closed.
        let api = unsafe { ffi::Api::load(lib) }
            .with_context(|| format!("{}: not an Embree 4 library", path.display()))?;
        // SAFETY: an empty configuration string; the device is released
        // right after reading its version.
        let version = unsafe {
            let dev = (api.calls.rtcNewDevice)(c"".as_ptr());
            if dev.is_null() {
                bail!("{}: Embree could not create a device", path.display());
            }
            let v = (api.rtcGetDeviceProperty)(dev, ffi::RTC_DEVICE_PROPERTY_VERSION);
            (api.calls.rtcReleaseDevice)(dev);
            v
        };
        if !(40000..50000).contains(&version) {
            bail!(
                "{}: reports Embree version {version}, expected 4.x",
                path.display()
            );
        }
        Ok(Arc::new(Embree4 {
            api,
            path,
            version: format!(
                "{}.{}.{}",
                version / 10000,
                version / 100 % 100,
                version % 100
            ),
        }))
    }
}

/// Where [`Embree4::load`] looks, in order.
fn find_library() -> Result<PathBuf> {
    let mut tried = Vec::new();
    if let Some(p) = std::env::var_os(LIBRARY_ENV) {
        let p = PathBuf::from(p);
        if p.is_file() {
            return Ok(p);
        }
        tried.push(format!("${LIBRARY_ENV} = {} (no such file)", p.display()));
    } else {
        tried.push(format!("${LIBRARY_ENV} (not set)"));
    }
    let python = std::env::var(PYTHON_ENV).unwrap_or_else(|_| "python3".to_string());
    let probe = "import embreex, os; print(os.path.join(os.path.dirname(os.path.dirname(embreex.__file__)), 'embreex.libs'))";
    match std::process::Command::new(&python)
        .args(["-c", probe])
        .output()
    {
        Ok(o) if o.status.success() => {
            let dir = PathBuf::from(String::from_utf8_lossy(&o.stdout).trim());
            match library_in(&dir) {
                Some(p) => return Ok(p),
                None => tried.push(format!(
                    "{python}'s embreex wheel: no libembree4*.so* in {}",
                    dir.display()
                )),
            }
        }
        Ok(o) => tried.push(format!(
            "{python} -c 'import embreex': {}",
            String::from_utf8_lossy(&o.stderr)
                .lines()
                .last()
                .unwrap_or("failed")
        )),
        Err(e) => tried.push(format!("{python}: {e}")),
    }
    Err(anyhow!(
        "Embree 4 not found; tried {}. Install it with `pip install embreex` (its wheel carries libembree4) or set {LIBRARY_ENV} to a libembree4.so.4",
        tried.join("; ")
    ))
}

/// The first `libembree4*.so*` file in `dir`.
fn library_in(dir: &Path) -> Option<PathBuf> {
    let mut found: Vec<PathBuf> = std::fs::read_dir(dir)
        .ok()?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("libembree4") && n.contains(".so"))
        })
        .collect();
    found.sort();
    found.into_iter().next()
}
