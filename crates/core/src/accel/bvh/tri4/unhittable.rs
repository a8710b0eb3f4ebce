//! The triangles that the wide BVHs over packs of four Möller triangles
//! leave out of their leaves, because no ray can hit them: those whose
//! edges, as [`Moller::precompute`] stores them, are parallel or zero (a
//! triangle without area, such as the collinear slivers of CAD
//! tessellations). Möller and Trumbore's (1997) determinant is then exactly
//! zero for every ray, and the test's rounding-error bound on it rejects
//! the ray as parallel (`tri/moller.rs`), so the leaves would only spend
//! pack lanes and stretch boxes on them. Embree's builders leave such
//! triangles out too (Wald et al. 2014).
//!
//! They still belong to the structure's regions: the spatial queries
//! ([`crate::accel::Accel::visit_regions`]) get them as one more leaf with
//! their own bounds. A refit keeps them out only while they stay without
//! area ([`Unhittable::still_unhittable`]).

use crate::aabb::Aabb;
use crate::mesh::TriangleMesh;
use crate::tri::{Moller, TriangleTest};
use glam::Vec3;
use rayon::prelude::*;

/// The mesh triangles left out of the leaves, and their bounds.
pub(crate) struct Unhittable {
    /// Mesh triangle indices, ascending.
    pub prims: Vec<u32>,
    /// Union of their reach ([`TriangleTest::reach`]); empty when
    /// there are none.
    pub bounds: Aabb,
}

/// Whether no ray can hit the triangle `a, b, c` under Möller's test: its
/// stored edges have an exactly zero cross product. The products of `f32`
/// components are exact in `f64`, and a difference of two of them is zero
/// exactly when they are equal, so the test has no rounding.
pub(crate) fn never_hit(a: Vec3, b: Vec3, c: Vec3) -> bool {
    let t = Moller::precompute(a, b, c);
    t.e1.as_dvec3().cross(t.e2.as_dvec3()) == glam::DVec3::ZERO
}

impl Unhittable {
    /// None.
    pub fn none() -> Self {
        Unhittable {
            prims: Vec::new(),
            bounds: Aabb::EMPTY,
        }
    }

    /// The triangles of `mesh` that no ray can hit ([`never_hit`]).
    pub fn of_mesh(mesh: &TriangleMesh) -> Self {
        let prims: Vec<u32> = (0..mesh.num_triangles() as u32)
            .into_par_iter()
            .with_min_len(4096)
            .filter(|&i| {
                let [a, b, c] = mesh.triangle(i as usize);
                never_hit(a, b, c)
            })
            .collect();
        Self::with_prims(prims, mesh)
    }

    /// The triangles `prims` (ascending) of `mesh`, with their bounds.
    pub fn with_prims(prims: Vec<u32>, mesh: &TriangleMesh) -> Self {
        let bounds = prims.iter().fold(Aabb::EMPTY, |b, &i| {
            let [p, q, r] = mesh.triangle(i as usize);
            b.union(Moller::reach(p, q, r))
        });
        Unhittable { prims, bounds }
    }

    /// Whether every triangle here is still one no ray can hit in `mesh`
    /// (the same triangles, vertices moved), so that a refit may keep them
    /// out of the leaves.
    pub fn still_unhittable(&self, mesh: &TriangleMesh) -> bool {
        self.prims.par_iter().all(|&i| {
            let [a, b, c] = mesh.triangle(i as usize);
            never_hit(a, b, c)
        })
    }

    /// The other triangles of a mesh of `triangles`: what the leaves hold.
    pub fn kept(&self, triangles: usize) -> Vec<u32> {
        let mut out = Vec::with_capacity(triangles - self.prims.len());
        let mut skip = self.prims.iter().peekable();
        for i in 0..triangles as u32 {
            if skip.peek() == Some(&&i) {
                skip.next();
            } else {
                out.push(i);
            }
        }
        out
    }
}
