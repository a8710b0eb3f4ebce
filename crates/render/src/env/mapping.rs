//! The equirectangular (latitude-longitude) direction ↔ texture coordinate
//! mapping shared by every map lookup. See the [module docs](super) for the
//! picture.

use raykit_core::glam::Vec3;
use std::f32::consts::{PI, TAU};

/// Texture coordinates `(u, v)` in `[0, 1]²` of direction `dir` (any
/// length): `u = 0.5 + atan2(x, -z) / 2π`, `v = acos(y / |dir|) / π`,
/// the latter computed as `atan2(√(x² + z²), y) / π`, which needs no
/// normalisation and stays accurate near the poles.
///
/// `-Z` gives `u = 0.5`, `+X` gives `u = 0.75`, `-X` gives `u = 0.25` and
/// `+Z` is the seam (`u = 1`, or `0` for `z = +0`, `x = -0`). `+Y` gives
/// `v = 0` (top row), `-Y` gives `v = 1`. A zero or non-finite direction gives
/// `None`.
pub fn dir_to_uv(dir: Vec3) -> Option<(f32, f32)> {
    if !dir.is_finite() || dir == Vec3::ZERO {
        return None;
    }
    let u = 0.5 + dir.x.atan2(-dir.z) / TAU;
    let v = (dir.x.hypot(dir.z)).atan2(dir.y) / PI;
    Some((u.clamp(0.0, 1.0), v.clamp(0.0, 1.0)))
}

/// The unit direction at texture coordinates `(u, v)`, the inverse of
/// [`dir_to_uv`]: with `φ = 2π(u − 0.5)` and `θ = πv`,
/// `dir = (sin θ sin φ, cos θ, −sin θ cos φ)`.
pub fn uv_to_dir(u: f32, v: f32) -> Vec3 {
    let phi = TAU * (u - 0.5);
    let theta = PI * v;
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    Vec3::new(st * sp, ct, -st * cp)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_land_where_documented() {
        let uv = |d: Vec3| dir_to_uv(d).unwrap();
        assert_eq!(uv(Vec3::NEG_Z), (0.5, 0.5));
        assert_eq!(uv(Vec3::X), (0.75, 0.5));
        assert_eq!(uv(Vec3::NEG_X), (0.25, 0.5));
        assert_eq!(uv(Vec3::Y).1, 0.0);
        assert_eq!(uv(Vec3::NEG_Y).1, 1.0);
        assert_eq!(dir_to_uv(Vec3::ZERO), None);
        assert_eq!(dir_to_uv(Vec3::new(f32::NAN, 0.0, 1.0)), None);
    }
}
