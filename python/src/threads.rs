//! Where the work runs: off the GIL, on all cores or on a pool of the
//! size the caller asked for.
//!
//! `threads = 0` uses rayon's global pool (one thread per core). Any other
//! size gets its own pool, made once per size and kept, so that a call
//! with `threads=1` costs no thread start-up.

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use rayon::{ThreadPool, ThreadPoolBuilder};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// Largest `threads` accepted: far above any core count, low enough that
/// a typo does not start a million threads.
const MAX_THREADS: i64 = 4096;

/// The pools made so far, by size.
fn pools() -> &'static Mutex<HashMap<usize, Arc<ThreadPool>>> {
    static POOLS: OnceLock<Mutex<HashMap<usize, Arc<ThreadPool>>>> = OnceLock::new();
    POOLS.get_or_init(|| Mutex::new(HashMap::new()))
}

/// The pool for `threads` (`None`: rayon's global pool).
fn pool(threads: i64) -> PyResult<Option<Arc<ThreadPool>>> {
    if !(0..=MAX_THREADS).contains(&threads) {
        return Err(PyValueError::new_err(format!(
            "threads must be between 0 (all cores) and {MAX_THREADS}, got {threads}"
        )));
    }
    if threads == 0 {
        return Ok(None);
    }
    let n = threads as usize;
    let mut map = pools()
        .lock()
        .map_err(|_| PyRuntimeError::new_err("the thread pool registry is poisoned"))?;
    if let Some(p) = map.get(&n) {
        return Ok(Some(p.clone()));
    }
    let p = ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start {n} threads: {e}")))?;
    let p = Arc::new(p);
    map.insert(n, p.clone());
    Ok(Some(p))
}

/// Run `work` with the GIL released, on the pool for `threads`.
pub fn detached<R, F>(py: Python<'_>, threads: i64, work: F) -> PyResult<R>
where
    F: FnOnce() -> R + Send,
    R: Send,
{
    let pool = pool(threads)?;
    Ok(py.detach(move || match pool {
        Some(p) => p.install(work),
        None => work(),
    }))
}
