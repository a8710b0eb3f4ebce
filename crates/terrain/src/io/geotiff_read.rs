//! GeoTIFF input: one band of 8/16/32-bit integer or 32/64-bit float
//! samples, striped or tiled (the `tiff` crate handles layout and
//! compression, except LZW tiles: `geotiff_lzw_tiles`), with
//! ModelPixelScale + ModelTiepoint or
//! ModelTransformation georeferencing and GDAL's nodata tag.

use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

use tiff::decoder::{ifd::Value, Decoder, DecodingResult, Limits};
use tiff::tags::Tag;

use super::crs_sidecar::{read_crs_sidecar, wkt_is_geographic};
use super::file_at::read_at;
use super::gdal_mask::apply_gdal_mask;
use super::gdal_metadata::{band_scale_offset, TAG_GDAL_METADATA};
use super::geokeys::{
    declares_crs, geo_key_short, validate_geo_keys, KEY_MODEL_TYPE, KEY_RASTER_TYPE,
};
use super::geotiff_lzw_tiles::{read_lzw_tiles, TileLayout, TileSamples};
use super::geotiff_sparse::{absent_height, block_byte_counts, read_sparse};
use super::limits::{check_dimensions, ensure_room, zeroed_heights, MAX_SAMPLES};
use super::nodata::NodataF32;
use super::tiff_header::TiffHeader;
use super::DemError;
use crate::dem::{Dem, GeoRef};

/// TIFF tag ModelPixelScale.
pub const TAG_MODEL_PIXEL_SCALE: u16 = 33550;
/// TIFF tag ModelTiepoint.
pub const TAG_MODEL_TIEPOINT: u16 = 33922;
/// TIFF tag ModelTransformation.
pub const TAG_MODEL_TRANSFORMATION: u16 = 34264;
/// TIFF tag GeoKeyDirectory.
pub const TAG_GEO_KEY_DIRECTORY: u16 = 34735;
/// TIFF tag GeoDoubleParams.
pub const TAG_GEO_DOUBLE_PARAMS: u16 = 34736;
/// TIFF tag GeoAsciiParams.
pub const TAG_GEO_ASCII_PARAMS: u16 = 34737;
/// TIFF tag GDAL_NODATA (ASCII).
pub const TAG_GDAL_NODATA: u16 = 42113;

