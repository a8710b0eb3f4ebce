//! The surface at a ray hit: point, normals and material.

use raykit_core::glam::Vec3;
use raykit_core::{Hit, Material, Ray, TriangleMesh};

/// What the shading needs to know about a hit.
#[derive(Clone, Copy, Debug)]
pub struct Surface<'a> {
    /// The hit point, interpolated from the corners with the barycentrics
    /// (more accurate than `origin + t·dir`).
    pub point: Vec3,
    /// Unit geometric normal, flipped to face the viewer (against the ray).
    pub geometric_normal: Vec3,
    /// Unit shading normal: the vertex normals interpolated with the
    /// barycentrics (the geometric normal when the mesh has none), flipped
    /// into the hemisphere of the geometric normal.
    pub shading_normal: Vec3,
    /// The triangle's material.
    pub material: &'a Material,
}

impl<'a> Surface<'a> {
    /// The surface of `mesh` where `ray` hits it (`hit` from an accel built on
    /// `mesh`); `fallback` is the material when the mesh has none.
    pub fn at(mesh: &'a TriangleMesh, ray: &Ray, hit: &Hit, fallback: &'a Material) -> Self {
        let prim = hit.prim as usize;
        let [a, b, c] = mesh.triangle(prim);
        let (u, v) = (hit.u, hit.v);
        let w = 1.0 - u - v;
        let point = a * w + b * u + c * v;
        let mut ng = (b - a).cross(c - a).normalize_or_zero();
        if ng.dot(ray.dir) > 0.0 {
            ng = -ng;
        }
        let mut ns = match &mesh.normals {
            Some(n) => {
                let [i, j, k] = mesh.indices[prim].map(|i| i as usize);
                (n[i] * w + n[j] * u + n[k] * v).normalize_or(ng)
            }
            None => ng,
        };
        if ns.dot(ng) < 0.0 {
            ns = -ns;
        }
        let material = mesh
            .materials
            .get(mesh.material_of(prim) as usize)
            .unwrap_or(fallback);
        Surface {
            point,
            geometric_normal: ng,
            shading_normal: ns,
            material,
        }
    }
}
