//! Esri ASCII grids (`.asc`, GDAL's AAIGrid): a header of keywords and
//! numbers (`ncols`, `nrows`, `xllcorner` or `xllcenter`, `yllcorner` or
//! `yllcenter`, `cellsize` or GDAL's `dx` and `dy`, optionally
//! `NODATA_value`), then the heights as text, rows from the north. Lidar
//! portals, QGIS and ArcGIS export DEMs this way. The grid carries no
//! coordinate system; a `.prj` beside it gives it as WKT
//! ([`crate::dem::GeoRef::crs_wkt`]), and one that is geographic (`GEOGCS`
//! or `GEOGCRS` at the top) marks the map units as degrees.

use std::path::Path;

use rayon::prelude::*;

use super::crs_sidecar::wkt_is_geographic;
use super::limits::{check_dimensions, zeroed_heights};
use super::nodata::NodataF32;
use super::DemError;
use crate::dem::{Dem, GeoRef};

/// The header's values.
struct Header {
    width: usize,
    height: usize,
    /// Lower-left corner of the lower-left cell.
    corner: (f64, f64),
    /// Cell width and height (positive).
    cell: (f64, f64),
    nodata: Option<f64>,
}

/// Reads an Esri ASCII grid (see the module notes).
///
/// Heights equal to `NODATA_value` become NaN. The georeferencing puts the
/// top-left corner at (`xllcorner`, `yllcorner` + `nrows` · `cellsize`), as
/// GDAL does (half a cell less for the `…center` keywords). Errors name the
/// line: a header keyword that is missing, repeated or not a number, a
/// value that is not a number, too few or too many values.
pub fn read_ascii_grid(path: impl AsRef<Path>) -> Result<Dem, DemError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| DemError::open(path, &e))?;
    let text = std::str::from_utf8(&bytes).map_err(|e| {
        DemError::at_byte(
            path,
            e.valid_up_to() as u64,
            "not text (UTF-8 or ASCII); expected an Esri ASCII grid",
        )
    })?;
    let mut lines = text.lines().enumerate().peekable();
    let header = read_header(path, &mut lines)?;
    let (w, h) = (header.width, header.height);
    let nodata = header.nodata.map(NodataF32::new);
    let mut heights = zeroed_heights(path, "header", w, h)?;
    let body: Vec<(usize, &str)> = lines.filter(|(_, l)| !l.trim().is_empty()).collect();
    let line_no = |k: usize| format!("line {}", k + 1);
    if body.len() == h
        && body
            .iter()
            .all(|(_, l)| l.split_ascii_whitespace().count() == w)
    {
        // One row per line, as every writer known makes them: in parallel.
        heights
            .par_chunks_mut(w)
            .zip(body.par_iter())
            .try_for_each(|(row, (k, l))| {
                for (x, token) in row.iter_mut().zip(l.split_ascii_whitespace()) {
                    *x = height(path, &line_no(*k), token, nodata)?;
                }
                Ok(())
            })?;
    } else {
        let mut tokens = body
            .iter()
            .flat_map(|(k, l)| l.split_ascii_whitespace().map(move |t| (*k, t)));
        for (i, x) in heights.iter_mut().enumerate() {
            let Some((k, token)) = tokens.next() else {
                let at = body
                    .last()
                    .map_or("end of file".into(), |(k, _)| line_no(*k));
                return Err(DemError::new(
                    path,
                    at,
                    format!(
                        "the file ends after {i} values; expected {w}×{h} = {}",
                        w * h
                    ),
                ));
            };
            *x = height(path, &line_no(k), token, nodata)?;
        }
        if let Some((k, token)) = tokens.next() {
            return Err(DemError::new(
                path,
                line_no(k),
                format!("value {token:?} beyond the {w}×{h} the header gives"),
            ));
        }
    }
    let crs_wkt = read_prj(path);
    let geographic = crs_wkt.as_deref().is_some_and(wkt_is_geographic);
    let (x0, y0) = header.corner;
    let (cw, ch) = header.cell;
    Ok(Dem {
        width: w,
        height: h,
        heights,
        nodata: header.nodata,
        georef: GeoRef {
            origin_x: x0,
            origin_y: y0 + h as f64 * ch,
            pixel_width: cw,
            pixel_height: -ch,
            geographic,
            geo_keys: Vec::new(),
            geo_doubles: Vec::new(),
            geo_ascii: String::new(),
            crs_wkt,
        },
    })
}

/// The WKT of the `.prj` beside `path`, trimmed: none when there is no such
/// file, or it is empty, not text, or larger than any coordinate system
/// (1 MiB).
fn read_prj(path: &Path) -> Option<String> {
    let prj = path.with_extension("prj");
    let small = std::fs::metadata(&prj).is_ok_and(|m| m.len() <= 1 << 20);
    let text = std::fs::read_to_string(prj).ok().filter(|_| small)?;
    let wkt = text.trim();
    (!wkt.is_empty()).then(|| wkt.to_string())
}

