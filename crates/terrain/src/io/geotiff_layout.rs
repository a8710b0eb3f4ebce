//! How a GeoTIFF's samples are laid out and compressed: strips or square
//! tiles, no compression, DEFLATE, LZW or PackBits (the TIFF 6.0 codes
//! 1, 8, 5 and 32773, which GDAL reads and writes under the creation
//! options `COMPRESS=NONE|DEFLATE|LZW|PACKBITS`, `TILED=YES`,
//! `BLOCKXSIZE`, `BLOCKYSIZE`).

/// The compression of a written GeoTIFF.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TiffCompression {
    /// Samples as they are (TIFF code 1).
    #[default]
    None,
    /// zlib streams (Adobe Deflate, TIFF code 8), at level 1 (GDAL's
    /// `ZLEVEL=1`): several times faster than level 6, and masks stay
    /// hundreds of times smaller than their samples.
    Deflate,
    /// Lempel-Ziv-Welch as TIFF 6.0 specifies it (code 5).
    Lzw,
    /// Run-length PackBits (code 32773).
    Packbits,
}

impl TiffCompression {
    /// Every compression, in the order of GDAL's `COMPRESS` names.
    pub const ALL: [TiffCompression; 4] = [
        TiffCompression::None,
        TiffCompression::Deflate,
        TiffCompression::Lzw,
        TiffCompression::Packbits,
    ];

    /// GDAL's name of the compression (`COMPRESS=NAME`).
    pub fn name(self) -> &'static str {
        match self {
            TiffCompression::None => "NONE",
            TiffCompression::Deflate => "DEFLATE",
            TiffCompression::Lzw => "LZW",
            TiffCompression::Packbits => "PACKBITS",
        }
    }

    /// The compression of a GDAL name, any case.
    pub fn parse(name: &str) -> Option<TiffCompression> {
        Self::ALL
            .into_iter()
            .find(|c| c.name().eq_ignore_ascii_case(name.trim()))
    }

    /// The TIFF Compression tag's value.
    pub fn tag_value(self) -> u16 {
        match self {
            TiffCompression::None => 1,
            TiffCompression::Deflate => 8,
            TiffCompression::Lzw => 5,
            TiffCompression::Packbits => 32773,
        }
    }
}

/// Strips or tiles, and the compression, of a written GeoTIFF.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GeoTiffLayout {
    /// Compression of every strip or tile.
    pub compression: TiffCompression,
    /// `Some((width, height))`: tiles of that size (each a multiple of 16,
    /// as TIFF requires), the last row and column of tiles padded; `None`:
    /// strips of whole rows.
    pub tile: Option<(u32, u32)>,
}

impl GeoTiffLayout {
    /// GDAL's default block size for `TILED=YES`.
    pub const DEFAULT_TILE: (u32, u32) = (256, 256);

    /// Whether the tile size is valid: both sides multiples of 16, 16 to
    /// 65536 (TIFF 6.0, section 15).
    pub fn check(&self) -> Result<(), String> {
        if let Some((w, h)) = self.tile {
            for (name, v) in [("width", w), ("height", h)] {
                if v == 0 || v % 16 != 0 || v > 65536 {
                    return Err(format!(
                        "tile {name} {v}: expected a multiple of 16 from 16 to 65536"
                    ));
                }
            }
        }
        Ok(())
    }

    /// The layout in words, e.g. "DEFLATE, tiles 256x256".
    pub fn describe(&self) -> String {
        match self.tile {
            Some((w, h)) => format!("{}, tiles {w}x{h}", self.compression.name()),
            None => format!("{}, strips", self.compression.name()),
        }
    }
}
