//! GDAL-style GeoTIFF creation options (`--co KEY=VALUE`, as `-co` in
//! gdal_translate and gdal_viewshed): `COMPRESS=DEFLATE|LZW|PACKBITS|NONE`
//! (DEFLATE when not given), `TILED=YES|NO`, `BLOCKXSIZE=N`, `BLOCKYSIZE=N`
//! (tile size, 256 by default, multiples of 16).

use super::geotiff_layout::{GeoTiffLayout, TiffCompression};

/// The keys understood, for error messages.
const KEYS: &str = "COMPRESS=DEFLATE|LZW|PACKBITS|NONE, TILED=YES|NO, BLOCKXSIZE=N, BLOCKYSIZE=N";

/// The layout that the creation options ask for; DEFLATE-compressed strips
/// when none is given. The error names the offending option as `--co '…'`.
pub fn layout_from_creation_options(options: &[String]) -> Result<GeoTiffLayout, String> {
    let mut compression = TiffCompression::Deflate;
    let mut tiled = false;
    let (mut bx, mut by) = (None, None);
    for option in options {
        let Some((key, value)) = option.split_once('=') else {
            return Err(format!(
                "--co '{option}': expected KEY=VALUE, one of {KEYS}"
            ));
        };
        let value = value.trim();
        match key.trim().to_ascii_uppercase().as_str() {
            "COMPRESS" => {
                compression = TiffCompression::parse(value).ok_or_else(|| {
                    format!(
                        "--co '{option}': unknown compression '{value}'; expected DEFLATE, LZW, PACKBITS or NONE"
                    )
                })?;
            }
            "TILED" => {
                tiled = match value.to_ascii_uppercase().as_str() {
                    "YES" | "TRUE" | "ON" | "1" => true,
                    "NO" | "FALSE" | "OFF" | "0" => false,
                    _ => return Err(format!("--co '{option}': expected TILED=YES or TILED=NO")),
                }
            }
            "BLOCKXSIZE" => bx = Some(block(option, value)?),
            "BLOCKYSIZE" => by = Some(block(option, value)?),
            _ => {
                return Err(format!(
                    "--co '{option}': unknown creation option '{key}'; expected one of {KEYS}"
                ))
            }
        }
    }
    if !tiled && (bx.is_some() || by.is_some()) {
        return Err("--co BLOCKXSIZE and BLOCKYSIZE need --co TILED=YES".to_string());
    }
    let (dx, dy) = GeoTiffLayout::DEFAULT_TILE;
    let layout = GeoTiffLayout {
        compression,
        tile: tiled.then(|| (bx.unwrap_or(dx), by.unwrap_or(dy))),
    };
    layout.check().map_err(|m| format!("--co: {m}"))?;
    Ok(layout)
}

/// A tile side: a multiple of 16 from 16 to 65536.
fn block(option: &str, value: &str) -> Result<u32, String> {
    match value.parse::<u32>() {
        Ok(v) if v > 0 && v % 16 == 0 && v <= 65536 => Ok(v),
        _ => Err(format!(
            "--co '{option}': expected a multiple of 16 from 16 to 65536"
        )),
    }
}
