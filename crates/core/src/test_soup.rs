//! Random triangle soups for the structure tests: `n` separate triangles
//! around centres uniform in the unit cube, each with its corners at
//! `min + spread · u^power` (u uniform in [0, 1)) from its centre in random
//! directions, so most triangles are small and a few large, overlapping and
//! crossing one another.

use crate::mesh::TriangleMesh;
use crate::rng::Pcg32;
use glam::Vec3;

/// A soup of `n` triangles from `seed` (see the module docs).
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
