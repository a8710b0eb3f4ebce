//! Streaming fixed-size binary samples from a reader into `f32` heights,
//! a block at a time (no second full-size buffer), with truncation reported
//! at the byte where the data ran out.

use std::io::{ErrorKind, Read};
use std::path::Path;

use super::DemError;

/// Reads `out.len()` samples of `size` bytes each from `reader`, whose first
/// byte is at file offset `start`, converting each with `decode` (which gets
/// exactly `size` bytes).
pub(crate) fn read_samples<R: Read>(
    path: &Path,
    reader: &mut R,
    start: u64,
    size: usize,
    out: &mut [f32],
    decode: impl Fn(&[u8]) -> f32,
) -> Result<(), DemError> {
    const BLOCK_SAMPLES: usize = 1 << 16;
    let total = out.len() as u64 * size as u64;
    let mut buf = vec![0u8; BLOCK_SAMPLES * size];
    let mut pos = start;
    for chunk in out.chunks_mut(BLOCK_SAMPLES) {
        let bytes = &mut buf[..chunk.len() * size];
        let mut filled = 0;
        while filled < bytes.len() {
            match reader.read(&mut bytes[filled..]) {
                Ok(0) => {
                    return Err(DemError::at_byte(
                        path,
                        pos + filled as u64,
                        format!(
                            "file ends inside the height samples; expected {total} bytes \
                             ({} samples of {size} bytes) from byte {start}",
                            out.len()
                        ),
                    ))
                }
                Ok(n) => filled += n,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => {
                    return Err(DemError::at_byte(
                        path,
                        pos + filled as u64,
                        format!("read failed: {e}"),
                    ))
                }
            }
        }
        for (h, b) in chunk.iter_mut().zip(bytes.chunks_exact(size)) {
            *h = decode(b);
        }
        pos += bytes.len() as u64;
    }
    Ok(())
}
