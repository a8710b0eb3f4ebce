//! GDAL's mask of valid cells: a one-band raster of the DEM's size whose
//! zeros mark cells without data. GDAL keeps it inside the GeoTIFF as an
//! extra image whose NewSubfileType (254) is 4, "transparency mask", or
//! beside it in `<file>.msk` (GDAL_TIFF_INTERNAL_MASK=NO, the default before
//! GDAL 3.9). GDAL's tools (gdalwarp, gdaldem, gdal_translate to a format
//! with nodata) treat the masked cells as no data; so do we, making them NaN.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::Tag;

use super::file_at::read_at;
use super::tiff_header::TiffHeader;
use super::DemError;

/// NewSubfileType of a full-resolution transparency mask.
const SUBFILE_MASK: u64 = 4;
/// Images looked at past the first before giving up on finding the mask:
/// GDAL puts the mask right after the image, then the overviews.
const MAX_IMAGES: usize = 64;
/// TIFF's PhotometricInterpretation tag and its BlackIsZero value.
const TAG_PHOTOMETRIC: u16 = 262;
const BLACK_IS_ZERO: u16 = 1;

/// Where a DEM's mask was found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MaskSource {
    /// An image inside the GeoTIFF, counted from 0 for the DEM itself.
    Internal(usize),
    /// The `.msk` file beside it.
    Sidecar(PathBuf),
}

/// Makes the cells that GDAL's mask marks invalid NaN: the mask inside the
/// file (`dec` reads `file`, whose header is `header`, and is positioned
/// anywhere after the DEM's image), else the `.msk` beside `path`. Returns where the mask came from,
/// or `None` when there is none.
pub fn apply_gdal_mask<R: Read + Seek>(
    path: &Path,
    file: &File,
    header: TiffHeader,
    dec: &mut Decoder<R>,
    heights: &mut [f32],
    size: (usize, usize),
) -> Result<Option<MaskSource>, DemError> {
    let mut index = 0;
    while index < MAX_IMAGES && dec.more_images() {
        index += 1;
        let at = format!("image {index} (IFD {})", index + 1);
        dec.next_image()
            .map_err(|e| DemError::new(path, &at, format!("unreadable: {e}")))?;
        if subfile_type(path, &at, dec)? == SUBFILE_MASK && dims(dec) == Some(size) {
            let ifd = dec.ifd_pointer().map_or(0, |p| p.0);
            let valid = read_mask(path, &at, file, header, ifd, size)?;
            blank_invalid(heights, &valid);
            return Ok(Some(MaskSource::Internal(index)));
        }
    }
    let sidecar = sidecar_path(path);
    if !sidecar.is_file() {
        return Ok(None);
    }
    let side = File::open(&sidecar).map_err(|e| DemError::open(&sidecar, &e))?;
    let side_header = TiffHeader::read(&sidecar, &side)?;
    let mut probe = Decoder::new(MaskView::new(&side, None)?)
        .map_err(|e| DemError::new(&sidecar, "image 0", format!("not a readable TIFF: {e}")))?;
    let got = dims(&mut probe);
    if got != Some(size) {
        return Err(DemError::new(
            &sidecar,
            "tag 256",
            format!(
                "GDAL mask of {} is {}; expected {}×{}, the DEM's size",
                path.display(),
                got.map_or("of no readable size".to_string(), |(w, h)| format!(
                    "{w}×{h}"
                )),
                size.0,
                size.1
            ),
        ));
    }
    let valid = read_mask(
        &sidecar,
        "image 0",
        &side,
        side_header,
        side_header.first_ifd,
        size,
    )?;
    blank_invalid(heights, &valid);
    Ok(Some(MaskSource::Sidecar(sidecar)))
}

/// A TIFF file seen with the image at a chosen IFD first and its
/// PhotometricInterpretation read as BlackIsZero. The `tiff` crate decodes
/// no image marked "transparency mask" (4), while the samples of GDAL's
/// masks are plain grey ones: this view lets the crate decode them with
/// every compression and layout it knows. It patches bytes as they are
/// read; the file is not changed.
struct MaskView<'a> {
    file: &'a File,
    len: u64,
    pos: u64,
    /// Byte ranges shown in place of the file's: (offset, bytes).
    patches: Vec<(u64, Vec<u8>)>,
}

impl<'a> MaskView<'a> {
    /// The view of `file`: with `patch`, (its header, the IFD to start at,
    /// where that IFD's PhotometricInterpretation value lies); without,
    /// the file as it is.
    fn new(file: &'a File, patch: Option<(TiffHeader, u64, u64)>) -> Result<Self, DemError> {
        let len = file.metadata().map(|m| m.len()).unwrap_or(0);
        let mut view = MaskView {
            file,
            len,
            pos: 0,
            patches: Vec::new(),
        };
        if let Some((header, ifd, photometric_at)) = patch {
            view.patches.push((0, header.pointing_at(ifd)));
            let grey = header.u16_bytes(BLACK_IS_ZERO);
            view.patches.push((photometric_at, grey.to_vec()));
        }
        Ok(view)
    }
}

