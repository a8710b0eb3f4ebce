//! Nearest-hit and occlusion queries on an instanced scene: the top level
//! walked nearest box first, each instance's bottom-level BVH traced with
//! the ray in object space.

use super::hit::SceneHit;
use super::scene::InstancedScene;
use crate::hit::Hit;
use crate::ray::Ray;

impl InstancedScene {
    /// The [`SceneHit`] of instance `instance`'s triangle hit `h`.
    #[inline]
    pub(crate) fn scene_hit(&self, instance: u32, h: &Hit) -> SceneHit {
        let inst = &self.instances[instance as usize];
        let g = &self.geometries[inst.geometry as usize];
        SceneHit {
            t: h.t,
            u: h.u,
            v: h.v,
            prim: h.prim,
            geometry: inst.geometry,
            instance,
            normal: inst.transform.world_normal(g.face_cross(h.prim)),
        }
    }

    /// Nearest hit with `t` in `[ray.tnear, ray.tfar]` among the instances
    /// that `mask` sees. Each instance's triangles are tested by its
    /// geometry's [`crate::accel::Bvh8`] (Möller–Trumbore with its
    /// watertight tolerance); at equal `t` the instance walked first keeps
    /// the hit.
    pub fn intersect(&self, ray: &Ray, mask: u32) -> Option<SceneHit> {
        let mut best: Option<(Hit, u32)> = None;
        let best_t = std::cell::Cell::new(ray.tfar);
        self.top.walk(
            ray,
            || best_t.get(),
            |i| {
                let inst = &self.instances[i as usize];
                if !self.visible(inst, mask) {
                    return true;
                }
                let oray = inst.transform.object_ray(ray, best_t.get());
                let g = &self.geometries[inst.geometry as usize];
                if let Some(h) = g.intersect(&oray) {
                    if best.is_none_or(|(b, _)| h.t < b.t) {
                        best_t.set(h.t);
                        best = Some((h, i));
                    }
                }
                true
            },
        );
        best.map(|(h, i)| self.scene_hit(i, &h))
    }

    /// True when any instance that `mask` sees is hit with `t` in
    /// `[ray.tnear, ray.tfar]`; stops at the first one found.
    pub fn occluded(&self, ray: &Ray, mask: u32) -> bool {
        let mut hit = false;
        self.top.walk(
            ray,
            || ray.tfar,
            |i| {
                let inst = &self.instances[i as usize];
                if !self.visible(inst, mask) {
                    return true;
                }
                let oray = inst.transform.object_ray(ray, ray.tfar);
                hit = self.geometries[inst.geometry as usize].occluded(&oray);
                !hit
            },
        );
        hit
    }
}
