//! The background seen by rays that miss everything.

use raykit_core::glam::Vec3;

/// Linear radiance straight up.
pub const ZENITH: Vec3 = Vec3::new(0.22, 0.40, 0.80);
/// Linear radiance at the horizon.
pub const HORIZON: Vec3 = Vec3::new(0.72, 0.80, 0.90);
/// Linear radiance straight down.
pub const NADIR: Vec3 = Vec3::new(0.30, 0.30, 0.32);

/// A soft gradient over the elevation of unit direction `dir` (y up):
/// horizon to zenith above, horizon to a dull grey below.
pub fn sky(dir: Vec3) -> Vec3 {
    let y = dir.y.clamp(-1.0, 1.0);
    if y >= 0.0 {
        HORIZON.lerp(ZENITH, y.sqrt())
    } else {
        HORIZON.lerp(NADIR, (-y).sqrt())
    }
}