impl Read for MaskView<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = (self.len.saturating_sub(self.pos)).min(buf.len() as u64) as usize;
        if n == 0 {
            return Ok(0);
        }
        read_at(self.file, &mut buf[..n], self.pos)?;
        for (at, bytes) in &self.patches {
            for (i, &b) in bytes.iter().enumerate() {
                let p = at + i as u64;
                if p >= self.pos && p < self.pos + n as u64 {
                    buf[(p - self.pos) as usize] = b;
                }
            }
        }
        self.pos += n as u64;
        Ok(n)
    }
}

impl Seek for MaskView<'_> {
    fn seek(&mut self, to: SeekFrom) -> std::io::Result<u64> {
        let next = match to {
            SeekFrom::Start(p) => Some(p),
            SeekFrom::End(d) => self.len.checked_add_signed(d),
            SeekFrom::Current(d) => self.pos.checked_add_signed(d),
        };
        self.pos = next.ok_or_else(|| {
            std::io::Error::new(std::io::ErrorKind::InvalidInput, "seek before the start")
        })?;
        Ok(self.pos)
    }
}

/// Where the value of the IFD at `ifd`'s PhotometricInterpretation entry
/// lies in `file` (whose header is `h`), if it has one.
fn photometric_value_at(file: &File, h: TiffHeader, ifd: u64) -> Option<u64> {
    let (count_len, entry_len, value_off) = if h.big { (8, 20, 12) } else { (2, 12, 8) };
    let mut count = [0u8; 8];
    read_at(file, &mut count[..count_len], ifd).ok()?;
    let n = match h.big {
        true => h.u64(&count),
        false => h.u16(&count[..2]) as u64,
    };
    let mut entry = [0u8; 2];
    for i in 0..n.min(4096) {
        let at = ifd + count_len as u64 + i * entry_len;
        read_at(file, &mut entry, at).ok()?;
        if h.u16(&entry) == TAG_PHOTOMETRIC {
            return Some(at + value_off);
        }
    }
    None
}

/// `<file>.msk`, GDAL's name for an external mask.
fn sidecar_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_os_string();
    name.push(".msk");
    PathBuf::from(name)
}

fn subfile_type<R: Read + Seek>(
    path: &Path,
    at: &str,
    dec: &mut Decoder<R>,
) -> Result<u64, DemError> {
    let bad = |e: tiff::TiffError| DemError::new(path, format!("{at}, tag 254"), e.to_string());
    match dec.find_tag(Tag::NewSubfileType).map_err(bad)? {
        None => Ok(0),
        Some(v) => v.into_u64().map_err(bad),
    }
}

fn dims<R: Read + Seek>(dec: &mut Decoder<R>) -> Option<(usize, usize)> {
    dec.dimensions().ok().map(|(w, h)| (w as usize, h as usize))
}

/// The mask stored at the IFD at `ifd` of `file` (whose header is
/// `header`), as one flag per cell
/// (true = valid). GDAL writes 1-bit masks (rows padded to whole bytes, 1 =
/// valid) and, beside lossy images, 8-bit ones (0 = invalid, anything else
/// valid).
fn read_mask(
    path: &Path,
    at: &str,
    file: &File,
    header: TiffHeader,
    ifd: u64,
    (w, h): (usize, usize),
) -> Result<Vec<bool>, DemError> {
    let undecodable =
        |e: String| DemError::new(path, at, format!("cannot decode the GDAL mask: {e}"));
    let photometric = photometric_value_at(file, header, ifd)
        .ok_or_else(|| undecodable("no PhotometricInterpretation (tag 262)".into()))?;
    let view = MaskView::new(file, Some((header, ifd, photometric)))?;
    let data = Decoder::new(view)
        .map(|d| d.with_limits(Limits::default()))
        .and_then(|mut d| d.read_image())
        .map_err(|e| undecodable(e.to_string()))?;
    let DecodingResult::U8(bytes) = data else {
        return Err(undecodable("samples are not 1- or 8-bit unsigned".into()));
    };
    let packed = w.div_ceil(8);
    if bytes.len() == w * h {
        Ok(bytes.iter().map(|&b| b != 0).collect())
    } else if bytes.len() == packed * h {
        Ok((0..w * h)
            .map(|i| {
                let (row, col) = (i / w, i % w);
                bytes[row * packed + col / 8] & (0x80 >> (col % 8)) != 0
            })
            .collect())
    } else {
        Err(undecodable(format!(
            "{} bytes decoded; expected {} (1 bit) or {} (8 bits) for {w}×{h}",
            bytes.len(),
            packed * h,
            w * h
        )))
    }
}

fn blank_invalid(heights: &mut [f32], valid: &[bool]) {
    for (height, &ok) in heights.iter_mut().zip(valid) {
        if !ok {
            *height = f32::NAN;
        }
    }
}
