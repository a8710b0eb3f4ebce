//! The quick renderer's shading: Blinn-Phong direct lighting
//! ([`crate::lighting`]) with hard shadows from shadow rays, the sky gradient
//! behind.

use crate::lighting::blinn_phong;
use crate::options::RenderOptions;
use crate::sky::sky;
pub use crate::surface::Surface;
use raykit_core::glam::Vec3;
use raykit_core::{Accel, Hit, Material, Ray, TriangleMesh};
use raykit_core::{Light, LightSample};

/// Offset of shadow-ray origins along the geometric normal for `mesh`:
/// `1e-5` times the larger of the bounding-box diagonal and the largest
/// coordinate magnitude, about a hundred float spacings at that magnitude
/// (so a model nanometres across gets an offset of its own scale).
pub fn shadow_bias(mesh: &TriangleMesh) -> f32 {
    let b = mesh.bounds();
    if b.is_empty() {
        return 1e-5;
    }
    let magnitude = b.min.abs().max(b.max.abs()).max_element();
    (1e-5 * b.diagonal().max(magnitude)).max(f32::MIN_POSITIVE)
}

/// Shades rays against one mesh, its accel and its lights.
pub struct Shader<'a> {
    mesh: &'a TriangleMesh,
    lights: &'a [Light],
    accel: &'a dyn Accel,
    ambient: Vec3,
    shadows: bool,
    bias: f32,
    fallback: Material,
}

impl<'a> Shader<'a> {
    /// A shader for `mesh` (with `accel` built on it) lit by `lights`, with the
    /// ambient term and shadow switch of `opts`.
    pub fn new(
        mesh: &'a TriangleMesh,
        lights: &'a [Light],
        accel: &'a dyn Accel,
        opts: &RenderOptions,
    ) -> Self {
        Shader {
            mesh,
            lights,
            accel,
            ambient: opts.ambient,
            shadows: opts.shadows,
            bias: shadow_bias(mesh),
            fallback: Material::default(),
        }
    }

    /// Linear radiance along `ray`: the shaded nearest hit, or the sky.
    pub fn radiance(&self, ray: &Ray) -> Vec3 {
        match self.accel.intersect(ray) {
            Some(hit) => self.shade(ray, &hit),
            None => sky(ray.dir().normalize_or_zero()),
        }
    }

    /// Linear radiance leaving the hit `hit` of `ray` towards the ray origin.
    pub fn shade(&self, ray: &Ray, hit: &Hit) -> Vec3 {
        let s = Surface::at(self.mesh, ray, hit, &self.fallback);
        let view = -ray.dir().normalize_or_zero();
        blinn_phong(&s, view, self.lights, self.ambient, &mut |_, ls| {
            if self.visible(&s, ls) {
                1.0
            } else {
                0.0
            }
        })
    }

    /// True when shadows are off or no triangle lies between the surface
    /// point (offset along the geometric normal) and the light.
    fn visible(&self, s: &Surface, light: &LightSample) -> bool {
        if !self.shadows {
            return true;
        }
        !self.accel.occluded(&shadow_ray(s, light, self.bias))
    }
}

/// The shadow ray from the surface point `s` towards the light sample
/// `light` (Whitted 1980's shadow feeler): it starts `bias` off the surface
/// along the geometric normal and `bias` along the ray, and stops just short
/// of the light. The start along the ray matters at a concave edge, where
/// the point offset along one face's normal still lies in the other face's
/// plane, which a ray from t = 0 would hit.
pub(crate) fn shadow_ray(s: &Surface, light: &LightSample, bias: f32) -> Ray {
    let origin = s.point + s.geometric_normal * bias;
    Ray::segment(origin, light.to_light, bias, light.distance * (1.0 - 1e-4))
}
