//! The TIFF header (TIFF 6.0, section 2; BigTIFF): byte order, classic
//! (32-bit offsets) or BigTIFF (64-bit), and the first IFD's offset. Read
//! once per file and shared by the GeoTIFF reader and the GDAL mask reader.

use std::fs::File;
use std::path::Path;

use super::file_at::read_up_to;
use super::DemError;

/// A TIFF file's header.
#[derive(Clone, Copy, Debug)]
pub(super) struct TiffHeader {
    /// "II" (true) or "MM" (false).
    pub little_endian: bool,
    /// BigTIFF (version 43, 16-byte header) rather than classic TIFF (42).
    pub big: bool,
    /// Where the first IFD starts.
    pub first_ifd: u64,
    /// The header's bytes (8 of them used for classic TIFF).
    bytes: [u8; 16],
}

impl TiffHeader {
    /// Reads the header at the start of `file` (without moving its
    /// cursor). Errors name `path` and the byte at fault.
    pub(super) fn read(path: &Path, file: &File) -> Result<TiffHeader, DemError> {
        let mut bytes = [0u8; 16];
        let n = read_up_to(file, &mut bytes, 0)
            .map_err(|e| DemError::at_byte(path, 0, format!("read failed: {e}")))?;
        let little_endian = match &bytes[..2.min(n)] {
            b"II" => true,
            b"MM" => false,
            other => {
                return Err(DemError::at_byte(
                    path,
                    0,
                    format!(
                        "not a TIFF: expected \"II\" or \"MM\", found {:?}",
                        String::from_utf8_lossy(other)
                    ),
                ))
            }
        };
        let mut header = TiffHeader {
            little_endian,
            big: false,
            first_ifd: 0,
            bytes,
        };
        let version = if n >= 4 { header.u16(&bytes[2..4]) } else { 0 };
        let need = if version == 43 { 16 } else { 8 };
        if n < need {
            return Err(DemError::at_byte(
                path,
                n as u64,
                "file ends inside the TIFF header",
            ));
        }
        match version {
            42 => header.first_ifd = header.u32(&bytes[4..8]) as u64,
            43 => {
                header.big = true;
                header.first_ifd = header.u64(&bytes[8..16]);
            }
            v => {
                return Err(DemError::at_byte(
                    path,
                    2,
                    format!("TIFF version {v}; expected 42 (TIFF) or 43 (BigTIFF)"),
                ))
            }
        }
        Ok(header)
    }

    /// A 16-bit number stored in the file's byte order (`b` holds 2 bytes).
    pub(super) fn u16(self, b: &[u8]) -> u16 {
        let b = [b[0], b[1]];
        match self.little_endian {
            true => u16::from_le_bytes(b),
            false => u16::from_be_bytes(b),
        }
    }

    /// A 32-bit number stored in the file's byte order (`b` holds 4 bytes).
    pub(super) fn u32(self, b: &[u8]) -> u32 {
        let b = [b[0], b[1], b[2], b[3]];
        match self.little_endian {
            true => u32::from_le_bytes(b),
            false => u32::from_be_bytes(b),
        }
    }

    /// A 64-bit number stored in the file's byte order (`b` holds 8 bytes).
    pub(super) fn u64(self, b: &[u8]) -> u64 {
        let b: [u8; 8] = [b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]];
        match self.little_endian {
            true => u64::from_le_bytes(b),
            false => u64::from_be_bytes(b),
        }
    }

    /// `v` as 2 bytes in the file's byte order.
    pub(super) fn u16_bytes(self, v: u16) -> [u8; 2] {
        match self.little_endian {
            true => v.to_le_bytes(),
            false => v.to_be_bytes(),
        }
    }

    /// The header's bytes rewritten so that the file starts at the IFD at
    /// `ifd` (8 bytes for classic TIFF, 16 for BigTIFF).
    pub(super) fn pointing_at(self, ifd: u64) -> Vec<u8> {
        let mut out = self.bytes.to_vec();
        if self.big {
            let b = match self.little_endian {
                true => ifd.to_le_bytes(),
                false => ifd.to_be_bytes(),
            };
            out[8..16].copy_from_slice(&b);
        } else {
            let v = ifd as u32;
            let b = match self.little_endian {
                true => v.to_le_bytes(),
                false => v.to_be_bytes(),
            };
            out[4..8].copy_from_slice(&b);
            out.truncate(8);
        }
        out
    }
}
