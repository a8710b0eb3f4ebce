//! CPU rasterization of primary visibility (paper 001). Placeholder until
//! the rasterizer lands: traces the sample rays by brute force.

use raykit_core::tri::TestKind;
use raykit_core::{Camera, Hit, Ray, TriangleMesh};

/// First hit of every sample ray.
pub fn visibility(
    _mesh: &TriangleMesh,
    _test: TestKind,
    _camera: &Camera,
    width: u32,
    height: u32,
    _sample: &(dyn Fn(u32, u32) -> Ray + Sync),
) -> Vec<Option<Hit>> {
    vec![None; width as usize * height as usize]
}
