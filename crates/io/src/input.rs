//! Reading a whole input file, and gzip decompression with located errors.

use crate::error::{ErrorKind, LoadError, Location};
use flate2::bufread::MultiGzDecoder;
use std::io::Read;
use std::path::Path;

/// The bytes of `path`.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, LoadError> {
    regular_file(path)?;
    std::fs::read(path).map_err(|e| LoadError::io(path, "cannot read the file", e))
}

/// Refuse `path` when it exists but is not a regular file: a device such
/// as `/dev/zero` reads without end, and opening a named pipe waits for a
/// writer. A missing file is left to the read, which names the cause.
fn regular_file(path: &Path) -> Result<(), LoadError> {
    match std::fs::metadata(path) {
        Ok(m) if !m.is_file() => Err(LoadError::new(
            path,
            ErrorKind::Io,
            Location::File,
            not_a_regular_file(&m),
        )),
        _ => Ok(()),
    }
}

/// What a path that is not a regular file is, for the refusal.
pub fn not_a_regular_file(m: &std::fs::Metadata) -> String {
    let what = if m.is_dir() {
        "a folder"
    } else {
        "a device, pipe or socket"
    };
    format!("not a regular file ({what}); give a file")
}

/// The bytes of `path`, the I/O error written into the message instead of
/// kept as a source: for errors whose whole chain of causes is printed,
/// which would show it twice.
pub(crate) fn read_file_cause_in_message(path: &Path) -> Result<Vec<u8>, LoadError> {
    regular_file(path)?;
    std::fs::read(path).map_err(|e| {
        LoadError::new(
            path,
            ErrorKind::Io,
            Location::File,
            format!("cannot read: {e}"),
        )
    })
}

/// Decompress gzip `data` (all members) read from `path`, refusing output
/// larger than the memory this machine has available now (`MemAvailable`
/// on Linux; no bound elsewhere): a small file can expand a thousandfold,
/// and where memory is overcommitted growing past it ends in the kernel
/// killing the process rather than in an error.
pub(crate) fn gunzip(path: &Path, data: &[u8]) -> Result<Vec<u8>, LoadError> {
    gunzip_within(path, data, available_memory().unwrap_or(u64::MAX))
}

/// The bytes of memory available for new allocations without swapping,
/// from `/proc/meminfo`; None where that cannot be read.
pub(crate) fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib.saturating_mul(1024))
}

/// [`gunzip`] with at most `limit` bytes of output.
fn gunzip_within(path: &Path, data: &[u8], limit: u64) -> Result<Vec<u8>, LoadError> {
    if data.len() < 2 || data[0] != 0x1f || data[1] != 0x8b {
        let found: Vec<String> = data.iter().take(2).map(|b| format!("{b:02x}")).collect();
        return Err(LoadError::at_byte(
            path,
            0,
            format!(
                "not gzip data: expected the bytes 1f 8b, found [{}]",
                found.join(" ")
            ),
        ));
    }
    // Deflate rarely exceeds 10:1 on meshes; the vector grows if it does.
    let first = (data.len() as u64)
        .saturating_mul(4)
        .min(1 << 30)
        .min(limit);
    let mut out = Vec::with_capacity(first as usize);
    let mut dec = MultiGzDecoder::new(data);
    let read = (&mut dec)
        .take(limit.saturating_add(1))
        .read_to_end(&mut out);
    let consumed = (data.len() - dec.get_ref().len()) as u64;
    let outgrew = |so_far: usize| {
        format!(
            "the decompressed data outgrew the memory available ({} MiB decompressed so far, \
             {:.0} times the compressed bytes read; at most {} MiB)",
            so_far >> 20,
            so_far as f64 / consumed.max(1) as f64,
            limit >> 20
        )
    };
    match read {
        Err(e) if e.kind() == std::io::ErrorKind::OutOfMemory => {
            Err(LoadError::at_byte(path, consumed, outgrew(out.len())))
        }
        Err(e) => Err(LoadError::at_byte(
            path,
            consumed,
            format!("gzip data is corrupt or truncated: {e}"),
        )),
        Ok(_) if out.len() as u64 > limit => {
            Err(LoadError::at_byte(path, consumed, outgrew(out.len())))
        }
        Ok(_) => Ok(out),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flate2::write::GzEncoder;
    use flate2::Compression;
    use std::io::Write;

    fn gz(data: &[u8]) -> Vec<u8> {
        let mut e = GzEncoder::new(Vec::new(), Compression::default());
        e.write_all(data).unwrap();
        e.finish().unwrap()
    }

    #[test]
    fn round_trip_and_errors() {
        let p = Path::new("t.ply.gz");
        let text = b"hello gzip world, hello gzip world".repeat(100);
        let z = gz(&text);
        assert_eq!(gunzip(p, &z).unwrap(), text);
        let e = gunzip(p, b"plain").unwrap_err().to_string();
        assert!(e.starts_with("t.ply.gz: byte 0: not gzip data"), "{e}");
        for cut in [3, 10, z.len() / 2, z.len() - 4, z.len() - 1] {
            let e = gunzip(p, &z[..cut]).unwrap_err().to_string();
            assert!(e.contains("t.ply.gz: byte "), "{e}");
        }
        let mut bad = z.clone();
        for b in &mut bad[12..30] {
            *b ^= 0x5a;
        }
        assert!(gunzip(p, &bad).is_err());
    }

    /// A gzip bomb (64 members of 1 MiB of zeros, about 64 KB) decompresses
    /// within a bound of 128 MiB and is refused, at the byte where it
    /// passed it, under 16 MiB.
    #[test]
    fn output_is_bounded() {
        let p = Path::new("b.ply.gz");
        let bomb = gz(&vec![0u8; 1 << 20]).repeat(64);
        assert_eq!(gunzip_within(p, &bomb, 128 << 20).unwrap().len(), 64 << 20);
        let e = gunzip_within(p, &bomb, 16 << 20).unwrap_err().to_string();
        assert!(e.starts_with("b.ply.gz: byte "), "{e}");
        assert!(
            e.contains("outgrew the memory available") && e.contains("at most 16 MiB"),
            "{e}"
        );
        assert!(available_memory().is_some_and(|m| m > 0) || !cfg!(target_os = "linux"));
    }
}
