//! Point lights.

use raykit_core::glam::Vec3;

/// A point light: position and radiant intensity in linear RGB. The
/// irradiance it gives a surface facing it at distance `d` is
/// `intensity / d²` (no other constant), which the renderers follow.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// Position in world space.
    pub position: Vec3,
    /// Radiant intensity, linear RGB; falloff `1/d²`.
    pub intensity: Vec3,
}

impl PointLight {
    /// A light at `position` with intensity `intensity`.
    pub fn new(position: Vec3, intensity: Vec3) -> Self {
        PointLight {
            position,
            intensity,
        }
    }

    /// A light at `position` that gives irradiance `irradiance` (linear RGB)
    /// at distance `distance`, i.e. intensity `irradiance · distance²`.
    pub fn with_irradiance_at(position: Vec3, irradiance: Vec3, distance: f32) -> Self {
        PointLight::new(position, irradiance * distance * distance)
    }

    /// Irradiance at `point` on a surface facing the light (before the cosine
    /// factor and before any shadowing).
    pub fn irradiance_at(&self, point: Vec3) -> Vec3 {
        self.intensity / (self.position - point).length_squared()
    }
}
