//! The fingerprint of what a rendered picture shows, written into each
//! part of a split render (`--tile`) so that `raykit merge-tiles` refuses
//! parts of different pictures of one size.
//!
//! It covers what decides the pixels and is the same on every machine: the
//! geometry (vertex bits, triangles and their materials' indices), the
//! materials' colours, coefficients and decoded textures, the environment
//! (its kind, texels, rotation and intensity), the camera, the lights and
//! the sampling and shading settings. File paths and names are not in it
//! (tiles rendered on several machines see different paths), nor the
//! integrator (both give the same pixels) or the crop window (each part's
//! own).

use raykit_core::{Camera, Light, TriangleMesh};
use raykit_render::env::{Environment, EquirectMap};
use raykit_render::whitted::{IntegratorKind, WhittedOptions};

/// 64-bit FNV-1a: stable across builds and platforms, unlike the
/// standard library's hasher.
struct Fnv(u64);

impl Fnv {
    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    fn words(&mut self, words: impl IntoIterator<Item = u32>) {
        for w in words {
            self.bytes(&w.to_le_bytes());
        }
    }
}

/// The fingerprint of what a scene shows whatever the view: `mesh` (its
/// geometry and materials) and its `environment`. Computed once per scene;
/// [`fingerprint`] adds each view.
pub(super) fn scene(mesh: &TriangleMesh, environment: &Environment) -> u64 {
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    let bits = |v: [f32; 3]| v.map(f32::to_bits);
    h.words(mesh.positions.iter().flat_map(|p| bits(p.to_array())));
    h.words(mesh.indices.iter().flatten().copied());
    h.words(mesh.tri_material.iter().copied());
    for m in &mesh.materials {
        h.words(bits(m.diffuse));
        h.words(bits(m.specular));
        h.words(bits(m.emission));
        let scalars = [m.shininess, m.reflectivity, m.transmission, m.ior];
        h.words(scalars.map(f32::to_bits));
        match &m.base_texture {
            Some(t) => {
                h.words([1, t.width, t.height]);
                h.words(t.texels.iter().flat_map(|c| c.to_array().map(f32::to_bits)));
            }
            None => h.words([0]),
        }
    }
    let map = |h: &mut Fnv, m: &EquirectMap| {
        h.words([m.width() as u32, m.height() as u32]);
        h.words([m.rotation_deg(), m.intensity()].map(f32::to_bits));
        h.words(m.texels().iter().flat_map(|&c| bits(c)));
    };
    match environment {
        Environment::Sky => h.words([0]),
        Environment::Constant(c) => {
            h.words([1]);
            h.words(bits(c.to_array()));
        }
        Environment::Map { map: m } => {
            h.words([2]);
            map(&mut h, m);
        }
        Environment::Box { map: m, bounds } => {
            h.words([3]);
            map(&mut h, m);
            h.words(bits(bounds.min.to_array()));
            h.words(bits(bounds.max.to_array()));
        }
    }
    h.0
}

/// The fingerprint of the picture of the scene fingerprinted `scene` seen
/// by `camera` under `lights` with `options` (never 0, which a part reads
/// as "not recorded").
pub(super) fn fingerprint(
    scene: u64,
    camera: &Camera,
    lights: &[Light],
    options: &WhittedOptions,
) -> u64 {
    let mut h = Fnv(scene);
    let settings = WhittedOptions {
        integrator: IntegratorKind::Recursive,
        window: None,
        ..options.clone()
    };
    h.bytes(format!("{camera:?} {lights:?} {settings:?}").as_bytes());
    h.0.max(1)
}