/// One height, read as a double and stored as a float as GDAL reads it:
/// NaN for the nodata value (compared as floats, see [`NodataF32`]).
fn height(path: &Path, at: &str, token: &str, nodata: Option<NodataF32>) -> Result<f32, DemError> {
    let v: f64 = token.parse().map_err(|_| {
        DemError::new(
            path,
            at,
            format!("{token:?} is not a number; expected a height"),
        )
    })?;
    let v = v as f32;
    Ok(if nodata.is_some_and(|nd| nd.matches(v)) {
        f32::NAN
    } else {
        v
    })
}

/// The header lines, up to the first line that starts with a number.
fn read_header<'a>(
    path: &Path,
    lines: &mut std::iter::Peekable<impl Iterator<Item = (usize, &'a str)>>,
) -> Result<Header, DemError> {
    let mut seen: Vec<(String, f64, usize)> = Vec::new();
    while let Some(&(k, line)) = lines.peek() {
        let mut parts = line.split_ascii_whitespace();
        let Some(key) = parts.next() else {
            lines.next();
            continue;
        };
        // The first row of samples ends the header: a number, or a NaN or
        // infinity as GDAL writes them in float grids.
        if key.starts_with(|c: char| c.is_ascii_digit() || "+-.".contains(c))
            || key.parse::<f64>().is_ok()
        {
            break;
        }
        lines.next();
        let at = format!("line {}", k + 1);
        let key = key.to_ascii_lowercase();
        let known = [
            "ncols",
            "nrows",
            "xllcorner",
            "xllcenter",
            "yllcorner",
            "yllcenter",
            "cellsize",
            "dx",
            "dy",
            "nodata_value",
        ];
        if !known.contains(&key.as_str()) {
            return Err(DemError::new(
                path,
                at,
                format!(
                    "unknown header keyword {key:?}; expected ncols, nrows, xllcorner or \
                     xllcenter, yllcorner or yllcenter, cellsize (or dx and dy), NODATA_value"
                ),
            ));
        }
        let value = parts
            .next()
            .and_then(|v| v.parse::<f64>().ok())
            .ok_or_else(|| DemError::new(path, &at, format!("{key} has no number after it")))?;
        if seen.iter().any(|(s, _, _)| *s == key) {
            return Err(DemError::new(path, at, format!("{key} is given twice")));
        }
        seen.push((key, value, k));
    }
    let get = |key: &str| {
        seen.iter()
            .find(|(s, _, _)| s == key)
            .map(|&(_, v, k)| (v, k))
    };
    let need = |key: &str| {
        get(key).ok_or_else(|| {
            DemError::new(
                path,
                "header",
                format!("no {key}; an Esri ASCII grid starts with it"),
            )
        })
    };
    let count = |key: &str| -> Result<usize, DemError> {
        let (v, k) = need(key)?;
        if v.fract() != 0.0 || v < 1.0 || v > usize::MAX as f64 {
            return Err(DemError::new(
                path,
                format!("line {}", k + 1),
                format!("{key} is {v}; expected a whole number of at least 1"),
            ));
        }
        Ok(v as usize)
    };
    let (width, height) = (count("ncols")?, count("nrows")?);
    check_dimensions(path, "header", width, height)?;
    let cell = match (get("cellsize"), get("dx"), get("dy")) {
        (Some((c, _)), None, None) => (c, c),
        (None, Some((dx, _)), Some((dy, _))) => (dx, dy),
        _ => {
            return Err(DemError::new(
                path,
                "header",
                "expected cellsize, or dx and dy, and not both",
            ))
        }
    };
    if !(cell.0 > 0.0 && cell.1 > 0.0 && cell.0.is_finite() && cell.1.is_finite()) {
        return Err(DemError::new(
            path,
            "header",
            format!(
                "cell size {} × {}; expected positive numbers",
                cell.0, cell.1
            ),
        ));
    }
    let axis = |corner: &str, centre: &str, size: f64| match (get(corner), get(centre)) {
        (Some((v, _)), None) => Ok(v),
        (None, Some((v, _))) => Ok(v - size / 2.0),
        _ => Err(DemError::new(
            path,
            "header",
            format!("expected one of {corner} and {centre}"),
        )),
    };
    Ok(Header {
        width,
        height,
        corner: (
            axis("xllcorner", "xllcenter", cell.0)?,
            axis("yllcorner", "yllcenter", cell.1)?,
        ),
        cell,
        nodata: get("nodata_value").map(|(v, _)| v),
    })
}
