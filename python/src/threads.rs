//! Where the work runs: off the GIL, on all cores or on a pool of the
//! size the caller asked for.
//!
//! `threads = 0` uses rayon's global pool (one thread per core). Any other
//! size gets its own pool, kept among the few most recently used ones, so
//! that repeated calls with `threads=1` cost no thread start-up while a
//! loop over many sizes does not keep a pool of each alive. A pool dropped
//! from the cache lives on until the calls running on it return.
//!
//! A child made by `fork()` (multiprocessing's default start method on
//! Linux) has its parent's memory but none of its threads: the global pool
//! and the kept pools, if the parent used them, would never run its work.
//! So a process that is not the one that loaded the module forgets the
//! kept pools without dropping them (their threads are not there to be
//! stopped) and installs pools of its own, `threads = 0` included.
//!
//! Long calls can be interrupted (Ctrl-C): [`interruptible`] runs the work
//! on its own thread while the caller's thread waits with the GIL released,
//! taking the GIL back a few times a second to let Python's signal handlers
//! run. A handler's exception (KeyboardInterrupt) raises [`Stop`], which
//! the work polls between its pieces; the call then waits for the pieces
//! in flight and raises the exception, its partial results dropped.

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use rayon::{ThreadPool, ThreadPoolBuilder};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, Mutex, OnceLock};
use std::time::Duration;

/// Largest `threads` accepted: far above any core count, low enough that
/// a typo does not start a million threads.
const MAX_THREADS: i64 = 4096;

/// How many pools the cache keeps.
const KEEP_POOLS: usize = 4;

/// Largest pool the cache keeps: bigger ones (more threads than a few
/// times the cores) are made for the call and end with it, so that the
/// cache holds at most `KEEP_POOLS` × this many idle threads.
fn largest_kept() -> usize {
    static LARGEST: OnceLock<usize> = OnceLock::new();
    *LARGEST.get_or_init(|| 4 * std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// Pools by size, most recently used last, and the process they belong to.
struct Kept {
    process: u32,
    pools: Vec<(usize, Arc<ThreadPool>)>,
}

/// The pools kept.
fn pools() -> &'static Mutex<Kept> {
    static POOLS: OnceLock<Mutex<Kept>> = OnceLock::new();
    POOLS.get_or_init(|| {
        Mutex::new(Kept {
            process: std::process::id(),
            pools: Vec::new(),
        })
    })
}

/// The process that loaded the module.
static LOADED_IN: OnceLock<u32> = OnceLock::new();

/// Notes the process loading the module (called once, at import).
pub fn note_loading_process() {
    LOADED_IN.get_or_init(std::process::id);
}

/// Whether this process is a `fork()` of the one that loaded the module.
fn forked() -> bool {
    LOADED_IN.get().is_some_and(|&p| p != std::process::id())
}

/// `threads` if it is a thread count this module takes, else the error.
fn checked(threads: i64) -> PyResult<i64> {
    if !(0..=MAX_THREADS).contains(&threads) {
        return Err(PyValueError::new_err(format!(
            "threads must be between 0 (all cores) and {MAX_THREADS}, got {threads}"
        )));
    }
    Ok(threads)
}

/// The pool for `threads` (`None`: rayon's global pool).
fn pool(threads: i64) -> PyResult<Option<Arc<ThreadPool>>> {
    checked(threads)?;
    if threads == 0 && !forked() {
        return Ok(None);
    }
    let n = match threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        t => t as usize,
    };
    let mut guard = pools()
        .lock()
        .map_err(|_| PyRuntimeError::new_err("the thread pool registry is poisoned"))?;
    let kept = &mut *guard;
    if kept.process != std::process::id() {
        // The parent's pools: their threads are not in this process.
        std::mem::forget(std::mem::take(&mut kept.pools));
        kept.process = std::process::id();
    }
    let kept = &mut kept.pools;
    if let Some(i) = kept.iter().position(|(size, _)| *size == n) {
        let entry = kept.remove(i);
        let p = entry.1.clone();
        kept.push(entry);
        return Ok(Some(p));
    }
    let p = ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start {n} threads: {e}")))?;
    let p = Arc::new(p);
    if n <= largest_kept() {
        if kept.len() == KEEP_POOLS {
            kept.remove(0);
        }
        kept.push((n, p.clone()));
    }
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

/// [`interruptible`], or, where the caller vouches that `work` is a
/// `single_task` (a few rays over structures already built, see
/// `image_order::banded`), on the caller's thread with the GIL released:
/// a single task takes one thread whatever the pool's size, and handing it
/// to a pool's thread cost a one-ray call with `threads = 1` 20 µs on a
/// quiet machine and 150 µs on a busy one, against the 3 µs the work
/// takes. Such work must start no parallel work of its own: on the
/// caller's thread it would spread over rayon's global pool, whatever
/// `threads` says, and hang in a forked child, where that pool has no
/// threads. `threads` is checked either way.
pub fn inline_or_interruptible<R, F>(
    py: Python<'_>,
    threads: i64,
    items: usize,
    single_task: bool,
    work: F,
) -> PyResult<R>
where
    F: FnOnce(&Stop) -> R + Send,
    R: Send,
{
    if !single_task {
        return interruptible(py, threads, items, work);
    }
    checked(threads)?;
    let stop = Stop::default();
    Ok(py.detach(|| work(&stop)))
}

/// Below this many rays or points a call runs as [`detached`] does: a
/// thread of its own would cost more than such a call takes.
pub const INTERRUPTIBLE_FROM: usize = 1 << 16;

/// How often a waiting caller looks for a signal.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Raised when the caller of an [`interruptible`] call is interrupted; the
/// work stops at its next check.
#[derive(Default)]
pub struct Stop(AtomicBool);

impl Stop {
    /// Whether the work should stop.
    #[inline]
    pub fn raised(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// [`detached`] for work on `items` rays or points that may take long:
/// from [`INTERRUPTIBLE_FROM`] items on, a signal handler's exception
/// (Ctrl-C's KeyboardInterrupt) raises [`Stop`] for the work and is raised
/// once the work returns.
pub fn interruptible<R, F>(py: Python<'_>, threads: i64, items: usize, work: F) -> PyResult<R>
where
    F: FnOnce(&Stop) -> R + Send,
    R: Send,
{
    let stop = Stop::default();
    if items < INTERRUPTIBLE_FROM {
        return detached(py, threads, || work(&stop));
    }
    let pool = pool(threads)?;
    std::thread::scope(|s| {
        let (done, finished) = mpsc::channel::<()>();
        let stop = &stop;
        let worker = s.spawn(move || {
            let r = match pool {
                Some(p) => p.install(|| work(stop)),
                None => work(stop),
            };
            let _ = done.send(());
            r
        });
        let mut interrupted = None;
        let mut finished = finished;
        loop {
            let waited;
            (finished, waited) = py.detach(move || {
                let waited = finished.recv_timeout(SIGNAL_POLL);
                (finished, waited)
            });
            if !matches!(waited, Err(mpsc::RecvTimeoutError::Timeout)) {
                break;
            }
            if interrupted.is_none() {
                if let Err(e) = py.check_signals() {
                    stop.0.store(true, Ordering::Relaxed);
                    interrupted = Some(e);
                }
            }
        }
        let r = py
            .detach(|| worker.join())
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        match interrupted {
            Some(e) => Err(e),
            None => Ok(r),
        }
    })
}
