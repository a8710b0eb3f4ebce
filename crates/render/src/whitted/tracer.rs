//! The Whitted shading kernel shared by both integrators: what one hit
//! emits and which reflection and refraction rays it spawns.
//!
//! For a hit with transmission `t`, reflectivity `r`, specular colour `ks`,
//! diffuse colour `kd` and emission `Le`, with `F` the dielectric Fresnel
//! reflectance (index of refraction from the material) and `Fs` Schlick's
//! conductor Fresnel with `F0 = ks`:
//!
//! ```text
//! L = Le + (1−t)(1−r) · direct
//!        + [(1−t) r Fs + t F] · L(reflected ray)
//!        + t (1−F) kd · L(refracted ray)
//! ```
//!
//! where `direct` is Blinn-Phong lighting ([`crate::lighting`]). A lossless
//! dielectric (`t = 1`, `kd = 1`) therefore conserves energy exactly, which
//! the furnace test checks. Reflection and refraction use the shading
//! normal, falling back to the geometric one when the interpolated normal
//! would send the ray to the wrong side; secondary rays start a small offset
//! off the surface. Paths stop after `max_depth` rays.

use super::optics::{fresnel_dielectric, fresnel_schlick, reflect, refract};
use crate::env::Environment;
use crate::lighting::blinn_phong;
use crate::shade::{shadow_bias, shadow_ray};
use crate::shadowmap::ShadowMaps;
use crate::surface::Surface;
use raykit_core::glam::Vec3;
use raykit_core::{Accel, Hit, Light, LightSample, Material, Ray, TriangleMesh};
use std::sync::atomic::{AtomicU64, Ordering};

/// Where the shading kernel learns whether a light is blocked.
pub enum ShadowSource<'a> {
    /// Lights are never blocked.
    Off,
    /// Occlusion rays through the accel.
    Rays,
    /// Filtered shadow-map lookups.
    Maps(&'a ShadowMaps),
}

/// Which kind of secondary ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bounce {
    /// Mirror reflection.
    Reflection,
    /// Refraction into or out of a dielectric.
    Refraction,
}

/// A reflection or refraction ray and the weight of what it brings back.
#[derive(Clone, Copy, Debug)]
pub struct Secondary {
    /// The ray, starting just off the surface.
    pub ray: Ray,
    /// Factor on the radiance it returns.
    pub weight: Vec3,
    /// Reflection or refraction.
    pub bounce: Bounce,
}

/// What a hit contributes: its own radiance and up to two secondary rays.
#[derive(Clone, Copy, Debug)]
pub struct Scatter {
    /// Emitted plus directly lit radiance towards the viewer.
    pub local: Vec3,
    /// Reflection and refraction rays, if any.
    pub secondary: [Option<Secondary>; 2],
}

/// A counter the rayon workers bump on the hot path without contending:
/// one cache line per worker slot, summed when read.
#[derive(Debug, Default)]
pub struct RayCounter {
    slots: [Slot; COUNTER_SLOTS],
}

/// Worker slots of a [`RayCounter`] (workers beyond share slots).
const COUNTER_SLOTS: usize = 16;

#[derive(Debug, Default)]
#[repr(align(64))]
struct Slot(AtomicU64);

impl RayCounter {
    /// Add `n`.
    #[inline]
    pub fn add(&self, n: u64) {
        let i = rayon::current_thread_index().unwrap_or(0) % COUNTER_SLOTS;
        self.slots[i].0.fetch_add(n, Ordering::Relaxed);
    }

    /// The total so far.
    pub fn get(&self) -> u64 {
        self.slots.iter().map(|s| s.0.load(Ordering::Relaxed)).sum()
    }
}

/// Ray counts of a frame.
#[derive(Debug, Default)]
pub struct RayCounts {
    /// Camera rays traced (not rasterized).
    pub primary: RayCounter,
    /// Shadow rays traced.
    pub shadow: RayCounter,
    /// Reflection and refraction rays traced.
    pub secondary: RayCounter,
    /// Rays that left the scene and took the environment's radiance.
    pub environment: RayCounter,
}

impl RayCounts {
    /// All rays traced.
    pub fn total(&self) -> u64 {
        self.primary.get() + self.shadow.get() + self.secondary.get()
    }
}

/// Everything the kernel shades against.
pub struct Tracer<'a> {
    /// The geometry.
    pub mesh: &'a TriangleMesh,
    /// An accel built on `mesh`.
    pub accel: &'a dyn Accel,
    /// Lights.
    pub lights: &'a [Light],
    /// What rays leaving the scene see.
    pub environment: &'a Environment,
    /// Occlusion source.
    pub shadows: ShadowSource<'a>,
    /// Ambient radiance.
    pub ambient: Vec3,
    /// Longest path in rays, counting the camera ray.
    pub max_depth: u32,
    /// Offset of secondary and shadow rays off the surface.
    pub bias: f32,
    /// Ray counters.
    pub counts: RayCounts,
    fallback: Material,
}

impl<'a> Tracer<'a> {
    /// A kernel over `mesh` and `accel`; the offset is [`shadow_bias`].
    pub fn new(
        mesh: &'a TriangleMesh,
        accel: &'a dyn Accel,
        lights: &'a [Light],
        environment: &'a Environment,
        shadows: ShadowSource<'a>,
        ambient: Vec3,
        max_depth: u32,
    ) -> Self {
        Tracer {
            mesh,
            accel,
            lights,
            environment,
            shadows,
            ambient,
            max_depth: max_depth.max(1),
            bias: shadow_bias(mesh),
            counts: RayCounts::default(),
            fallback: Material::default(),
        }
    }

