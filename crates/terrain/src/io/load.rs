//! Loading a DEM of any supported format, chosen by the file extension.

use std::path::Path;

use super::{
    read_ascii_grid, read_geotiff, read_hgt, read_png, read_raw, read_ter, DemError, RawType,
};
use crate::dem::Dem;

/// The extensions [`load_dem`] understands.
pub const SUPPORTED_EXTENSIONS: &str =
    ".tif/.tiff (GeoTIFF), .asc (Esri ASCII grid), .hgt (SRTM), .ter (Terragen), \
     .png (grayscale), .raw/.bin/.r16/.r32 (raw samples)";

/// Size and sample type of a raw height file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RawSpec {
    /// Samples per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Sample type.
    pub sample: RawType,
}

/// Format parameters that a file cannot carry itself.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadOptions {
    /// Size and type of `.raw`/`.bin`/`.r16`/`.r32` files. Required for
    /// `.raw` and `.bin`; when absent, `.r16` is read as a square of
    /// little-endian u16 and `.r32` as a square of little-endian f32, the
    /// side taken from the file size.
    pub raw: Option<RawSpec>,
    /// PNG height = sample × `png_scale` + `png_offset` (default 1).
    pub png_scale: f64,
    /// See `png_scale` (default 0).
    pub png_offset: f64,
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions {
            raw: None,
            png_scale: 1.0,
            png_offset: 0.0,
        }
    }
}

/// Loads a DEM, choosing the reader by extension (case-insensitive): see
/// [`SUPPORTED_EXTENSIONS`]. An unknown extension is an error listing the
/// supported ones.
pub fn load_dem(path: impl AsRef<Path>, options: &LoadOptions) -> Result<Dem, DemError> {
    let path = path.as_ref();
    let dem = read_any(path, options)?;
    if let Some((col, row, h)) = dem.first_unusable() {
        return Err(DemError::new(
            path,
            format!("row {row}, column {col}"),
            crate::dem::unusable_height(h),
        ));
    }
    Ok(dem)
}

/// [`load_dem`]'s reader for the extension, without the check of the heights.
fn read_any(path: &Path, options: &LoadOptions) -> Result<Dem, DemError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "tif" | "tiff" => read_geotiff(path),
        "asc" => read_ascii_grid(path),
        "hgt" => read_hgt(path),
        "ter" => read_ter(path),
        "png" => read_png(path, options.png_scale, options.png_offset),
        "raw" | "bin" | "r16" | "r32" => {
            let spec =
                match (options.raw, ext.as_str()) {
                    (Some(spec), _) => spec,
                    (None, "r16") => square_raw(path, RawType::U16Le)?,
                    (None, "r32") => square_raw(path, RawType::F32Le)?,
                    (None, _) => return Err(DemError::new(
                        path,
                        "file name",
                        "a .raw or .bin grid carries no size or sample type; name a square grid \
                         of 16-bit samples .r16 or of 32-bit floats .r32 (its side follows from \
                         its size), convert it to GeoTIFF (gdal_translate), or, from the library, \
                         give LoadOptions::raw",
                    )),
                };
            read_raw(path, spec.width, spec.height, spec.sample)
        }
        _ => Err(DemError::new(
            path,
            "file name",
            format!("unknown extension {ext:?}; expected one of {SUPPORTED_EXTENSIONS}"),
        )),
    }
}

/// A square raw grid of `sample`s whose side follows from the file size.
fn square_raw(path: &Path, sample: RawType) -> Result<RawSpec, DemError> {
    let len = std::fs::metadata(path)
        .map_err(|e| DemError::open(path, &e))?
        .len();
    let samples = len / sample.bytes() as u64;
    let n = (samples as f64).sqrt().round() as u64;
    if n == 0 || n * n * sample.bytes() as u64 != len {
        return Err(DemError::at_byte(
            path,
            len,
            format!(
                "file is {len} bytes, not a square of {} samples; convert it to GeoTIFF \
                 (gdal_translate), or, from the library, give its size with LoadOptions::raw",
                sample.name()
            ),
        ));
    }
    Ok(RawSpec {
        width: n as usize,
        height: n as usize,
        sample,
    })
}