/// Reads a single-band GeoTIFF as a DEM.
///
/// Samples may be unsigned or signed 8/16/32-bit integers or 32/64-bit
/// floats, striped or tiled. Georeferencing, in order of preference:
/// ModelTransformation (34264; rotation or shear is refused), else
/// ModelPixelScale (33550) with a single ModelTiepoint (33922), else none
/// (1 m pixels at the origin). When the GeoKeyDirectory's GTRasterTypeGeoKey
/// (1025) is PixelIsPoint (2), the tiepoint is a pixel centre and the origin
/// is moved half a pixel up and left to the pixel-corner convention of
/// [`GeoRef`], as GDAL does. GeoKeyDirectory, GeoDoubleParams and
/// GeoAsciiParams are kept raw; `geographic` is GTModelTypeGeoKey (1024) ==
/// 2. GDAL_NODATA (42113) sets `nodata` and those samples become NaN (a
/// nodata within 1e-6 of ±f32::MAX, as GDAL writes it in text, matches
/// ±f32::MAX in float32 data as well as the value rounded to float32). A
/// strip or tile stored as no bytes (GDAL's `SPARSE_OK` files) is no data,
/// or zero where there is no nodata value, as GDAL reads it. A band scale and offset in GDAL_METADATA (42112) are
/// applied (`height = sample × scale + offset`, as `gdal_translate
/// -unscale`); cells that GDAL's mask of valid cells (an image inside the
/// file, or `<file>.msk` beside it) marks invalid are no data
/// (see `io/gdal_mask.rs`); a raster stored south-up or east-to-west is turned north-up
/// ([`Dem::north_up`]).
pub fn read_geotiff(path: impl AsRef<Path>) -> Result<Dem, DemError> {
    let path = path.as_ref();
    let mut file = File::open(path).map_err(|e| DemError::open(path, &e))?;
    let header = TiffHeader::read(path, &file)?;
    let (ifd_at, little_endian) = (header.first_ifd, header.little_endian);
    let strips_file = file.try_clone().map_err(|e| DemError::open(path, &e))?;
    file.seek(SeekFrom::Start(0))
        .map_err(|e| DemError::at_byte(path, 0, format!("seek failed: {e}")))?;
    let limits = {
        let mut l = Limits::default();
        l.decoding_buffer_size = MAX_SAMPLES * 8;
        l.ifd_value_size = 16 << 20;
        l
    };
    let mut dec = Decoder::new(BufReader::new(file))
        .map_err(|e| DemError::at_byte(path, ifd_at, format!("unreadable first IFD: {e}")))?
        .with_limits(limits);

    let (w, h) = dec
        .dimensions()
        .map_err(|e| DemError::new(path, "tag 256", format!("no usable image size: {e}")))?;
    let (width, height) = (w as usize, h as usize);
    check_dimensions(path, "tag 256", width, height)?;
    let spp = unsigned(path, &mut dec, Tag::SamplesPerPixel)?.unwrap_or(1);
    if spp != 1 {
        return Err(DemError::new(
            path,
            "tag 277",
            format!("{spp} samples per pixel; expected a single band"),
        ));
    }
    let bits = unsigned(path, &mut dec, Tag::BitsPerSample)?.unwrap_or(1);
    let format = unsigned(path, &mut dec, Tag::SampleFormat)?.unwrap_or(1);
    let supported = match format {
        1 | 2 => matches!(bits, 8 | 16 | 32),
        3 => matches!(bits, 32 | 64),
        _ => false,
    };
    if !supported {
        let kind = match format {
            1 => "unsigned integer",
            2 => "signed integer",
            3 => "float",
            5 => "complex integer",
            6 => "complex float",
            _ => "unknown",
        };
        return Err(DemError::new(
            path,
            "tag 339",
            format!(
                "{bits}-bit {kind} samples (SampleFormat {format}); expected 8/16/32-bit \
                 unsigned or signed integers or 32/64-bit floats"
            ),
        ));
    }

    // TIFF 6.0 makes tile sides multiples of 16; a file that breaks the
    // rule has a layout no reader agrees on.
    for tag in [Tag::TileWidth, Tag::TileLength] {
        if let Some(side) = unsigned(path, &mut dec, tag)? {
            if side == 0 || side % 16 != 0 {
                return Err(DemError::new(
                    path,
                    format!("tag {}", tag.to_u16()),
                    format!("tile side {side} is not a positive multiple of 16 (TIFF 6.0)"),
                ));
            }
        }
    }

    if let Some(code) = unsigned(path, &mut dec, Tag::Compression)? {
        if let Some(name) = unsupported_compression(code) {
            return Err(DemError::new(
                path,
                "tag 259",
                format!(
                    "{name} compression (code {code}) is not supported; convert with \
                     `gdal_translate -co COMPRESS=DEFLATE IN OUT` (or ZSTD, LZW)"
                ),
            ));
        }
    }
    let georef = read_georef(path, &mut dec)?;
    let nodata = match find(path, &mut dec, TAG_GDAL_NODATA)? {
        None => None,
        Some(v) => {
            let s = v
                .into_string()
                .map_err(|e| tag_err(path, TAG_GDAL_NODATA, e))?;
            let t = s.trim_matches(|c: char| c.is_whitespace() || c == '\0');
            Some(t.parse::<f64>().map_err(|_| {
                DemError::new(
                    path,
                    format!("tag {TAG_GDAL_NODATA}"),
                    format!("GDAL_NODATA is {s:?}; expected a number"),
                )
            })?)
        }
    };
    let (scale, offset) = match find(path, &mut dec, TAG_GDAL_METADATA)? {
        None => (1.0, 0.0),
        Some(v) => {
            let xml = v
                .into_string()
                .map_err(|e| tag_err(path, TAG_GDAL_METADATA, e))?;
            band_scale_offset(&xml).map_err(|bad| {
                DemError::new(
                    path,
                    format!("tag {TAG_GDAL_METADATA}"),
                    format!("the band's scale or offset is {bad:?}; expected a finite number"),
                )
            })?
        }
    };

    let plain = little_endian && cfg!(target_endian = "little") && bits == 32 && format == 3;
    let absent = absent_height(nodata);
    let mut heights = match plain
        .then(|| plain_strips(path, &mut dec, &strips_file, (width, height), absent))
        .transpose()?
        .flatten()
    {
        Some(mut heights) => {
            if let Some(nd) = nodata.filter(|nd| !nd.is_nan()) {
                let nd32 = NodataF32::new(nd);
                use rayon::prelude::*;
                heights.par_iter_mut().for_each(|s| {
                    if nd32.matches(*s) {
                        *s = f32::NAN
                    }
                });
            }
            heights
        }
        None => {
            // The decoded samples and the heights made from them.
            ensure_room(path, "tag 256", width, height, bits as usize / 8 + 4)?;
            let samples = TileSamples {
                bits: bits as u16,
                format: format as u16,
                predictor: unsigned(path, &mut dec, Tag::Predictor)?.unwrap_or(1) as u16,
                little_endian,
            };
            if let Some((offsets, counts, tile)) = lzw_tile_layout(path, &mut dec, samples)? {
                let layout = TileLayout {
                    offsets: &offsets,
                    counts: &counts,
                    tile,
                };
                read_lzw_tiles(
                    path,
                    &strips_file,
                    &layout,
                    (width, height),
                    samples,
                    absent,
                    |data| to_heights(data, nodata),
                )?
            } else {
                match block_byte_counts(path, &mut dec)? {
                    Some(counts) if counts.contains(&0) => {
                        read_sparse(path, &mut dec, &counts, (width, height), nodata, to_heights)?
                    }
                    _ => {
                        let data = dec.read_image().map_err(|e| {
                            DemError::new(path, "image data", format!("cannot decode samples: {e}"))
                        })?;
                        to_heights(data, nodata)
                    }
                }
            }
        }
    };
    if heights.len() != width * height {
        return Err(DemError::new(
            path,
            "image data",
            format!(
                "decoded {} samples; expected {width}×{height}",
                heights.len()
            ),
        ));
    }
    apply_gdal_mask(
        path,
        &strips_file,
        header,
        &mut dec,
        &mut heights,
        (width, height),
    )?;
    if (scale, offset) != (1.0, 0.0) {
        use rayon::prelude::*;
        heights
            .par_iter_mut()
            .for_each(|h| *h = (*h as f64 * scale + offset) as f32);
    }
    Ok(Dem {
        width,
        height,
        heights,
        nodata,
        georef,
    }
    .north_up())
}

