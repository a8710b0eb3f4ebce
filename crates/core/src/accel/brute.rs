//! Brute force: every ray against every triangle. The reference every other
//! structure is tested against.

use super::leaf::LeafTriangles;
use super::{Accel, AccelStats};
use crate::aabb::Aabb;
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::TriangleTest;

/// All triangles in mesh order, tested one after the other.
pub struct BruteForce<T: TriangleTest> {
    tris: LeafTriangles<T>,
    /// Bounds of the mesh: the one region of [`Accel::visit_regions`].
    bounds: Aabb,
}

impl<T: TriangleTest> BruteForce<T> {
    /// Precompute the triangle data of `mesh`.
    pub fn new(mesh: &TriangleMesh) -> Self {
        let order = (0..mesh.num_triangles() as u32).collect();
        BruteForce {
            tris: LeafTriangles::new(mesh, order),
            bounds: mesh.bounds(),
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

    /// One leaf holding every triangle, its region the mesh bounds.
    fn visit_regions(&self, enter: &mut dyn FnMut(&Aabb) -> bool, leaf: &mut dyn FnMut(&[u32])) {
        let n = self.tris.len();
        if n > 0 && enter(&self.bounds) {
            leaf(self.tris.prims(0, n));
        }
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
