//! Brute force: every ray against every triangle. The reference every other
//! structure is tested against.

use super::{Accel, AccelStats};
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::TriangleTest;

/// All triangles in mesh order, tested one after the other.
pub struct BruteForce<T: TriangleTest> {
    tris: Vec<T::Tri>,
}

impl<T: TriangleTest> BruteForce<T> {
    /// Precompute the triangle data of `mesh`.
    pub fn new(mesh: &TriangleMesh) -> Self {
        let tris = (0..mesh.num_triangles())
            .map(|i| {
                let [a, b, c] = mesh.triangle(i);
                T::precompute(a, b, c)
            })
            .collect();
        BruteForce { tris }
    }
}

impl<T: TriangleTest> Accel for BruteForce<T> {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let rd = T::prepare(ray);
        let mut best: Option<Hit> = None;
        let mut tfar = ray.tfar;
        for (i, tri) in self.tris.iter().enumerate() {
            if let Some(h) = T::intersect(tri, ray, &rd, tfar) {
                // Strictly nearer only, so ties go to the lowest index.
                if best.is_none_or(|b| h.t < b.t) {
                    tfar = h.t;
                    best = Some(Hit {
                        t: h.t,
                        u: h.u,
                        v: h.v,
                        prim: i as u32,
                    });
                }
            }
        }
        best
    }

    fn occluded(&self, ray: &Ray) -> bool {
        let rd = T::prepare(ray);
        self.tris
            .iter()
            .any(|tri| T::occluded(tri, ray, &rd, ray.tfar))
    }

    fn stats(&self) -> AccelStats {
        let n = self.tris.len();
        AccelStats {
            nodes: 0,
            leaves: 1,
            bytes: n * std::mem::size_of::<T::Tri>(),
            node_bytes: 0,
            depth: 0,
            sah_cost: n as f64,
            triangle_refs: n,
        }
    }
}
