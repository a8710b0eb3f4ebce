//! The DEM argument of the terrain commands: a file or `fractal:SIZE[:SEED]`.

use anyhow::Result;
use raykit_terrain::io::load_dem_source;
use raykit_terrain::Dem;

pub use raykit_terrain::io::FRACTAL_PREFIX as FRACTAL;

/// Load `spec`: a DEM file or `fractal:SIZE[:SEED]`
/// ([`raykit_terrain::io::load_dem_source`]).
pub fn load(spec: &str) -> Result<Dem> {
    load_dem_source(spec).map_err(anyhow::Error::msg)
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
