//! Random triangle soups for the structure tests: `n` separate triangles
//! around centres uniform in the unit cube, each with its corners at
//! `min + spread · u^power` (u uniform in [0, 1)) from its centre in random
//! directions, so most triangles are small and a few large, overlapping and
//! crossing one another; and grid surfaces, whose shared edges and corners
//! rays meet often.

use glam::Vec3;
use raykit_core::rng::Pcg32;
use raykit_core::TriangleMesh;

/// A soup of `n` triangles from `seed` (see the module docs).
#[allow(dead_code)]
pub fn soup(n: usize, seed: u64, min: f32, spread: f32, power: i32) -> TriangleMesh {
    let mut rng = Pcg32::new(seed);
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for i in 0..n {
        let c = rng.in_box(Vec3::ZERO, Vec3::ONE);
        let size = min + spread * rng.next_f32().powi(power);
        for _ in 0..3 {
            positions.push(c + rng.unit_vector() * size);
        }
        let b = 3 * i as u32;
        indices.push([b, b + 1, b + 2]);
    }
    TriangleMesh::new(positions, indices)
}

/// An `n` × `n` grid of quads over [0, 1]² in the `xz` plane, two triangles
/// each, at the heights `height()` gives vertex by vertex (rows of `x`,
/// then `z`).
#[allow(dead_code)]
pub fn grid(n: usize, mut height: impl FnMut() -> f32) -> TriangleMesh {
    let mut positions = Vec::new();
    for y in 0..=n {
        for x in 0..=n {
            positions.push(Vec3::new(
                x as f32 / n as f32,
                height(),
                y as f32 / n as f32,
            ));
        }
    }
    let w = n as u32 + 1;
    let mut indices = Vec::new();
    for y in 0..n as u32 {
        for x in 0..n as u32 {
            let a = y * w + x;
            indices.push([a, a + 1, a + w + 1]);
            indices.push([a, a + w + 1, a + w]);
        }
    }
    TriangleMesh::new(positions, indices)
}
