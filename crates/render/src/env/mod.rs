//! Environments for rays that leave the scene (paper 001). Placeholder until
//! the environment-map work lands.

use raykit_core::glam::Vec3;

/// What a ray that leaves the scene sees.
#[derive(Clone, Debug)]
pub enum Environment {
    /// The sky gradient of [`crate::sky::sky`].
    Sky,
    /// The same radiance from every direction.
    Constant(Vec3),
}

impl Environment {
    /// Radiance seen along the ray from `origin` in direction `dir`.
    pub fn radiance(&self, _origin: Vec3, dir: Vec3) -> Vec3 {
        match self {
            Environment::Sky => crate::sky::sky(dir.normalize_or_zero()),
            Environment::Constant(c) => *c,
        }
    }
}
