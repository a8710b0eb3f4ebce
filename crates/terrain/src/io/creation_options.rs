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
            "BLOCKXSIZE" => bx = Some((option, value)),
            "BLOCKYSIZE" => by = Some((option, value)),
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
    let side = |given: Option<(&String, &str)>, default| match given {
        Some((option, value)) => block(option, value),
        None => Ok(default),
    };
    let layout = GeoTiffLayout {
        compression,
        tile: match tiled {
            true => Some((side(bx, dx)?, side(by, dy)?)),
            false => None,
        },
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

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(options: &[&str]) -> Result<GeoTiffLayout, String> {
        let options: Vec<String> = options.iter().map(|o| o.to_string()).collect();
        layout_from_creation_options(&options)
    }

    /// GDAL's meanings: DEFLATE strips by default here, keys and values
    /// case-insensitive, tiles 256 unless sized, block sizes only with tiles.
    #[test]
    fn options_follow_gdal_and_errors_name_the_option() {
        let strips = parse(&[]).unwrap();
        assert_eq!(
            (strips.compression, strips.tile),
            (TiffCompression::Deflate, None)
        );
        let tiles = parse(&["compress=lzw", "TILED=yes", "BLOCKXSIZE=512"]).unwrap();
        assert_eq!(
            (tiles.compression, tiles.tile),
            (TiffCompression::Lzw, Some((512, 256)))
        );
        for (options, needle) in [
            (&["BLOCKYSIZE=100"][..], "need --co TILED=YES"),
            (
                &["TILED=YES", "BLOCKYSIZE=100"][..],
                "'BLOCKYSIZE=100': expected a multiple of 16",
            ),
            (&["TILED=MAYBE"][..], "TILED=YES or TILED=NO"),
            (&["COMPRESS=JPEG"][..], "unknown compression 'JPEG'"),
            (&["FOO=1"][..], "unknown creation option 'FOO'"),
            (&["TILED"][..], "'TILED': expected KEY=VALUE"),
        ] {
            let e = parse(options).unwrap_err();
            assert!(e.contains(needle), "{options:?}: {e}");
        }
    }
}
