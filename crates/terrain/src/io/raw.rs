//! Headerless raw height grids: `width` × `height` samples of one fixed
//! type, row by row from the top (north) row, nothing else in the file.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use super::limits::{check_dimensions, zeroed_heights};
use super::samples::read_samples;
use super::DemError;
use crate::dem::Dem;

/// The sample type of a raw height file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RawType {
    /// Unsigned 8-bit.
    U8,
    /// Signed 16-bit, little-endian.
    I16Le,
    /// Signed 16-bit, big-endian (as in SRTM `.hgt`).
    I16Be,
    /// Unsigned 16-bit, little-endian (as in Unity/World Machine `.r16`).
    U16Le,
    /// Unsigned 16-bit, big-endian.
    U16Be,
    /// IEEE 754 32-bit float, little-endian (as in `.r32`).
    F32Le,
    /// IEEE 754 32-bit float, big-endian.
    F32Be,
}

impl RawType {
    /// Bytes per sample.
    pub fn bytes(self) -> usize {
        match self {
            RawType::U8 => 1,
            RawType::I16Le | RawType::I16Be | RawType::U16Le | RawType::U16Be => 2,
            RawType::F32Le | RawType::F32Be => 4,
        }
    }

    /// Lower-case name (`"u8"`, `"i16le"`, …), as [`RawType::parse`] reads it.
    pub fn name(self) -> &'static str {
        match self {
            RawType::U8 => "u8",
            RawType::I16Le => "i16le",
            RawType::I16Be => "i16be",
            RawType::U16Le => "u16le",
            RawType::U16Be => "u16be",
            RawType::F32Le => "f32le",
            RawType::F32Be => "f32be",
        }
    }

    /// The type named `name` (case-insensitive: `u8`, `i16le`, `i16be`,
    /// `u16le`, `u16be`, `f32le`, `f32be`).
    pub fn parse(name: &str) -> Option<RawType> {
        let all = [
            RawType::U8,
            RawType::I16Le,
            RawType::I16Be,
            RawType::U16Le,
            RawType::U16Be,
            RawType::F32Le,
            RawType::F32Be,
        ];
        all.into_iter()
            .find(|t| t.name().eq_ignore_ascii_case(name))
    }

    /// The value of one sample given its [`RawType::bytes`] bytes.
    pub fn decode(self, b: &[u8]) -> f32 {
        match self {
            RawType::U8 => b[0] as f32,
            RawType::I16Le => i16::from_le_bytes([b[0], b[1]]) as f32,
            RawType::I16Be => i16::from_be_bytes([b[0], b[1]]) as f32,
            RawType::U16Le => u16::from_le_bytes([b[0], b[1]]) as f32,
            RawType::U16Be => u16::from_be_bytes([b[0], b[1]]) as f32,
            RawType::F32Le => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            RawType::F32Be => f32::from_be_bytes([b[0], b[1], b[2], b[3]]),
        }
    }
}

/// Reads a raw grid of `width` × `height` samples of type `sample`, rows
/// from the top (north) row. Heights are the sample values (no scale, no
/// nodata); the georeferencing is the identity with 1 m pixels.
///
/// The file size must be exactly `width × height × sample.bytes()`; any
/// other size is an error naming both.
pub fn read_raw(
    path: impl AsRef<Path>,
    width: usize,
    height: usize,
    sample: RawType,
) -> Result<Dem, DemError> {
    let path = path.as_ref();
    check_dimensions(path, "raw size", width, height)?;
    let file = File::open(path).map_err(|e| DemError::open(path, &e))?;
    let len = file.metadata().map_err(|e| DemError::open(path, &e))?.len();
    let expected = (width * height * sample.bytes()) as u64;
    if len != expected {
        return Err(DemError::at_byte(
            path,
            len.min(expected),
            format!(
                "file is {len} bytes; {width}×{height} {} samples need exactly {expected} bytes",
                sample.name()
            ),
        ));
    }
    let mut heights = zeroed_heights(path, "raw size", width, height)?;
    read_samples(
        path,
        &mut BufReader::new(file),
        0,
        sample.bytes(),
        &mut heights,
        |b| sample.decode(b),
    )?;
    Ok(Dem::from_heights(width, height, heights))
}
