//! Brute force: every ray against every triangle. The reference every other
//! structure is tested against.

use super::leaf::LeafTriangles;
use super::{Accel, AccelStats};
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::TriangleTest;

/// All triangles in mesh order, tested one after the other.
pub struct BruteForce<T: TriangleTest> {
    tris: LeafTriangles<T>,
}

impl<T: TriangleTest> BruteForce<T> {
    /// Precompute the triangle data of `mesh`.
    pub fn new(mesh: &TriangleMesh) -> Self {
        let order = (0..mesh.num_triangles() as u32).collect();
        BruteForce {
            tris: LeafTriangles::new(mesh, order),
        }
    }

    fn test<const ANY: bool>(&self, ray: &Ray) -> (Option<Hit>, bool) {
        let rd = T::prepare(ray);
        let mut best = None;
        let mut tfar = ray.tfar;
        let any = self
            .tris
            .test::<ANY>(0, self.tris.len(), ray, &rd, &mut tfar, &mut best);
        (best, any)
    }
}

impl<T: TriangleTest> Accel for BruteForce<T> {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.test::<false>(ray).0
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.test::<true>(ray).1
    }

    fn stats(&self) -> AccelStats {
        let n = self.tris.len();
        AccelStats {
            nodes: 0,
            leaves: 1,
            bytes: self.tris.bytes(),
            node_bytes: 0,
            depth: 0,
            sah_cost: n as f64,
            triangle_refs: n,
        }
    }
}
