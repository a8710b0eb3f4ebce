//! Timing helpers: thread pools of a given size and medians of repeated runs.

use anyhow::{Context, Result};
use std::time::Instant;

/// The most worker threads a command starts (`--threads`): far beyond any
/// machine's cores, and short of what stalls a process spawning threads.
pub const MAX_THREADS: usize = 4096;

/// `threads` as `--threads` takes it: 0 (one per core) to [`MAX_THREADS`].
pub fn check_threads(threads: usize) -> Result<usize> {
    if threads > MAX_THREADS {
        anyhow::bail!(
            "--threads {threads}: at most {MAX_THREADS} worker threads (0 = one per core, {} here)",
            std::thread::available_parallelism().map_or(1, |n| n.get())
        );
    }
    Ok(threads)
}

/// A rayon pool with `threads` workers (0 = one per core), refused above
/// [`MAX_THREADS`].
pub fn pool(threads: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(check_threads(threads)?)
        .build()
        .context("cannot start the thread pool")
}

/// Run `f` and return its result with the elapsed seconds.
pub fn timed<R>(f: impl FnOnce() -> R) -> (R, f64) {
    let start = Instant::now();
    let r = f();
    (r, start.elapsed().as_secs_f64())
}

/// Items per second for `n` items in `seconds`: 0 for no items (or no
/// measurable time), so that the JSON stats lines never hold NaN.
pub fn per_second(n: usize, seconds: f64) -> f64 {
    if n == 0 || seconds <= 0.0 {
        0.0
    } else {
        n as f64 / seconds
    }
}

/// Median, minimum and maximum of a sample; all 0 for an empty one (no
/// runs measured nothing), like [`per_second`], so that no caller panics and
/// the JSON stats lines never hold NaN.
pub fn median_min_max(samples: &[f64]) -> (f64, f64, f64) {
    let mut s = samples.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n == 0 {
        return (0.0, 0.0, 0.0);
    }
    let median = if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    };
    (median, s[0], s[n - 1])
}

/// The noise of repeated timings: their spread (max − min) relative to the
/// median. `None` for fewer than two samples, which measure no spread, and
/// for a zero median.
pub fn spread(samples: &[f64]) -> Option<f64> {
    let (median, lo, hi) = median_min_max(samples);
    (samples.len() >= 2 && median > 0.0).then(|| (hi - lo) / median)
}

/// The worse of two noise figures; `None` only when neither was measured.
pub fn worse_spread(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.max(b)),
        (a, b) => a.or(b),
    }
}

/// A noise figure as a table shows it: a whole percentage, or `n/a` when
/// fewer than two repetitions were timed.
pub fn spread_percent(spread: Option<f64>) -> String {
    spread.map_or_else(|| "n/a".into(), |s| format!("{:.0}%", 100.0 * s))
}

/// Median of `samples` (seconds) in milliseconds, and the noise: the spread
/// (max − min) relative to the median, `None` from fewer than two samples.
pub fn median_ms(samples: &[f64]) -> (f64, Option<f64>) {
    (median_min_max(samples).0 * 1e3, spread(samples))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_samples() {
        assert_eq!(median_min_max(&[3.0, 1.0, 2.0]), (2.0, 1.0, 3.0));
        assert_eq!(median_min_max(&[4.0, 1.0, 2.0, 3.0]), (2.5, 1.0, 4.0));
    }

    #[test]
    fn spread_needs_two_samples() {
        assert_eq!(spread(&[]), None);
        assert_eq!(spread(&[2.0]), None);
        let sample = [3.0, 1.0, 2.0];
        let (median, lo, hi) = median_min_max(&sample);
        assert_eq!(spread(&sample), Some((hi - lo) / median));
        assert_eq!(spread_percent(spread(&[2.0])), "n/a");
        assert_eq!(worse_spread(None, spread(&sample)), spread(&sample));
        assert_eq!(worse_spread(None, None), None);
    }

    #[test]
    fn an_empty_sample_gives_zeros_instead_of_a_panic() {
        assert_eq!(median_min_max(&[]), (0.0, 0.0, 0.0));
        assert_eq!(median_ms(&[]), (0.0, None));
    }
}