    /// Radiance of a ray that left the scene.
    pub fn miss(&self, ray: &Ray) -> Vec3 {
        self.counts.environment.add(1);
        self.environment.radiance(ray.origin, ray.dir())
    }

    /// The surface at a hit.
    pub fn surface(&self, ray: &Ray, hit: &Hit) -> Surface<'_> {
        Surface::at(self.mesh, ray, hit, &self.fallback)
    }

    /// Shade the hit `hit` of `ray`, the `depth`-th ray of its path (the
    /// camera ray is depth 1).
    pub fn scatter(&self, ray: &Ray, hit: &Hit, depth: u32) -> Scatter {
        let s = self.surface(ray, hit);
        let m = s.material;
        let d = ray.dir().normalize_or_zero();
        let t = m.transmission.clamp(0.0, 1.0);
        let r = m.reflectivity.clamp(0.0, 1.0);
        let mut local = Vec3::from(m.emission);
        let opaque_diffuse = (1.0 - t) * (1.0 - r);
        if opaque_diffuse > 0.0 {
            local += opaque_diffuse * self.direct(&s, -d);
        }
        let mut secondary = [None, None];
        if depth >= self.max_depth || (t == 0.0 && r == 0.0) {
            return Scatter { local, secondary };
        }
        let eta = if s.front_face { 1.0 / m.ior } else { m.ior };
        // The shading normal bends reflection and refraction smoothly; where
        // it would send a ray to the wrong side of the triangle, both use the
        // geometric normal, so the Fresnel weights and directions agree.
        let ng = s.geometric_normal;
        let mut n = s.shading_normal;
        if reflect(d, n).dot(ng) <= 0.0
            || (t > 0.0 && refract(d, n, eta).is_some_and(|r| r.dot(ng) >= 0.0))
        {
            n = ng;
        }
        let cos_i = (-d.dot(n)).clamp(0.0, 1.0);
        let fresnel = if t > 0.0 {
            fresnel_dielectric(cos_i, eta)
        } else {
            0.0
        };
        let reflect_weight = (1.0 - t) * r * fresnel_schlick(cos_i, Vec3::from(m.specular))
            + Vec3::splat(t * fresnel);
        if reflect_weight.max_element() > 0.0 {
            secondary[0] = Some(Secondary {
                ray: Ray::new(s.point + ng * self.bias, reflect(d, n)),
                weight: reflect_weight,
                bounce: Bounce::Reflection,
            });
        }
        if t > 0.0 && fresnel < 1.0 {
            if let Some(dir) = refract(d, n, eta) {
                secondary[1] = Some(Secondary {
                    ray: Ray::new(s.point - ng * self.bias, dir),
                    weight: t * (1.0 - fresnel) * s.diffuse,
                    bounce: Bounce::Refraction,
                });
            }
        }
        Scatter { local, secondary }
    }

    /// Blinn-Phong direct lighting of `s` seen from `view`, with this
    /// kernel's shadow source.
    pub fn direct(&self, s: &Surface, view: Vec3) -> Vec3 {
        blinn_phong(s, view, self.lights, self.ambient, &mut |i, ls| {
            self.visibility(i, s, ls)
        })
    }

    /// How much of light `light` (sample `ls`) reaches `s`.
    fn visibility(&self, light: usize, s: &Surface, ls: &LightSample) -> f32 {
        match self.shadows {
            ShadowSource::Off => 1.0,
            ShadowSource::Rays => {
                self.counts.shadow.add(1);
                let ray = shadow_ray(s, ls, self.bias);
                if self.accel.occluded(&ray) {
                    0.0
                } else {
                    1.0
                }
            }
            ShadowSource::Maps(maps) => maps.visibility(light, s.point, s.geometric_normal),
        }
    }

    /// Trace `ray` (a secondary or camera ray, the `depth`-th of its path)
    /// and return the radiance it brings back, recursively.
    pub fn radiance(&self, ray: &Ray, depth: u32) -> Vec3 {
        match self.accel.intersect(ray) {
            Some(hit) => self.shade_recursive(ray, &hit, depth),
            None => self.miss(ray),
        }
    }

    /// Radiance leaving the hit `hit` of `ray` towards its origin, following
    /// secondary rays depth-first.
    pub fn shade_recursive(&self, ray: &Ray, hit: &Hit, depth: u32) -> Vec3 {
        let sc = self.scatter(ray, hit, depth);
        let mut out = sc.local;
        for sec in sc.secondary.iter().flatten() {
            self.counts.secondary.add(1);
            out += sec.weight * self.radiance(&sec.ray, depth + 1);
        }
        out
    }

    /// The chain of refraction rays a camera ray follows through dielectrics
    /// (the transmitted branch at every hit, up to `max_depth` rays): what the
    /// renderer traces, exposed for checks against Snell's law.
    pub fn transmitted_path(&self, ray: &Ray) -> Vec<Ray> {
        let mut path = vec![*ray];
        let mut cur = *ray;
        for depth in 1..self.max_depth {
            let Some(hit) = self.accel.intersect(&cur) else {
                break;
            };
            let sc = self.scatter(&cur, &hit, depth);
            match sc.secondary[1] {
                Some(sec) => {
                    path.push(sec.ray);
                    cur = sec.ray;
                }
                None => break,
            }
        }
        path
    }
}