/// The tiles' offsets, byte counts and size when the image is LZW-compressed
/// tiles that [`read_lzw_tiles`] decodes: a predictor it knows and tiles of
/// at most 2²⁴ samples; none otherwise, for the `tiff` crate to decode (or
/// refuse).
#[allow(clippy::type_complexity)]
fn lzw_tile_layout<R: Read + Seek>(
    path: &Path,
    dec: &mut Decoder<R>,
    samples: TileSamples,
) -> Result<Option<(Vec<u64>, Vec<u64>, (usize, usize))>, DemError> {
    if unsigned(path, dec, Tag::Compression)? != Some(5) || !(1..=3).contains(&samples.predictor) {
        return Ok(None);
    }
    let (Some(tw), Some(th)) = (
        unsigned(path, dec, Tag::TileWidth)?,
        unsigned(path, dec, Tag::TileLength)?,
    ) else {
        return Ok(None);
    };
    if tw.saturating_mul(th) > 1 << 24 {
        return Ok(None);
    }
    let list = |dec: &mut Decoder<R>, tag: Tag| match find(path, dec, tag.to_u16())? {
        None => Err(DemError::new(
            path,
            format!("tag {}", tag.to_u16()),
            "missing; a tiled image lists its tiles there",
        )),
        Some(v) => v.into_u64_vec().map_err(|e| tag_err(path, tag.to_u16(), e)),
    };
    let offsets = list(dec, Tag::TileOffsets)?;
    let counts = list(dec, Tag::TileByteCounts)?;
    Ok(Some((offsets, counts, (tw as usize, th as usize))))
}

