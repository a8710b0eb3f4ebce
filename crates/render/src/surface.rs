//! The surface at a ray hit: point, normals and material.

use raykit_core::glam::{Vec2, Vec3};
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
    /// True when the ray arrived at the front side (the side the
    /// counter-clockwise winding faces): it enters a closed object there.
    pub front_face: bool,
    /// Interpolated texture coordinates (zero when the mesh has none).
    pub uv: Vec2,
    /// Diffuse colour: the material's, times its base-colour texture at `uv`.
    pub diffuse: Vec3,
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
        let mut ng = mesh.unit_normal(prim);
        let front_face = ng.dot(ray.dir()) <= 0.0;
        if !front_face {
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
        let uv = match &mesh.uvs {
            Some(t) => {
                let [i, j, k] = mesh.indices[prim].map(|i| i as usize);
                t[i] * w + t[j] * u + t[k] * v
            }
            None => Vec2::ZERO,
        };
        let mut diffuse = Vec3::from(material.diffuse);
        if let Some(tex) = &material.base_texture {
            diffuse *= tex.sample(uv).truncate();
        }
        Surface {
            point,
            geometric_normal: ng,
            shading_normal: ns,
            material,
            front_face,
            uv,
            diffuse,
        }
    }
}
