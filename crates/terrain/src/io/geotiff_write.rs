//! GeoTIFF output: one band of `u8` or `f32` samples in strips or tiles,
//! uncompressed or compressed ([`GeoTiffLayout`]), georeferenced with
//! ModelPixelScale + ModelTiepoint (PixelIsArea) and the raw geokey tags,
//! written atomically.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use tiff::encoder::colortype::{ColorType, Gray32Float, Gray8};
use tiff::encoder::{
    DirectoryEncoder, TiffEncoder, TiffKind, TiffKindBig, TiffKindStandard, TiffValue,
};
use tiff::tags::Tag;

use super::crs_sidecar::{remove_crs_sidecar, write_crs_sidecar};
use super::geokeys::{declares_crs, set_geo_key_short, validate_geo_keys, KEY_RASTER_TYPE};
use super::geotiff_blocks::{write_strips, write_tiles, TileSample};
use super::geotiff_layout::{GeoTiffLayout, TiffCompression};
use super::geotiff_read::{
    TAG_GDAL_NODATA, TAG_GEO_ASCII_PARAMS, TAG_GEO_DOUBLE_PARAMS, TAG_GEO_KEY_DIRECTORY,
    TAG_MODEL_PIXEL_SCALE, TAG_MODEL_TIEPOINT,
};
use super::limits::check_dimensions;
use super::nodata::{nodata_as_f32, nodata_text};
use super::DemError;
use crate::dem::{Dem, GeoRef};

/// Above this many bytes of samples the file is written as BigTIFF.
const BIG_TIFF_BYTES: u64 = (1 << 32) - (1 << 26);

/// Writes `width` × `height` bytes (rows from the top) as a single-band
/// 8-bit GeoTIFF in uncompressed strips; see [`write_geotiff_f32`] for the
/// georeferencing. A `nodata` must be a whole number in 0..=255.
pub fn write_geotiff_u8(
    path: impl AsRef<Path>,
    width: usize,
    height: usize,
    data: &[u8],
    georef: &GeoRef,
    nodata: Option<f64>,
) -> Result<(), DemError> {
    write_geotiff_u8_with(
        path,
        width,
        height,
        data,
        georef,
        nodata,
        &GeoTiffLayout::default(),
    )
}

/// [`write_geotiff_u8`] with the strips or tiles and the compression of
/// `layout`; the padding of edge tiles is `nodata` (else 0).
pub fn write_geotiff_u8_with(
    path: impl AsRef<Path>,
    width: usize,
    height: usize,
    data: &[u8],
    georef: &GeoRef,
    nodata: Option<f64>,
    layout: &GeoTiffLayout,
) -> Result<(), DemError> {
    let path = path.as_ref();
    if let Some(nd) = nodata {
        if !(nd.fract() == 0.0 && (0.0..=255.0).contains(&nd)) {
            return Err(DemError::new(
                path,
                format!("tag {TAG_GDAL_NODATA}"),
                format!("nodata {nd} is not a u8 sample; expected a whole number in 0..=255"),
            ));
        }
    }
    let pad = nodata.map_or(0, |nd| nd as u8);
    write::<Gray8>(
        path,
        width,
        height,
        data,
        georef,
        nodata,
        layout,
        pad,
        |s| s,
    )
}

/// Writes `width` × `height` heights (rows from the top) as a single-band
/// float32 GeoTIFF, atomically (temporary file in the same folder, renamed
/// at the end).
///
/// Georeferencing: ModelPixelScale (`pixel_width`, `-pixel_height`, 0) and
/// one ModelTiepoint from pixel (0, 0) to the origin, with GTRasterTypeGeoKey
/// PixelIsArea: `georef.geo_keys` is written as given except that a
/// PixelIsPoint raster type is changed to PixelIsArea (the origin is already
/// the pixel corner); empty `geo_keys` become a minimal directory (model
/// type projected or geographic, PixelIsArea), and a coordinate system
/// known only as WKT (`georef.crs_wkt`, when the GeoKeys declare none) is
/// written beside the file in GDAL's `.aux.xml` ([`write_crs_sidecar`]);
/// otherwise an `.aux.xml` left there by an earlier file of that name is
/// removed. GeoDoubleParams and
/// GeoAsciiParams are written when non-empty, GDAL_NODATA when `nodata` is
/// given, and then NaN samples are written as the nodata value. Files over
/// about 4 GiB are BigTIFF. Samples are written in uncompressed strips
/// ([`write_geotiff_f32_with`] takes a layout).
pub fn write_geotiff_f32(
    path: impl AsRef<Path>,
    width: usize,
    height: usize,
    data: &[f32],
    georef: &GeoRef,
    nodata: Option<f64>,
) -> Result<(), DemError> {
    write_geotiff_f32_with(
        path,
        width,
        height,
        data,
        georef,
        nodata,
        &GeoTiffLayout::default(),
    )
}

