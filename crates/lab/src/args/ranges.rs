//! Range checks of the experiments' numeric options, refused before any work
//! starts with the flag, its range and the value given.

use anyhow::{bail, Result};
use std::fmt::Display;

/// The most timed repetitions an experiment takes (`--reps`).
pub const MAX_REPS: usize = 1000;

/// `value` of `flag` when it lies in `lo..=hi`; otherwise an error naming
/// the flag, the range and the value.
pub fn in_range<T: PartialOrd + Display + Copy>(flag: &str, value: T, lo: T, hi: T) -> Result<T> {
    if value < lo || value > hi {
        bail!("{flag} must be between {lo} and {hi}, got {value}");
    }
    Ok(value)
}

/// An image side (`--size`, `--width`, `--height`): 1 to
/// [`raykit_io::MAX_IMAGE_SIDE`], as `raykit rays` and `raykit render`
/// take it.
pub fn image_side(flag: &str, value: u32) -> Result<u32> {
    in_range(flag, value, 1, raykit_io::MAX_IMAGE_SIDE)
}

/// A count of timed repetitions (`--reps`): 1 to [`MAX_REPS`].
pub fn reps(value: usize) -> Result<usize> {
    in_range("--reps", value, 1, MAX_REPS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_outside_the_range_are_refused_naming_flag_and_value() {
        assert_eq!(in_range("--n", 5, 1, 10).unwrap(), 5);
        assert_eq!(in_range("--n", 1, 1, 10).unwrap(), 1);
        assert_eq!(in_range("--n", 10, 1, 10).unwrap(), 10);
        for bad in [0, 11] {
            let e = in_range("--n", bad, 1, 10).unwrap_err().to_string();
            assert_eq!(e, format!("--n must be between 1 and 10, got {bad}"));
        }
        assert!(image_side("--size", 0).is_err());
        assert!(image_side("--size", raykit_io::MAX_IMAGE_SIDE + 1).is_err());
        assert!(reps(0).is_err());
        assert!(reps(MAX_REPS + 1).is_err());
    }
}
