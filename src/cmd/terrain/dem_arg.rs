//! The DEM argument of the terrain commands: a file or `fractal:SIZE[:SEED]`.

use anyhow::{bail, Context, Result};
use raykit_terrain::io::{load_dem, LoadOptions};
use raykit_terrain::Dem;

/// Prefix of generated DEMs.
pub const FRACTAL: &str = "fractal:";

/// Load `spec`: a DEM file (GeoTIFF, .hgt, .ter, 16-bit PNG, raw) or
/// `fractal:SIZE[:SEED]` (diamond-square, 10 m pixels, 0..2000 m).
pub fn load(spec: &str) -> Result<Dem> {
    if let Some(rest) = spec.strip_prefix(FRACTAL) {
        let mut parts = rest.split(':');
        let size: usize = parts.next().unwrap_or_default().parse().with_context(|| {
            format!("'{spec}': expected fractal:SIZE[:SEED] with SIZE an integer")
        })?;
        let seed: u64 = match parts.next() {
            Some(s) => s
                .parse()
                .with_context(|| format!("'{spec}': SEED must be an integer"))?,
            None => 1,
        };
        if !(2..=16384).contains(&size) {
            bail!("'{spec}': SIZE must be between 2 and 16384");
        }
        return Ok(raykit_terrain::fractal::fractal(size, seed, 0.55));
    }
    Ok(load_dem(spec, &LoadOptions::default())?)
}

/// Parse `N` comma-separated finite numbers; `what` (e.g. "X,Y,Z", or
/// empty) names them in the error.
pub fn parse_numbers<const N: usize>(s: &str, what: &str) -> Result<[f64; N], String> {
    let named = if what.is_empty() {
        String::new()
    } else {
        format!(" {what}")
    };
    let err = || format!("expected {N} comma-separated numbers{named}, got '{s}'");
    let v: Vec<f64> = s
        .split(',')
        .map(|c| c.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| err())?;
    let arr: [f64; N] = v.try_into().map_err(|_| err())?;
    if arr.iter().any(|x| !x.is_finite()) {
        return Err(format!("numbers must be finite, got '{s}'"));
    }
    Ok(arr)
}

/// [`parse_numbers`] for `flag`, its error naming the flag.
pub fn numbers<const N: usize>(flag: &str, s: &str) -> Result<[f64; N]> {
    parse_numbers::<N>(s, "").map_err(|e| anyhow::anyhow!("{flag}: {e}"))
}