/// The name of a compression GDAL writes that the `tiff` crate does not
/// decode; none for the ones it does (and for codes no writer uses, which
/// the decoder reports itself).
fn unsupported_compression(code: u64) -> Option<&'static str> {
    Some(match code {
        34712 => "JPEG 2000",
        34887 => "LERC",
        34925 => "LZMA",
        50001 => "WebP",
        50002 => "JPEG XL",
        _ => return None,
    })
}

/// The samples of an image of 32-bit floats in the machine's byte order,
/// stored as uncompressed strips in one plane (gdalwarp's and
/// gdal_translate's default layout), read from `file` straight into place,
/// the strips in parallel; none for any other layout, which the `tiff`
/// crate decodes. A strip stored as no bytes (GDAL's sparse files) is
/// `absent` throughout. A strip that the file ends inside is an error
/// naming its offset.
fn plain_strips<R: Read + Seek>(
    path: &Path,
    dec: &mut Decoder<R>,
    file: &File,
    (width, height): (usize, usize),
    absent: f32,
) -> Result<Option<Vec<f32>>, DemError> {
    // No compression, no predictor, one plane: each tag absent or 1.
    let plain = |dec: &mut Decoder<R>, tag: Tag| {
        Ok::<_, DemError>(unsigned(path, dec, tag)?.unwrap_or(1) == 1)
    };
    if !plain(dec, Tag::Compression)?
        || !plain(dec, Tag::Predictor)?
        || !plain(dec, Tag::PlanarConfiguration)?
        || find(path, dec, Tag::TileWidth.to_u16())?.is_some()
    {
        return Ok(None);
    }
    let list = |dec: &mut Decoder<R>, tag: Tag| match find(path, dec, tag.to_u16())? {
        None => Ok(None),
        Some(v) => v
            .into_u64_vec()
            .map(Some)
            .map_err(|e| tag_err(path, tag.to_u16(), e)),
    };
    let (Some(offsets), Some(counts)) = (
        list(dec, Tag::StripOffsets)?,
        list(dec, Tag::StripByteCounts)?,
    ) else {
        return Ok(None);
    };
    let rows = unsigned(path, dec, Tag::RowsPerStrip)?
        .unwrap_or(height as u64)
        .clamp(1, height as u64) as usize;
    let strip = rows * width;
    let strips = height.div_ceil(rows);
    let fits = offsets.len() == strips
        && counts.len() == strips
        && (0..strips).all(|k| {
            counts[k] == 0 || counts[k] >= 4 * (strip.min(width * height - k * strip)) as u64
        });
    if !fits {
        return Ok(None);
    }
    let mut heights = zeroed_heights(path, "tag 256", width, height)?;
    use rayon::prelude::*;
    heights
        .par_chunks_mut(strip)
        .zip(offsets.par_iter().zip(counts.par_iter()))
        .try_for_each(|(samples, (&at, &count))| {
            if count == 0 {
                samples.fill(absent);
                return Ok(());
            }
            // SAFETY: any four bytes are a valid f32, and the byte view
            // covers exactly the samples' memory.
            let bytes = unsafe {
                std::slice::from_raw_parts_mut(samples.as_mut_ptr().cast::<u8>(), 4 * samples.len())
            };
            read_at(file, bytes, at).map_err(|e| {
                DemError::at_byte(path, at, format!("cannot read the strip there: {e}"))
            })
        })?;
    Ok(Some(heights))
}

