//! Reading single values from, and checking, a raw GeoTIFF GeoKeyDirectory
//! (tag 34735): a header `[version, revision, minor, key count]` followed by
//! one `[key id, location tag, count, value or offset]` entry per key.

/// GTModelTypeGeoKey: 1 projected, 2 geographic, 3 geocentric.
pub const KEY_MODEL_TYPE: u16 = 1024;
/// GTRasterTypeGeoKey: 1 PixelIsArea, 2 PixelIsPoint.
pub const KEY_RASTER_TYPE: u16 = 1025;

/// Checks that `keys` is empty or holds the header and all the entries it
/// declares; the message says what was expected.
pub fn validate_geo_keys(keys: &[u16]) -> Result<(), String> {
    if keys.is_empty() {
        return Ok(());
    }
    if keys.len() < 4 {
        return Err(format!(
            "GeoKeyDirectory has {} values; expected at least the 4-value header",
            keys.len()
        ));
    }
    let need = 4 + 4 * keys[3] as usize;
    if keys.len() < need {
        return Err(format!(
            "GeoKeyDirectory has {} values; its header declares {} keys, needing {need}",
            keys.len(),
            keys[3]
        ));
    }
    Ok(())
}

/// The value of key `id` when stored inline (location 0, count 1), else
/// `None`.
pub fn geo_key_short(keys: &[u16], id: u16) -> Option<u16> {
    entry_index(keys, id).and_then(|i| (keys[i + 1] == 0).then_some(keys[i + 3]))
}

/// Sets inline key `id` to `value` when the key is present and inline;
/// returns whether it was.
pub fn set_geo_key_short(keys: &mut [u16], id: u16, value: u16) -> bool {
    match entry_index(keys, id) {
        Some(i) if keys[i + 1] == 0 => {
            keys[i + 3] = value;
            true
        }
        _ => false,
    }
}

/// GeographicTypeGeoKey: the geographic coordinate system's code (32767
/// for one defined by further keys).
pub const KEY_GEOGRAPHIC_TYPE: u16 = 2048;
/// ProjectedCSTypeGeoKey: the projected coordinate system's code (32767
/// for one defined by further keys).
pub const KEY_PROJECTED_TYPE: u16 = 3072;

/// Whether a valid directory declares a horizontal coordinate system: it
/// holds GeographicTypeGeoKey or ProjectedCSTypeGeoKey, by code or as
/// user-defined. Citations and vertical keys alone declare none.
pub fn declares_crs(keys: &[u16]) -> bool {
    [KEY_GEOGRAPHIC_TYPE, KEY_PROJECTED_TYPE]
        .iter()
        .any(|&id| entry_index(keys, id).is_some())
}

/// Index of the entry for key `id` in a valid directory.
fn entry_index(keys: &[u16], id: u16) -> Option<usize> {
    let n = *keys.get(3)? as usize;
    (0..n)
        .map(|k| 4 + 4 * k)
        .take_while(|&i| i + 3 < keys.len())
        .find(|&i| keys[i] == id)
}

/// GeoKey ProjLinearUnitsGeoKey: the unit of a projected system's
/// coordinates (EPSG unit codes).
pub const KEY_PROJ_LINEAR_UNITS: u16 = 3076;

/// The name of a projected raster's linear unit when it is not the metre
/// (EPSG 9001): the foot (9002), the US survey foot (9003), or the EPSG
/// code; none for metres or when the keys do not say.
pub fn linear_unit_not_metre(keys: &[u16]) -> Option<String> {
    match geo_key_short(keys, KEY_PROJ_LINEAR_UNITS)? {
        9001 => None,
        9002 => Some("feet (EPSG 9002)".into()),
        9003 => Some("US survey feet (EPSG 9003)".into()),
        code => Some(format!("units of EPSG code {code}")),
    }
}
