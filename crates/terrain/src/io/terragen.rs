//! Terragen `.ter` terrain files: the "TERRAGENTERRAIN " magic, then
//! little-endian chunks (`SIZE`, `XPTS`, `YPTS`, `SCAL`, `CRAD`, `CRVM`),
//! then `ALTW` with the `i16` elevations, optionally `EOF `.

use std::fs::File;
use std::io::{BufReader, ErrorKind, Read};
use std::path::Path;

use super::limits::{check_dimensions, zeroed_heights};
use super::samples::read_samples;
use super::DemError;
use crate::dem::{Dem, GeoRef};

/// A little-endian reader that knows its byte offset, for error positions.
struct Cursor<'a, R> {
    path: &'a Path,
    inner: R,
    pos: u64,
}

impl<R: Read> Cursor<'_, R> {
    fn bytes<const N: usize>(&mut self, what: &str) -> Result<[u8; N], DemError> {
        let mut b = [0u8; N];
        let mut filled = 0;
        while filled < N {
            match self.inner.read(&mut b[filled..]) {
                Ok(0) => {
                    return Err(DemError::at_byte(
                        self.path,
                        self.pos + filled as u64,
                        format!("file ends; expected {what} ({N} bytes)"),
                    ))
                }
                Ok(n) => filled += n,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => {
                    return Err(DemError::at_byte(
                        self.path,
                        self.pos,
                        format!("read failed: {e}"),
                    ))
                }
            }
        }
        self.pos += N as u64;
        Ok(b)
    }

    fn u16(&mut self, what: &str) -> Result<u16, DemError> {
        self.bytes::<2>(what).map(u16::from_le_bytes)
    }

    fn i16(&mut self, what: &str) -> Result<i16, DemError> {
        self.bytes::<2>(what).map(i16::from_le_bytes)
    }

    fn f32(&mut self, what: &str) -> Result<f32, DemError> {
        self.bytes::<4>(what).map(f32::from_le_bytes)
    }
}

/// Reads a Terragen `.ter` file.
///
/// Terragen's y axis points north and its rows run from south to north; the
/// DEM stores them flipped, north row first, as every [`Dem`] does. Heights
/// in metres are `(BaseHeight + elevation × HeightScale / 65536) × SCAL.z`
/// (SCAL defaults to 30 m). Pixel size is SCAL x/y. The file has no map
/// position: the south-west corner of the south-west pixel is put at
/// (0, 0) with y north, as in Terragen, so the DEM's top-left corner is at
/// (0, rows × SCAL.y). (GDAL's Terragen driver gives the same rows in the
/// same north-first order but reports origin (0, 0) with a positive pixel
/// height, i.e. y growing southwards.) Not geographic, no nodata.
pub fn read_ter(path: impl AsRef<Path>) -> Result<Dem, DemError> {
    let path = path.as_ref();
    let file = File::open(path).map_err(|e| DemError::open(path, &e))?;
    let len = file.metadata().map_err(|e| DemError::open(path, &e))?.len();
    let mut c = Cursor {
        path,
        inner: BufReader::new(file),
        pos: 0,
    };
    let magic: [u8; 16] = c.bytes("the magic \"TERRAGENTERRAIN \"")?;
    if &magic != b"TERRAGENTERRAIN " {
        return Err(DemError::at_byte(
            path,
            0,
            format!(
                "expected the magic \"TERRAGENTERRAIN \", found {:?}",
                String::from_utf8_lossy(&magic)
            ),
        ));
    }
    let mut size: Option<u16> = None;
    let (mut xpts, mut ypts): (Option<u16>, Option<u16>) = (None, None);
    let mut scale = [30f32; 3];
    let (height_scale, base_height) = loop {
        let at = c.pos;
        let id: [u8; 4] = c.bytes("a chunk marker (SIZE, XPTS, YPTS, SCAL, CRAD, CRVM or ALTW)")?;
        match &id {
            b"SIZE" => {
                size = Some(c.u16("the SIZE value")?);
                c.bytes::<2>("SIZE padding")?;
            }
            b"XPTS" => {
                xpts = Some(c.u16("the XPTS value")?);
                c.bytes::<2>("XPTS padding")?;
            }
            b"YPTS" => {
                ypts = Some(c.u16("the YPTS value")?);
                c.bytes::<2>("YPTS padding")?;
            }
            b"SCAL" => {
                for s in &mut scale {
                    *s = c.f32("a SCAL value")?;
                }
                if scale.iter().any(|s| !s.is_finite() || *s <= 0.0) {
                    return Err(DemError::at_byte(
                        path,
                        at,
                        format!(
                            "SCAL is {scale:?}; expected three positive metres-per-unit values"
                        ),
                    ));
                }
            }
            b"CRAD" => {
                c.f32("the CRAD planet radius")?;
            }
            b"CRVM" => {
                c.bytes::<4>("the CRVM curve mode")?;
            }
            b"ALTW" => {
                break (
                    c.i16("the ALTW HeightScale")?,
                    c.i16("the ALTW BaseHeight")?,
                )
            }
            b"EOF " => {
                return Err(DemError::at_byte(
                    path,
                    at,
                    "EOF chunk before any ALTW chunk; expected the ALTW elevations",
                ))
            }
            _ => {
                return Err(DemError::at_byte(
                    path,
                    at,
                    format!(
                        "unknown chunk {:?}; expected SIZE, XPTS, YPTS, SCAL, CRAD, CRVM or ALTW",
                        String::from_utf8_lossy(&id)
                    ),
                ))
            }
        }
    };
    let altw_at = c.pos - 12;
    let square = size.map(|s| s as usize + 1);
    let width = xpts.map(usize::from).or(square);
    let height = ypts.map(usize::from).or(square);
    let (Some(width), Some(height)) = (width, height) else {
        return Err(DemError::at_byte(
            path,
            altw_at,
            "ALTW chunk before any SIZE (or XPTS and YPTS) chunk; expected the grid size first",
        ));
    };
    check_dimensions(path, &format!("byte {altw_at}"), width, height)?;
    let need = (width * height * 2) as u64;
    if len < c.pos + need {
        return Err(DemError::at_byte(
            path,
            len,
            format!(
                "file ends inside the ALTW elevations; expected {need} bytes ({width}×{height} \
                 i16) from byte {}, file is {len} bytes",
                c.pos
            ),
        ));
    }
    let mut heights = zeroed_heights(path, &format!("byte {altw_at}"), width, height)?;
    let (k, base, sz) = (
        height_scale as f64 / 65536.0,
        base_height as f64,
        scale[2] as f64,
    );
    let start = c.pos;
    read_samples(path, &mut c.inner, start, 2, &mut heights, |b| {
        ((base + i16::from_le_bytes([b[0], b[1]]) as f64 * k) * sz) as f32
    })?;
    // South row first in the file; north row first in the DEM.
    for r in 0..height / 2 {
        let (top, bottom) = heights.split_at_mut((height - 1 - r) * width);
        top[r * width..(r + 1) * width].swap_with_slice(&mut bottom[..width]);
    }
    let (sx, sy) = (scale[0] as f64, scale[1] as f64);
    Ok(Dem {
        width,
        height,
        heights,
        nodata: None,
        georef: GeoRef {
            origin_x: 0.0,
            origin_y: height as f64 * sy,
            pixel_width: sx,
            pixel_height: -sy,
            ..GeoRef::default()
        },
    })
}
