//! Reading a whole input file, and gzip decompression with located errors.

use crate::error::{ErrorKind, LoadError, Location};
use flate2::bufread::MultiGzDecoder;
use std::io::Read;
use std::path::Path;

/// The bytes of `path`.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, LoadError> {
    std::fs::read(path).map_err(|e| LoadError::io(path, "cannot read the file", e))
}

/// The bytes of `path`, the I/O error written into the message instead of
/// kept as a source: for errors whose whole chain of causes is printed,
/// which would show it twice.
pub(crate) fn read_file_cause_in_message(path: &Path) -> Result<Vec<u8>, LoadError> {
    std::fs::read(path).map_err(|e| {
        LoadError::new(
            path,
            ErrorKind::Io,
            Location::File,
            format!("cannot read: {e}"),
        )
    })
}

/// Decompress gzip `data` (all members) read from `path`.
pub(crate) fn gunzip(path: &Path, data: &[u8]) -> Result<Vec<u8>, LoadError> {
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
    let mut out = Vec::with_capacity(data.len().saturating_mul(4).min(1 << 30));
    let mut dec = MultiGzDecoder::new(data);
    if let Err(e) = dec.read_to_end(&mut out) {
        let consumed = data.len() - dec.get_ref().len();
        let message = if e.kind() == std::io::ErrorKind::OutOfMemory {
            format!(
                "the decompressed data outgrew the memory the process may use \
                 ({} MiB decompressed so far, {:.0} times the compressed bytes read)",
                out.len() >> 20,
                out.len() as f64 / consumed.max(1) as f64
            )
        } else {
            format!("gzip data is corrupt or truncated: {e}")
        };
        return Err(LoadError::at_byte(path, consumed as u64, message));
    }
    Ok(out)
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
}
