//! SRTM `.hgt` tiles: a square of big-endian `i16` heights in metres, rows
//! from the north, -32768 for voids, located only by the file name
//! (`N57E011.hgt` covers latitudes 57..58 N and longitudes 11..12 E; its
//! edge samples lie on those lines and are shared with the neighbours).

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use super::limits::check_dimensions;
use super::samples::read_samples;
use super::DemError;
use crate::dem::{Dem, GeoRef};

/// The value SRTM uses for voids.
pub const HGT_VOID: i16 = -32768;

/// Latitude and longitude (degrees, south and west negative) of the
/// south-west corner named by an SRTM file name such as `N57E011.hgt` or
/// `s09w080.SRTMGL1.hgt`: `N`/`S`, two digits, `E`/`W`, three digits, then
/// anything. `None` if the name does not start that way or is out of range.
pub fn parse_hgt_name(name: &str) -> Option<(i32, i32)> {
    let b = name.as_bytes();
    if b.len() < 7 || !b[1..3].iter().chain(&b[4..7]).all(u8::is_ascii_digit) {
        return None;
    }
    let digits = |s: &[u8]| s.iter().fold(0i32, |n, &d| n * 10 + (d - b'0') as i32);
    let lat = digits(&b[1..3]);
    let lon = digits(&b[4..7]);
    let lat = match b[0].to_ascii_uppercase() {
        b'N' => lat,
        b'S' => -lat,
        _ => return None,
    };
    let lon = match b[3].to_ascii_uppercase() {
        b'E' => lon,
        b'W' => -lon,
        _ => return None,
    };
    if !(-90..90).contains(&lat) || !(-180..180).contains(&lon) {
        return None;
    }
    Some((lat, lon))
}

/// The side of a square `.hgt` file of `len` bytes (`len` = 2·n², n ≥ 2).
fn side_from_len(len: u64) -> Option<usize> {
    if !len.is_multiple_of(2) {
        return None;
    }
    let samples = len / 2;
    let n = (samples as f64).sqrt().round() as u64;
    (n >= 2 && n * n == samples).then_some(n as usize)
}

/// Reads an SRTM `.hgt` tile.
///
/// The side n comes from the file size (2·n² bytes: 1201 for 3″ tiles, 3601
/// for 1″ ones, any other square accepted). Voids (-32768) become NaN and
/// `nodata` is `Some(-32768)`. The georeferencing is geographic (WGS 84):
/// pixel size 1/(n−1)°, so that the samples lie on whole degrees at the
/// edges, and the pixel-corner origin is (lon − ½ pixel, lat + 1 + ½ pixel)
/// from the file name's south-west corner. `geo_keys` is filled with a
/// minimal WGS 84 GeoKeyDirectory (geographic model, pixel-is-area,
/// EPSG:4326) so the DEM can be written as a GeoTIFF.
pub fn read_hgt(path: impl AsRef<Path>) -> Result<Dem, DemError> {
    let path = path.as_ref();
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or_default();
    let (lat, lon) = parse_hgt_name(&name).ok_or_else(|| {
        DemError::new(
            path,
            "file name",
            format!(
                "cannot locate the tile: expected a name like N57E011.hgt (N or S, two digits \
                 of latitude, E or W, three digits of longitude), found {name:?}"
            ),
        )
    })?;
    let file = File::open(path).map_err(|e| DemError::open(path, &e))?;
    let len = file.metadata().map_err(|e| DemError::open(path, &e))?.len();
    let n = side_from_len(len).ok_or_else(|| {
        DemError::at_byte(
            path,
            len,
            format!(
                "file is {len} bytes; an SRTM tile is a square of 2-byte samples, 2·n² bytes \
                 (2884802 for 1201², 25934402 for 3601²)"
            ),
        )
    })?;
    check_dimensions(path, "file size", n, n)?;
    let mut heights = vec![0f32; n * n];
    read_samples(
        path,
        &mut BufReader::new(file),
        0,
        2,
        &mut heights,
        |b| match i16::from_be_bytes([b[0], b[1]]) {
            HGT_VOID => f32::NAN,
            h => h as f32,
        },
    )?;
    let pixel = 1.0 / (n - 1) as f64;
    Ok(Dem {
        width: n,
        height: n,
        heights,
        nodata: Some(HGT_VOID as f64),
        georef: GeoRef {
            origin_x: lon as f64 - 0.5 * pixel,
            origin_y: (lat + 1) as f64 + 0.5 * pixel,
            pixel_width: pixel,
            pixel_height: -pixel,
            geographic: true,
            geo_keys: vec![1, 1, 0, 3, 1024, 0, 1, 2, 1025, 0, 1, 1, 2048, 0, 1, 4326],
            geo_doubles: Vec::new(),
            geo_ascii: String::new(),
            crs_wkt: None,
        },
    })
}
