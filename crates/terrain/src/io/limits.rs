//! Size limits every reader checks before allocating, so that a corrupt or
//! hostile header cannot ask for terabytes.

use std::path::Path;

use super::DemError;

/// Largest accepted width or height, in samples.
pub const MAX_SIDE: usize = 65_536;

/// Largest accepted number of samples (width × height): 2³¹, i.e. 8 GiB of
/// `f32` heights.
pub const MAX_SAMPLES: usize = 1 << 31;

/// Checks `width` × `height` against [`MAX_SIDE`] and [`MAX_SAMPLES`] (and
/// that neither is zero); `at` names where the dimensions were read.
pub fn check_dimensions(
    path: &Path,
    at: &str,
    width: usize,
    height: usize,
) -> Result<(), DemError> {
    if width == 0 || height == 0 {
        return Err(DemError::new(
            path,
            at,
            format!("raster is {width}×{height}; expected at least 1×1 samples"),
        ));
    }
    if width > MAX_SIDE || height > MAX_SIDE {
        return Err(DemError::new(
            path,
            at,
            format!("raster is {width}×{height}; expected at most {MAX_SIDE} samples per side"),
        ));
    }
    if width * height > MAX_SAMPLES {
        return Err(DemError::new(
            path,
            at,
            format!(
                "raster is {width}×{height} = {} samples; expected at most {MAX_SAMPLES}",
                width * height
            ),
        ));
    }
    Ok(())
}

/// Zeroed room for the `width` × `height` heights of `path`, or an error
/// naming their size when this machine cannot allocate it (rather than the
/// process aborting); `at` names where the dimensions were read.
pub fn zeroed_heights(
    path: &Path,
    at: &str,
    width: usize,
    height: usize,
) -> Result<Vec<f32>, DemError> {
    ensure_room(path, at, width, height, 4)?;
    Ok(vec![0.0; width * height])
}

/// Bytes per sample that the terrain commands allocate over the heights
/// once read: the max-mipmap pyramid (`[max, min]` per cell, 8 bytes, and
/// a third more for its coarser levels) and a mask byte, rounded up.
pub const WORK_BYTES_PER_SAMPLE: usize = 12;

/// Fail, naming the size, when `bytes_per_sample` bytes for each of the
/// `width` × `height` samples of `path` (the memory a decoder is about to
/// ask for), and [`WORK_BYTES_PER_SAMPLE`] more for what is built over the
/// heights, cannot be allocated now, rather than let a later allocation
/// abort the process.
pub fn ensure_room(
    path: &Path,
    at: &str,
    width: usize,
    height: usize,
    bytes_per_sample: usize,
) -> Result<(), DemError> {
    let bytes = (width * height).saturating_mul(bytes_per_sample + WORK_BYTES_PER_SAMPLE);
    if Vec::<u8>::new().try_reserve_exact(bytes).is_err() {
        return Err(DemError::new(
            path,
            at,
            format!(
                "raster is {width}×{height}: reading it and the pyramid over it need {} MiB, which \
                 cannot be allocated",
                bytes >> 20
            ),
        ));
    }
    Ok(())
}
