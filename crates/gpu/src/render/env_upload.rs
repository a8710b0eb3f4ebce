//! The environment as the WGSL reads it (`shaders/render/environment.wgsl`):
//! the sky, a constant, an equirectangular map by direction, or the Purcell-style stream tracer's
//! environment box.

use raykit_core::glam::Vec3;
use raykit_render::env::{Environment, EquirectMap};

/// The environment as the shaders read it: kind (0 sky, 1 constant, 2 map
/// by direction, 3 The environment box), colour, map and box.
#[derive(Default)]
pub struct EnvUpload {
    /// 0 sky, 1 constant, 2 map by direction, 3 environment box.
    pub kind: u32,
    /// The constant's radiance.
    pub color: Vec3,
    /// Map width, height, turn and intensity.
    pub map: Option<(u32, u32, f32, f32)>,
    /// Map texels, RGB f32 bit patterns.
    pub texels: Vec<u32>,
    /// The environment box.
    pub bounds: Option<raykit_core::Aabb>,
}

/// What the shaders need to know about `env`.
pub fn environment_upload(env: &Environment) -> EnvUpload {
    let with_map = |kind, map: &EquirectMap| {
        // EquirectMap::with_rotation_deg's turn, from the same inputs.
        let turn = (map.rotation_deg() / 360.0).rem_euclid(1.0);
        EnvUpload {
            kind,
            map: Some((
                map.width() as u32,
                map.height() as u32,
                turn,
                map.intensity(),
            )),
            texels: map.texels().iter().flatten().map(|x| x.to_bits()).collect(),
            ..EnvUpload::default()
        }
    };
    match env {
        Environment::Sky => EnvUpload::default(),
        Environment::Constant(c) => EnvUpload {
            kind: 1,
            color: *c,
            ..EnvUpload::default()
        },
        Environment::Map { map } => with_map(2, map),
        Environment::Box { map, bounds } => EnvUpload {
            bounds: Some(*bounds),
            ..with_map(3, map)
        },
    }
}
