//! Triangles precomputed in a structure's leaf order, and the leaf loop that
//! every structure shares.

use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::TriangleTest;
use rayon::prelude::*;

/// Precomputed triangle data in leaf order (a leaf's triangles are
/// contiguous), with the map back to mesh triangle indices.
pub(crate) struct LeafTriangles<T: TriangleTest> {
    tris: Vec<T::Tri>,
    prims: Vec<u32>,
}

impl<T: TriangleTest> LeafTriangles<T> {
    /// Precompute the triangles of `mesh` in the given order.
    pub fn new(mesh: &TriangleMesh, order: Vec<u32>) -> Self {
        let tris = order
            .par_iter()
            .map(|&p| {
                let [a, b, c] = mesh.triangle(p as usize);
                T::precompute(a, b, c)
            })
            .collect();
        LeafTriangles { tris, prims: order }
    }

    /// Recompute every triangle from `mesh`, whose triangles keep their
    /// indices and corners' vertex indices but whose positions may have
    /// moved (a refit); every index must be in range.
    pub fn recompute(&mut self, mesh: &TriangleMesh) {
        self.tris
            .par_iter_mut()
            .zip(self.prims.par_iter())
            .with_min_len(1024)
            .for_each(|(tri, &p)| {
                let [a, b, c] = mesh.triangle(p as usize);
                *tri = T::precompute(a, b, c);
            });
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// The precomputed triangle at position `i`.
    #[inline]
    pub fn tri(&self, i: usize) -> &T::Tri {
        &self.tris[i]
    }

    /// Mesh triangle index of the triangle at position `i`.
    #[inline]
    pub fn prim(&self, i: usize) -> u32 {
        self.prims[i]
    }

    /// Mesh triangle indices of triangles `first..first + count`.
    pub fn prims(&self, first: usize, count: usize) -> &[u32] {
        &self.prims[first..first + count]
    }

    /// The precomputed triangles as 32-bit words and the map back to mesh
    /// triangles, for devices with kernels of their own.
    pub fn flat(&self) -> super::flat::FlatTriangles {
        let mut words = Vec::with_capacity(self.tris.len() * T::WORDS);
        for tri in &self.tris {
            T::write_words(tri, &mut words);
        }
        super::flat::FlatTriangles {
            test: T::NAME,
            words_per_tri: T::WORDS,
            words,
            prims: self.prims.clone(),
        }
    }

    /// Bytes held (precomputed data and the index map).
    pub fn bytes(&self) -> usize {
        self.tris.len() * std::mem::size_of::<T::Tri>() + self.prims.len() * 4
    }

    /// Test triangles `first..first + count`. Nearest-hit mode (`ANY =
    /// false`) keeps the nearest hit in `best` and shrinks `tfar` to it (ties
    /// keep the earlier triangle); any-hit mode returns true at the first hit.
    #[inline(always)]
    pub fn test<const ANY: bool>(
        &self,
        first: usize,
        count: usize,
        ray: &Ray,
        rd: &T::RayData,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        self.test_each::<ANY>(first..first + count, ray, rd, tfar, best)
    }

    /// [`LeafTriangles::test`] on the triangles at the given positions (a
    /// kd-tree leaf's entries in its triangle-index list).
    #[inline(always)]
    pub fn test_indexed<const ANY: bool>(
        &self,
        indices: &[u32],
        ray: &Ray,
        rd: &T::RayData,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        self.test_each::<ANY>(indices.iter().map(|&i| i as usize), ray, rd, tfar, best)
    }

    #[inline(always)]
    fn test_each<const ANY: bool>(
        &self,
        positions: impl Iterator<Item = usize>,
        ray: &Ray,
        rd: &T::RayData,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        for i in positions {
            let tri = &self.tris[i];
            if ANY {
                if T::occluded(tri, ray, rd, *tfar) {
                    return true;
                }
            } else if let Some(h) = T::intersect(tri, ray, rd, *tfar) {
                if best.is_none_or(|b| h.t < b.t) {
                    *tfar = h.t;
                    *best = Some(Hit {
                        t: h.t,
                        u: h.u,
                        v: h.v,
                        prim: self.prims[i],
                    });
                }
            }
        }
        false
    }
}