/// [`write_geotiff_f32`] with the strips or tiles and the compression of
/// `layout`; the padding of edge tiles is the nodata value (else NaN).
pub fn write_geotiff_f32_with(
    path: impl AsRef<Path>,
    width: usize,
    height: usize,
    data: &[f32],
    georef: &GeoRef,
    nodata: Option<f64>,
    layout: &GeoTiffLayout,
) -> Result<(), DemError> {
    let path = path.as_ref();
    let fill = match nodata {
        Some(nd) if !nd.is_nan() => {
            let f = nodata_as_f32(nd);
            if !f.is_finite() {
                return Err(DemError::new(
                    path,
                    format!("tag {TAG_GDAL_NODATA}"),
                    format!("nodata {nd} is not a finite float32; expected a float32 value"),
                ));
            }
            Some(f)
        }
        _ => None,
    };
    match fill {
        Some(f) => {
            write::<Gray32Float>(path, width, height, data, georef, nodata, layout, f, |s| {
                if s.is_nan() {
                    f
                } else {
                    s
                }
            })
        }
        None => write::<Gray32Float>(
            path,
            width,
            height,
            data,
            georef,
            nodata,
            layout,
            f32::NAN,
            |s| s,
        ),
    }
}

/// Writes a DEM's heights, georeferencing and nodata with
/// [`write_geotiff_f32`].
pub fn write_dem_geotiff(path: impl AsRef<Path>, dem: &Dem) -> Result<(), DemError> {
    write_geotiff_f32(
        path,
        dem.width,
        dem.height,
        &dem.heights,
        &dem.georef,
        dem.nodata,
    )
}

#[allow(clippy::too_many_arguments)]
fn write<C>(
    path: &Path,
    width: usize,
    height: usize,
    data: &[C::Inner],
    georef: &GeoRef,
    nodata: Option<f64>,
    layout: &GeoTiffLayout,
    pad: C::Inner,
    fix: impl Fn(C::Inner) -> C::Inner + Sync,
) -> Result<(), DemError>
where
    C: ColorType,
    C::Inner: TileSample + Sync,
    [C::Inner]: TiffValue,
{
    check_dimensions(path, "arguments", width, height)?;
    layout
        .check()
        .map_err(|m| DemError::new(path, "tile size", m))?;
    if data.len() != width * height {
        return Err(DemError::new(
            path,
            "arguments",
            format!("{} samples given; expected {width}×{height}", data.len()),
        ));
    }
    let g = georef;
    if ![g.origin_x, g.origin_y, g.pixel_width, g.pixel_height]
        .iter()
        .all(|v| v.is_finite())
        || g.pixel_width == 0.0
        || g.pixel_height == 0.0
    {
        return Err(DemError::new(
            path,
            format!("tag {TAG_MODEL_PIXEL_SCALE}"),
            format!(
                "origin ({}, {}), pixel size ({}, {}); expected finite values and a nonzero \
                 pixel size",
                g.origin_x, g.origin_y, g.pixel_width, g.pixel_height
            ),
        ));
    }
    let mut keys = if g.geo_keys.is_empty() {
        let model = if g.geographic { 2 } else { 1 };
        vec![1, 1, 0, 2, 1024, 0, 1, model, KEY_RASTER_TYPE, 0, 1, 1]
    } else {
        g.geo_keys.clone()
    };
    validate_geo_keys(&keys)
        .map_err(|m| DemError::new(path, format!("tag {TAG_GEO_KEY_DIRECTORY}"), m))?;
    set_geo_key_short(&mut keys, KEY_RASTER_TYPE, 1);
    if !g.geo_ascii.is_ascii() || g.geo_ascii.contains('\0') {
        return Err(DemError::new(
            path,
            format!("tag {TAG_GEO_ASCII_PARAMS}"),
            "GeoAsciiParams must be ASCII without NUL characters",
        ));
    }
    let tags = Tags {
        scale: [g.pixel_width, -g.pixel_height, 0.0],
        tie: [0.0, 0.0, 0.0, g.origin_x, g.origin_y, 0.0],
        keys,
        doubles: &g.geo_doubles,
        ascii: &g.geo_ascii,
        nodata: nodata.map(nodata_text),
    };
    let bytes = data.len() as u64 * std::mem::size_of::<C::Inner>() as u64;
    let image = Image {
        width,
        height,
        data,
        layout,
        pad,
    };
    raykit_io::write_atomic_file(
        path,
        |w| {
            if bytes > BIG_TIFF_BYTES {
                encode::<C, TiffKindBig>(path, w, &image, &tags, &fix)
            } else {
                encode::<C, TiffKindStandard>(path, w, &image, &tags, &fix)
            }
        },
        |e| DemError::new(path, "write", e.to_string()),
    )?;
    // A coordinate system the GeoKeys do not hold goes beside the file; a
    // sidecar left from an earlier file of that name goes.
    match &g.crs_wkt {
        Some(wkt) if !declares_crs(&g.geo_keys) => write_crs_sidecar(path, wkt),
        _ => remove_crs_sidecar(path),
    }
}