fn tag_err(path: &Path, tag: u16, e: impl std::fmt::Display) -> DemError {
    DemError::new(path, format!("tag {tag}"), format!("unreadable value: {e}"))
}

fn find<R: Read + std::io::Seek>(
    path: &Path,
    dec: &mut Decoder<R>,
    tag: u16,
) -> Result<Option<Value>, DemError> {
    dec.find_tag(Tag::from_u16_exhaustive(tag))
        .map_err(|e| tag_err(path, tag, e))
}

/// First value of an unsigned tag (BitsPerSample may repeat per sample).
fn unsigned<R: Read + std::io::Seek>(
    path: &Path,
    dec: &mut Decoder<R>,
    tag: Tag,
) -> Result<Option<u64>, DemError> {
    let id = tag.to_u16();
    match dec.find_tag(tag).map_err(|e| tag_err(path, id, e))? {
        None => Ok(None),
        Some(v) => {
            let v = v.into_u64_vec().map_err(|e| tag_err(path, id, e))?;
            Ok(v.first().copied())
        }
    }
}

fn f64s<R: Read + std::io::Seek>(
    path: &Path,
    dec: &mut Decoder<R>,
    tag: u16,
) -> Result<Option<Vec<f64>>, DemError> {
    match find(path, dec, tag)? {
        None => Ok(None),
        Some(v) => Ok(Some(v.into_f64_vec().map_err(|e| tag_err(path, tag, e))?)),
    }
}

