//! Multi-hit ray queries on an instanced scene: every hit along a ray
//! sorted by `t` (with a cap, which makes it the first `k` hits), the
//! number of hits, and any-hit with a filter callback.
//!
//! Each instance's triangles are crossed through its geometry's
//! [`crate::query::SurfaceBvh`] (made on the first such query), which
//! counts a crossing at an edge or a corner that triangles share once, as
//! [`crate::query::all_hits`] describes for one mesh; the filter sees
//! each candidate as a [`SceneHit`], with its ids and world normal.

use super::hit::SceneHit;
use super::scene::InstancedScene;
use crate::query::QueryKind;
use crate::ray::Ray;

/// The hits kept: sorted by `(t, instance, prim)`, at most `cap`.
struct Kept<'a> {
    hits: &'a mut Vec<SceneHit>,
    cap: usize,
}

impl Kept<'_> {
    /// The farthest `t` still worth looking at.
    fn reach(&self, tfar: f32) -> f32 {
        if self.hits.len() >= self.cap {
            self.hits.last().map_or(tfar, |h| h.t)
        } else {
            tfar
        }
    }

    fn insert(&mut self, h: SceneHit) {
        let key = |x: &SceneHit| (x.t, x.instance, x.prim);
        let at = self.hits.partition_point(|x| key(x) <= key(&h));
        if at >= self.cap {
            return;
        }
        self.hits.insert(at, h);
        self.hits.truncate(self.cap);
    }
}

impl InstancedScene {
    /// Make the surfaces and ray-casting trees of the geometries whose
    /// instances `mask` sees, which the multi-hit queries would otherwise
    /// make on first use: the batches call this before their parallel
    /// loops, where making them could deadlock (see
    /// [`crate::query::SurfaceBvh`]).
    pub fn prepare_multi_hit(&self, mask: u32) {
        let mut made = vec![false; self.geometries.len()];
        for inst in &self.instances {
            let g = inst.geometry as usize;
            if self.visible(inst, mask) && !std::mem::replace(&mut made[g], true) {
                self.geometries[g].surface().prepare(QueryKind::Count);
            }
        }
    }

    /// The hits along `ray` (`t` in `[ray.tnear, ray.tfar]`) on the
    /// instances `mask` sees that `accept` keeps, sorted by `t` (then
    /// instance, then triangle), at most `max_hits` of them (the nearest),
    /// written to `out` (cleared first). A ray that is not valid has none.
    pub fn ray_hits_filtered<F: FnMut(&SceneHit) -> bool>(
        &self,
        ray: &Ray,
        mask: u32,
        max_hits: usize,
        mut accept: F,
        out: &mut Vec<SceneHit>,
    ) {
        out.clear();
        if max_hits == 0 {
            return;
        }
        let kept = std::cell::RefCell::new(Kept {
            hits: out,
            cap: max_hits,
        });
        let mut found = Vec::new();
        self.top.walk(
            ray,
            || kept.borrow().reach(ray.tfar),
            |i| {
                let inst = &self.instances[i as usize];
                if !self.visible(inst, mask) {
                    return true;
                }
                let reach = kept.borrow().reach(ray.tfar);
                let oray = inst.transform.object_ray(ray, reach);
                let surface = self.geometries[inst.geometry as usize].surface();
                surface.ray_hits_filtered(&oray, max_hits, |_| true, &mut found);
                for h in &found {
                    let sh = self.scene_hit(i, h);
                    if accept(&sh) {
                        kept.borrow_mut().insert(sh);
                    }
                }
                true
            },
        );
    }

    /// Every hit along `ray` on the instances `mask` sees, sorted by `t`,
    /// at most `max_hits` (the nearest); see
    /// [`InstancedScene::ray_hits_filtered`].
    pub fn ray_hits(&self, ray: &Ray, mask: u32, max_hits: usize) -> Vec<SceneHit> {
        let mut out = Vec::new();
        self.ray_hits_filtered(ray, mask, max_hits, |_| true, &mut out);
        out
    }

    /// The `k` nearest hits along `ray`, sorted by `t`.
    pub fn first_hits(&self, ray: &Ray, mask: u32, k: usize) -> Vec<SceneHit> {
        self.ray_hits(ray, mask, k)
    }

    /// Number of triangle crossings along `ray` (`t` in `[ray.tnear,
    /// ray.tfar]`) on the instances `mask` sees.
    pub fn count_hits(&self, ray: &Ray, mask: u32) -> u32 {
        let mut n = 0u32;
        self.top.walk(
            ray,
            || ray.tfar,
            |i| {
                let inst = &self.instances[i as usize];
                if self.visible(inst, mask) {
                    let oray = inst.transform.object_ray(ray, ray.tfar);
                    n += self.geometries[inst.geometry as usize]
                        .surface()
                        .count_hits(&oray);
                }
                true
            },
        );
        n
    }

    /// Any hit on the instances `mask` sees that `accept` takes (the first
    /// found, not the nearest), for example
    /// `|h| !h.is_back_face(ray.dir)`; stops at the first accepted hit.
    pub fn any_hit_filtered<F: FnMut(&SceneHit) -> bool>(
        &self,
        ray: &Ray,
        mask: u32,
        mut accept: F,
    ) -> Option<SceneHit> {
        let mut found = None;
        self.top.walk(
            ray,
            || ray.tfar,
            |i| {
                let inst = &self.instances[i as usize];
                if !self.visible(inst, mask) {
                    return true;
                }
                let oray = inst.transform.object_ray(ray, ray.tfar);
                let surface = self.geometries[inst.geometry as usize].surface();
                found = surface
                    .any_hit(&oray, |h| accept(&self.scene_hit(i, h)))
                    .map(|h| self.scene_hit(i, &h));
                found.is_none()
            },
        );
        found
    }
}
