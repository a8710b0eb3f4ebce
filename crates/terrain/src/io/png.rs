//! Grayscale PNG height maps: one 16-bit (or 8-bit) gray channel, heights
//! `sample × scale + offset`, rows from the top (north).

use std::path::Path;

use image::{ColorType, DynamicImage, ImageDecoder, ImageReader, Limits};

use super::limits::{check_dimensions, ensure_room, MAX_SAMPLES, MAX_SIDE};
use super::DemError;
use crate::dem::Dem;

/// Reads a grayscale PNG height map: height = sample × `scale` + `offset`
/// (16-bit samples 0..65535, 8-bit ones 0..255). Colour or alpha images
/// are refused rather than guessed at. Georeferencing is the identity with
/// 1 m pixels; no nodata.
pub fn read_png(path: impl AsRef<Path>, scale: f64, offset: f64) -> Result<Dem, DemError> {
    let path = path.as_ref();
    let mut reader = ImageReader::open(path).map_err(|e| DemError::open(path, &e))?;
    reader.set_format(image::ImageFormat::Png);
    let mut limits = Limits::default();
    limits.max_image_width = Some(MAX_SIDE as u32);
    limits.max_image_height = Some(MAX_SIDE as u32);
    limits.max_alloc = Some(MAX_SAMPLES as u64 * 2 + (1 << 20));
    reader.limits(limits);
    let decoder = reader
        .into_decoder()
        .map_err(|e| DemError::new(path, "PNG header", format!("not a readable PNG: {e}")))?;
    let (w, h) = decoder.dimensions();
    check_dimensions(path, "PNG header", w as usize, h as usize)?;
    let colour = decoder.color_type();
    if !matches!(colour, ColorType::L8 | ColorType::L16) {
        return Err(DemError::new(
            path,
            "PNG header",
            format!("colour type is {colour:?}; expected 8- or 16-bit grayscale (L8 or L16)"),
        ));
    }
    // The decoded samples and the heights made from them.
    let bytes = if colour == ColorType::L16 { 2 } else { 1 };
    ensure_room(path, "PNG header", w as usize, h as usize, bytes + 4)?;
    let image = DynamicImage::from_decoder(decoder)
        .map_err(|e| DemError::new(path, "PNG image data", format!("cannot decode: {e}")))?;
    let map = |s: f64| (s * scale + offset) as f32;
    let heights: Vec<f32> = match &image {
        DynamicImage::ImageLuma16(img) => img.as_raw().iter().map(|&s| map(s as f64)).collect(),
        DynamicImage::ImageLuma8(img) => img.as_raw().iter().map(|&s| map(s as f64)).collect(),
        other => {
            return Err(DemError::new(
                path,
                "PNG image data",
                format!("decoded as {:?}; expected grayscale", other.color()),
            ))
        }
    };
    Ok(Dem::from_heights(w as usize, h as usize, heights))
}
