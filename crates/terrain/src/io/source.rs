//! A DEM named on a command line: a file (GeoTIFF, SRTM `.hgt`, Terragen
//! `.ter`, 16-bit PNG, raw) or a generated `fractal:SIZE[:SEED]`.

use super::load::{load_dem, LoadOptions};
use crate::dem::Dem;
use crate::fractal::fractal;

/// Prefix of generated DEMs: `fractal:SIZE[:SEED]`.
pub const FRACTAL_PREFIX: &str = "fractal:";

/// Load `spec`: a DEM file read by [`load_dem`] with the default options, or
/// `fractal:SIZE[:SEED]` (diamond-square after Fournier, Fussell and
/// Carpenter 1982; 10 m pixels, 0..2000 m, seed 1 when not given). The
/// error names the file and the position in it, or what is wrong with the
/// spec.
pub fn load_dem_source(spec: &str) -> Result<Dem, String> {
    let Some(rest) = spec.strip_prefix(FRACTAL_PREFIX) else {
        return load_dem(spec, &LoadOptions::default()).map_err(|e| e.to_string());
    };
    let mut parts = rest.split(':');
    let size: usize =
        parts.next().unwrap_or_default().parse().map_err(|e| {
            format!("'{spec}': expected fractal:SIZE[:SEED] with SIZE an integer: {e}")
        })?;
    let seed: u64 = match parts.next() {
        Some(s) => s
            .parse()
            .map_err(|e| format!("'{spec}': SEED must be an integer: {e}"))?,
        None => 1,
    };
    if !(2..=16384).contains(&size) {
        return Err(format!("'{spec}': SIZE must be between 2 and 16384"));
    }
    Ok(fractal(size, seed, 0.55))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fractal_specs_match_the_generator() {
        let dem = load_dem_source("fractal:33:7").unwrap();
        let direct = fractal(33, 7, 0.55);
        assert_eq!((dem.width, dem.height), (direct.width, direct.height));
        assert_eq!(dem.heights, direct.heights);
        assert_eq!(
            load_dem_source("fractal:9").unwrap().heights,
            fractal(9, 1, 0.55).heights
        );
    }

    #[test]
    fn bad_fractal_specs_say_what_is_wrong() {
        assert!(load_dem_source("fractal:x")
            .unwrap_err()
            .contains("SIZE an integer"));
        assert!(load_dem_source("fractal:9:y").unwrap_err().contains("SEED"));
        assert!(load_dem_source("fractal:1")
            .unwrap_err()
            .contains("between 2"));
    }
}
