//! The fingerprint of what a rendered picture shows, written into each
//! part of a split render (`--tile`) so that `raykit merge-tiles` refuses
//! parts of different pictures of one size.
//!
//! It covers what decides the pixels and is the same on every machine: the
//! geometry (vertex bits, triangles and their materials' indices), the
//! camera, the lights and the sampling and shading settings. File paths
//! are not in it (tiles rendered on several machines see different
//! paths), nor the integrator (both give the same pixels) or the crop
//! window (each part's own). Material colours and the environment are not
//! either: a fingerprint that misses a difference lets parts through, as
//! before; one that saw a difference where there is none would refuse
//! good parts.

use raykit_core::{Camera, Light, TriangleMesh};
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

/// The fingerprint of the picture of `mesh` seen by `camera` under `lights`
/// with `options` (never 0, which a part reads as "not recorded").
pub(super) fn fingerprint(
    mesh: &TriangleMesh,
    camera: &Camera,
    lights: &[Light],
    options: &WhittedOptions,
) -> u64 {
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    h.words(
        mesh.positions
            .iter()
            .flat_map(|p| p.to_array().map(f32::to_bits)),
    );
    h.words(mesh.indices.iter().flatten().copied());
    h.words(mesh.tri_material.iter().copied());
    let settings = WhittedOptions {
        integrator: IntegratorKind::Recursive,
        window: None,
        ..options.clone()
    };
    h.bytes(format!("{camera:?} {lights:?} {settings:?}").as_bytes());
    h.0.max(1)
}
