//! Shadow maps (paper 001). Placeholder until the shadow-map work lands.

use raykit_core::glam::Vec3;

/// Shadow maps of a set of lights.
pub struct ShadowMaps;

impl ShadowMaps {
    /// Fraction of light `light` reaching `point`.
    pub fn visibility(&self, _light: usize, _point: Vec3, _normal: Vec3) -> f32 {
        1.0
    }
}