/// The georeferencing tags to write.
struct Tags<'a> {
    scale: [f64; 3],
    tie: [f64; 6],
    keys: Vec<u16>,
    doubles: &'a [f64],
    ascii: &'a str,
    nodata: Option<String>,
}

/// The samples to write and how.
struct Image<'a, T> {
    width: usize,
    height: usize,
    data: &'a [T],
    layout: &'a GeoTiffLayout,
    /// The sample that pads the edge tiles.
    pad: T,
}

fn encode<C, K>(
    path: &Path,
    w: &mut BufWriter<File>,
    image: &Image<C::Inner>,
    tags: &Tags,
    fix: &(impl Fn(C::Inner) -> C::Inner + Sync),
) -> Result<(), DemError>
where
    C: ColorType,
    C::Inner: TileSample + Sync,
    [C::Inner]: TiffValue,
    K: TiffKind,
{
    let err = |at: &str| {
        let at = at.to_string();
        move |e: tiff::TiffError| DemError::new(path, at.clone(), format!("cannot write: {e}"))
    };
    let (width, height, data) = (image.width, image.height, image.data);
    let compression = image.layout.compression;
    let mut enc = TiffEncoder::<_, K>::new_generic(w).map_err(err("header"))?;
    if image.layout.tile.is_some() || compression != TiffCompression::None {
        let mut d = enc.image_directory().map_err(err("image directory"))?;
        match image.layout.tile {
            Some(tile) => write_tiles::<_, K, C>(
                &mut d,
                width,
                height,
                data,
                tile,
                compression,
                image.pad,
                fix,
            )
            .map_err(err("tiles"))?,
            None => write_strips::<_, K, C>(&mut d, width, height, data, compression, fix)
                .map_err(err("strips"))?,
        }
        write_geo_tags(path, &mut d, tags)?;
        return d.finish().map_err(err("image directory"));
    }
    let mut img = enc
        .new_image::<C>(width as u32, height as u32)
        .map_err(err("image directory"))?;
    write_geo_tags(path, img.encoder(), tags)?;
    let mut start = 0;
    let mut strip = Vec::new();
    while img.next_strip_sample_count() > 0 {
        let n = img.next_strip_sample_count() as usize;
        strip.clear();
        strip.extend(data[start..start + n].iter().map(|&s| fix(s)));
        img.write_strip(&strip).map_err(err("image data"))?;
        start += n;
    }
    img.finish().map_err(err("image directory"))?;
    Ok(())
}

/// The georeferencing and nodata tags.
fn write_geo_tags<W, K>(
    path: &Path,
    d: &mut DirectoryEncoder<'_, W, K>,
    tags: &Tags,
) -> Result<(), DemError>
where
    W: std::io::Write + std::io::Seek,
    K: TiffKind,
{
    let err = |at: String| {
        move |e: tiff::TiffError| DemError::new(path, at.clone(), format!("cannot write: {e}"))
    };
    let tag = |t: u16| Tag::from_u16_exhaustive(t);
    let at = |t: u16| format!("tag {t}");
    d.write_tag(tag(TAG_MODEL_PIXEL_SCALE), &tags.scale[..])
        .map_err(err(at(TAG_MODEL_PIXEL_SCALE)))?;
    d.write_tag(tag(TAG_MODEL_TIEPOINT), &tags.tie[..])
        .map_err(err(at(TAG_MODEL_TIEPOINT)))?;
    d.write_tag(tag(TAG_GEO_KEY_DIRECTORY), &tags.keys[..])
        .map_err(err(at(TAG_GEO_KEY_DIRECTORY)))?;
    if !tags.doubles.is_empty() {
        d.write_tag(tag(TAG_GEO_DOUBLE_PARAMS), tags.doubles)
            .map_err(err(at(TAG_GEO_DOUBLE_PARAMS)))?;
    }
    if !tags.ascii.is_empty() {
        d.write_tag(tag(TAG_GEO_ASCII_PARAMS), tags.ascii)
            .map_err(err(at(TAG_GEO_ASCII_PARAMS)))?;
    }
    if let Some(nd) = &tags.nodata {
        d.write_tag(tag(TAG_GDAL_NODATA), nd.as_str())
            .map_err(err(at(TAG_GDAL_NODATA)))?;
    }
    Ok(())
}