fn read_georef<R: Read + std::io::Seek>(
    path: &Path,
    dec: &mut Decoder<R>,
) -> Result<GeoRef, DemError> {
    let geo_keys = match find(path, dec, TAG_GEO_KEY_DIRECTORY)? {
        None => Vec::new(),
        Some(v) => v
            .into_u16_vec()
            .map_err(|e| tag_err(path, TAG_GEO_KEY_DIRECTORY, e))?,
    };
    validate_geo_keys(&geo_keys)
        .map_err(|m| DemError::new(path, format!("tag {TAG_GEO_KEY_DIRECTORY}"), m))?;
    let geo_doubles = f64s(path, dec, TAG_GEO_DOUBLE_PARAMS)?.unwrap_or_default();
    let geo_ascii = match find(path, dec, TAG_GEO_ASCII_PARAMS)? {
        None => String::new(),
        Some(v) => v
            .into_string()
            .map_err(|e| tag_err(path, TAG_GEO_ASCII_PARAMS, e))?,
    };
    let scale = f64s(path, dec, TAG_MODEL_PIXEL_SCALE)?;
    let tie = f64s(path, dec, TAG_MODEL_TIEPOINT)?;
    let transform = f64s(path, dec, TAG_MODEL_TRANSFORMATION)?;
    let bad = |tag: u16, m: String| DemError::new(path, format!("tag {tag}"), m);

    let placed = if let Some(m) = transform {
        let t = TAG_MODEL_TRANSFORMATION;
        if m.len() != 16 {
            return Err(bad(
                t,
                format!("{} values; expected a 4×4 matrix (16)", m.len()),
            ));
        }
        if m[1] != 0.0 || m[4] != 0.0 {
            return Err(bad(
                t,
                format!(
                    "rotated or sheared raster (terms {} and {}); expected a north-up \
                     transformation with zero rotation terms",
                    m[1], m[4]
                ),
            ));
        }
        Some((m[3], m[7], m[0], m[5], t))
    } else {
        match (scale, tie) {
            (Some(s), Some(t)) => {
                if s.len() < 2 {
                    return Err(bad(
                        TAG_MODEL_PIXEL_SCALE,
                        format!("{} values; expected 3 (x, y, z scale)", s.len()),
                    ));
                }
                if t.len() != 6 {
                    return Err(bad(
                        TAG_MODEL_TIEPOINT,
                        format!(
                            "{} values; expected one tiepoint (6 values) with ModelPixelScale \
                             (several tiepoints, i.e. ground control points, are not supported)",
                            t.len()
                        ),
                    ));
                }
                Some((
                    t[3] - t[0] * s[0],
                    t[4] + t[1] * s[1],
                    s[0],
                    -s[1],
                    TAG_MODEL_PIXEL_SCALE,
                ))
            }
            (Some(_), None) => {
                return Err(bad(
                    TAG_MODEL_PIXEL_SCALE,
                    "ModelPixelScale without ModelTiepoint; expected both".into(),
                ))
            }
            (None, Some(_)) => {
                return Err(bad(
                    TAG_MODEL_TIEPOINT,
                    "ModelTiepoint without ModelPixelScale (ground control points are not \
                     supported); expected both, or ModelTransformation"
                        .into(),
                ))
            }
            (None, None) => None,
        }
    };
    let (mut ox, mut oy, pw, ph) = match placed {
        None => (0.0, 0.0, 1.0, -1.0),
        Some((ox, oy, pw, ph, tag)) => {
            let all = [ox, oy, pw, ph];
            if all.iter().any(|v| !v.is_finite()) || pw == 0.0 || ph == 0.0 {
                return Err(bad(
                    tag,
                    format!(
                        "origin ({ox}, {oy}), pixel size ({pw}, {ph}); expected finite values \
                         and a nonzero pixel size"
                    ),
                ));
            }
            (ox, oy, pw, ph)
        }
    };
    if placed.is_some() && geo_key_short(&geo_keys, KEY_RASTER_TYPE) == Some(2) {
        // PixelIsPoint: the model point is the pixel centre.
        ox -= 0.5 * pw;
        oy -= 0.5 * ph;
    }
    // A coordinate system the GeoKeys do not declare may be in GDAL's
    // sidecar, as this crate writes it for ASCII grids' `.prj`.
    let crs_wkt = (!declares_crs(&geo_keys))
        .then(|| read_crs_sidecar(path))
        .flatten();
    let geographic = match geo_key_short(&geo_keys, KEY_MODEL_TYPE) {
        Some(model) => model == 2,
        None => crs_wkt.as_deref().is_some_and(wkt_is_geographic),
    };
    Ok(GeoRef {
        origin_x: ox,
        origin_y: oy,
        pixel_width: pw,
        pixel_height: ph,
        geographic,
        geo_keys,
        geo_doubles,
        geo_ascii,
        crs_wkt,
    })
}

/// Converts decoded samples to heights, nodata samples to NaN.
fn to_heights(data: DecodingResult, nodata: Option<f64>) -> Vec<f32> {
    fn ints<T: Copy + Into<f64>>(v: Vec<T>, nodata: Option<f64>) -> Vec<f32> {
        v.into_iter()
            .map(|s| {
                let x: f64 = s.into();
                if Some(x) == nodata {
                    f32::NAN
                } else {
                    x as f32
                }
            })
            .collect()
    }
    match data {
        DecodingResult::F32(mut v) => {
            if let Some(nd) = nodata.filter(|nd| !nd.is_nan()) {
                let nd32 = NodataF32::new(nd);
                for s in &mut v {
                    if nd32.matches(*s) {
                        *s = f32::NAN;
                    }
                }
            }
            v
        }
        DecodingResult::F64(v) => v
            .into_iter()
            .map(|s| {
                if Some(s) == nodata {
                    f32::NAN
                } else {
                    s as f32
                }
            })
            .collect(),
        DecodingResult::U8(v) => ints(v, nodata),
        DecodingResult::U16(v) => ints(v, nodata),
        DecodingResult::U32(v) => ints(v, nodata),
        DecodingResult::I8(v) => ints(v, nodata),
        DecodingResult::I16(v) => ints(v, nodata),
        DecodingResult::I32(v) => ints(v, nodata),
        // Excluded by the SampleFormat/BitsPerSample check before decoding.
        _ => Vec::new(),
    }
}
