//! The earth's curvature and atmospheric refraction as a height correction,
//! as gdal_viewshed applies it (`-cc`): seen from an observer, a point at
//! horizontal distance `d` appears lower by `cc · d² / D`, with `D` the
//! earth's diameter and `cc` the curvature coefficient (1 for curvature
//! alone, 1 − k with refraction coefficient k; gdal_viewshed's default
//! 0.85714 is 1 − 1/7). With the corrected heights, straight segments give
//! the lines of sight over the curved earth.

use crate::dem::Dem;

/// The earth's diameter in metres: twice the WGS 84 semi-major axis, as
/// gdal_viewshed takes it from the raster's ellipsoid.
pub const EARTH_DIAMETER_M: f64 = 2.0 * 6_378_137.0;

/// `dem` with every height lowered by `coefficient · d² /`
/// [`EARTH_DIAMETER_M`], where `d` is the horizontal distance in metres
/// (cells of [`Dem::cell_size_m`]) from grid position (`col`, `row`), the
/// observer. No-data samples (NaN) stay NaN; a coefficient of 0 returns
/// the heights unchanged.
pub fn curvature_corrected(dem: &Dem, col: f64, row: f64, coefficient: f64) -> Dem {
    let mut out = dem.clone();
    if coefficient == 0.0 {
        return out;
    }
    let (sx, sy) = dem.cell_size_m();
    let k = coefficient / EARTH_DIAMETER_M;
    for (i, h) in out.heights.iter_mut().enumerate() {
        let (c, r) = ((i % dem.width) as f64, (i / dem.width) as f64);
        let (dx, dy) = ((c - col) * sx, (r - row) * sy);
        *h = (*h as f64 - k * (dx * dx + dy * dy)) as f32;
    }
    out
}
