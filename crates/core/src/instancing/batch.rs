//! The queries of an instanced scene for many rays at once, in parallel
//! over the rayon pool.
//!
//! Nearest hits and occlusion are traced instance by instance where that
//! pays: a task's rays are sorted by the instances whose boxes they enter,
//! and each instance gets its rays together, moved into its space and cut
//! at their nearest hit so far, through its geometry's batch path. Rays of
//! one image stay in order within an instance, so the bottom level's
//! coherent packets (Wald et al. 2001) form there as in a scene without
//! instances, and incoherent rays go through its walks stepped in turn.
//! It pays for rays that leave one point (a pinhole camera's, a point
//! light's shadow rays), which also orders the instances front to back, and
//! for rays that enter few instance boxes each; other rays are traced one
//! at a time, nearest instance box first, which prunes better where the
//! boxes overlap ([`InstancedScene::by_instance`]).

use super::hit::SceneHit;
use super::scene::InstancedScene;
use crate::accel::BATCH_GRAIN;
use crate::hit::Hit;
use crate::query::batch::answer_each;
use crate::ray::Ray;
use glam::{Affine3A, Vec3};
use rayon::prelude::*;
use std::ops::Range;

/// Rays per task of the instance-by-instance batches: an image row of the
/// standard 1024² sets, so that each instance gets runs of neighbouring
/// rays long enough for packets.
const INSTANCED_CHUNK: usize = 1024;

/// Instances in the order traced, each with its range of the ray indices
/// that follow (see [`InstancedScene::by_instance`]).
type Plan = (Vec<(u32, Range<usize>)>, Vec<u32>);

/// Boxes entered per ray, on average, up to which rays from many points
/// are traced instance by instance.
const MOST_BOXES_PER_RAY: f32 = 1.5;

/// Rays from many points whose boxes are counted before the rest are
/// walked: when they enter too many, the task is traced ray by ray.
const SAMPLED_RAYS: usize = 64;

/// Most instances a cone round rays from one point may hold for each of
/// them to get every ray: each costs its root's test of every ray, so
/// with more the top level is walked ray by ray.
const MOST_INSTANCES_IN_CONE: usize = 4;

/// True when `boxes` entered by `rays` rays are more than
/// [`MOST_BOXES_PER_RAY`] each.
fn too_many(boxes: usize, rays: usize) -> bool {
    boxes as f32 > MOST_BOXES_PER_RAY * rays as f32
}

impl InstancedScene {
    /// [`InstancedScene::intersect`] for every ray, in parallel, traced
    /// instance by instance where that pays (see the module documentation).
    /// At equal `t` the instance traced first keeps the hit, which may
    /// differ from the single-ray walk's choice between coincident faces.
    pub fn intersect_batch(&self, rays: &[Ray], mask: u32, hits: &mut [Option<SceneHit>]) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        self.in_tasks(
            rays,
            mask,
            hits,
            |rays, plan, hits| self.intersect_chunk(rays, plan, hits),
            |r| self.intersect(r, mask),
        );
    }

    /// [`InstancedScene::occluded`] for every ray, in parallel, traced
    /// instance by instance where that pays (see the module documentation).
    pub fn occluded_batch(&self, rays: &[Ray], mask: u32, occluded: &mut [bool]) {
        assert_eq!(rays.len(), occluded.len(), "one result per ray");
        self.in_tasks(
            rays,
            mask,
            occluded,
            |rays, plan, occluded| self.occluded_chunk(rays, plan, occluded),
            |r| self.occluded(r, mask),
        );
    }

    /// Answer `rays` into `out` in parallel tasks of [`INSTANCED_CHUNK`]:
    /// a task that [`InstancedScene::by_instance`] plans by `planned`, any
    /// other ray by ray by `single`.
    fn in_tasks<O: Send>(
        &self,
        rays: &[Ray],
        mask: u32,
        out: &mut [O],
        planned: impl Fn(&[Ray], Plan, &mut [O]) + Sync,
        single: impl Fn(&Ray) -> O + Sync,
    ) {
        rays.par_chunks(INSTANCED_CHUNK)
            .zip(out.par_chunks_mut(INSTANCED_CHUNK))
            .for_each(|(rays, out)| match self.by_instance(rays, mask) {
                Some(plan) => planned(rays, plan, out),
                None => out.iter_mut().zip(rays).for_each(|(o, r)| *o = single(r)),
            });
    }

    /// How one task's `rays` are traced instance by instance: the
    /// instances that `mask` sees and whose boxes the rays may enter, each
    /// with its rays (`(instance, range)` pairs, the range into the ray
    /// indices returned with them), nearest to the first ray's origin
    /// first. `None` when the rays are better traced one at a time.
    ///
    /// Rays from one point: when a cone round them is narrow and holds few
    /// instances ([`MOST_INSTANCES_IN_CONE`]), the top level is walked once
    /// with it and each instance inside gets every ray (its own root
    /// rejects the rays that pass by); otherwise it is walked per ray.
    /// Either way the nearer instances come first, so their hits cut the
    /// rays before the farther ones are traced. Rays from
    /// many points get no such order, so they are traced instance by
    /// instance only when they enter few boxes each
    /// ([`MOST_BOXES_PER_RAY`], judged first on [`SAMPLED_RAYS`] rays);
    /// one at a time, a ray visits the boxes nearest first and stops at
    /// its hit.
    fn by_instance(&self, rays: &[Ray], mask: u32) -> Option<Plan> {
        let eye = rays.first().map_or(Vec3::ZERO, |r| r.origin);
        let key = |i: u32| {
            let inst = &self.instances[i as usize];
            self.visible(inst, mask).then(|| {
                let b = inst.world_box();
                // A distance's bits order as the distance does.
                (eye.clamp(b.min, b.max) - eye).length_squared().to_bits()
            })
        };
        // A cone holds the rays' forward halves only: rays that also reach
        // behind their origin (tnear < 0) are walked one by one.
        let one_origin = rays.iter().all(|r| r.origin == eye && r.tnear >= 0.0);
        if let Some(cone) = one_origin.then(|| RayCone::around(rays)).flatten() {
            let mut kept = Vec::new();
            self.top.each_kept(
                |min, max| cone.may_enter(min, max),
                |i| kept.extend(key(i).map(|key| (key, i))),
            );
            if kept.len() <= MOST_INSTANCES_IN_CONE {
                kept.sort_unstable();
                let valid: Vec<u32> = (0..rays.len() as u32)
                    .filter(|&k| rays[k as usize].is_valid())
                    .collect();
                let groups = kept.iter().map(|&(_, i)| (i, 0..valid.len())).collect();
                return Some((groups, valid));
            }
        }
        let mut triples = Vec::with_capacity(rays.len() * 2);
        let mut stack = self.top.stack();
        // The last instance's key: neighbouring rays enter the same ones.
        let mut last = (u32::MAX, None);
        for (k, r) in rays.iter().enumerate() {
            if k == SAMPLED_RAYS && !one_origin && too_many(triples.len(), k) {
                return None;
            }
            self.top.walk_on(
                &mut stack,
                r,
                || r.tfar,
                |i| {
                    if i != last.0 {
                        last = (i, key(i));
                    }
                    if let Some(key) = last.1 {
                        triples.push((key, i, k as u32));
                    }
                    true
                },
            );
        }
        if !one_origin && too_many(triples.len(), rays.len()) {
            return None;
        }
        if !triples.is_sorted() {
            triples.sort_unstable();
        }
        let mut groups = Vec::new();
        let mut at = 0;
        for g in triples.chunk_by(|a, b| a.1 == b.1) {
            groups.push((g[0].1, at..at + g.len()));
            at += g.len();
        }
        Some((groups, triples.iter().map(|t| t.2).collect()))
    }

    /// Nearest hits of one task's rays, instance by instance.
    fn intersect_chunk(&self, rays: &[Ray], plan: Plan, hits: &mut [Option<SceneHit>]) {
        let mut best: Vec<Option<(Hit, u32)>> = vec![None; rays.len()];
        let (mut moved, mut found) = (Vec::new(), Vec::new());
        let (groups, which) = plan;
        for (i, range) in groups {
            let group = &which[range];
            let inst = &self.instances[i as usize];
            moved.clear();
            moved.extend(group.iter().map(|&k| {
                let k = k as usize;
                let reach = best[k].map_or(rays[k].tfar, |(h, _)| h.t);
                inst.transform.object_ray(&rays[k], reach)
            }));
            found.clear();
            found.resize(moved.len(), None);
            self.geometries[inst.geometry as usize].intersect_batch(&moved, &mut found);
            for (&k, h) in group.iter().zip(&found) {
                if let Some(h) = h {
                    let b = &mut best[k as usize];
                    if b.is_none_or(|(b, _)| h.t < b.t) {
                        *b = Some((*h, i));
                    }
                }
            }
        }
        for (out, b) in hits.iter_mut().zip(&best) {
            *out = b.map(|(h, i)| self.scene_hit(i, &h));
        }
    }

    /// Occlusion of one task's rays, instance by instance; a ray found
    /// occluded is not traced again.
    fn occluded_chunk(&self, rays: &[Ray], plan: Plan, occluded: &mut [bool]) {
        occluded.fill(false);
        let (mut moved, mut open, mut found) = (Vec::new(), Vec::new(), Vec::new());
        let (groups, which) = plan;
        for (i, range) in groups {
            let inst = &self.instances[i as usize];
            moved.clear();
            open.clear();
            for &k in &which[range] {
                let k = k as usize;
                if !occluded[k] {
                    moved.push(inst.transform.object_ray(&rays[k], rays[k].tfar));
                    open.push(k);
                }
            }
            found.clear();
            found.resize(moved.len(), false);
            self.geometries[inst.geometry as usize].occluded_batch(&moved, &mut found);
            for (&k, &o) in open.iter().zip(&found) {
                occluded[k] |= o;
            }
        }
    }

    /// The one visible instance of a scene that holds one, placed as its
    /// geometry lies (the identity transform): its rays are the scene's
    /// rays, so the geometry's batch queries answer for the scene.
    fn single_in_place(&self, mask: u32) -> Option<u32> {
        match self.instances.as_slice() {
            [inst]
                if self.visible(inst, mask) && inst.transform.to_world() == Affine3A::IDENTITY =>
            {
                Some(0)
            }
            _ => None,
        }
    }

    /// [`InstancedScene::count_hits`] for every ray, in parallel (one
    /// geometry in place: its [`crate::query::SurfaceBvh::count_hits_batch`],
    /// the same counts with the rays walked in turn).
    pub fn count_hits_batch(&self, rays: &[Ray], mask: u32, counts: &mut [u32]) {
        if let Some(i) = self.single_in_place(mask) {
            let g = self.instances[i as usize].geometry;
            return self.geometries[g as usize]
                .surface()
                .count_hits_batch(rays, counts);
        }
        self.prepare_multi_hit(mask);
        answer_each(rays, counts, |r| self.count_hits(r, mask));
    }

    /// [`InstancedScene::ray_hits`] for every ray, in parallel: one sorted
    /// list per ray (one geometry in place: its
    /// [`crate::query::SurfaceBvh::ray_hits_batch`], the same lists).
    pub fn ray_hits_batch(&self, rays: &[Ray], mask: u32, max_hits: usize) -> Vec<Vec<SceneHit>> {
        if let Some(i) = self.single_in_place(mask) {
            let g = self.instances[i as usize].geometry;
            let lists = self.geometries[g as usize]
                .surface()
                .ray_hits_batch(rays, max_hits);
            return lists
                .into_par_iter()
                .map(|l| l.iter().map(|h| self.scene_hit(i, h)).collect())
                .collect();
        }
        self.prepare_multi_hit(mask);
        rays.par_iter()
            .with_min_len(BATCH_GRAIN)
            .map(|r| self.ray_hits(r, mask, max_hits))
            .collect()
    }
}

/// A cone from one point holding a set of rays: the point, the unit axis
/// and the half-angle.
struct RayCone {
    apex: Vec3,
    axis: Vec3,
    half: f32,
}

impl RayCone {
    /// Widest cone worth walking the top level with (radians); wider sets
    /// of rays are better walked one by one.
    const WIDEST: f32 = 1.0;

    /// The cone round the valid rays of `rays`, which leave one point;
    /// `None` when there are none or they spread wider than
    /// [`RayCone::WIDEST`].
    fn around(rays: &[Ray]) -> Option<RayCone> {
        let valid = || rays.iter().filter(|r| r.is_valid());
        let axis = valid()
            .map(|r| r.dir * r.dir.length_recip())
            .sum::<Vec3>()
            .normalize_or_zero();
        if axis == Vec3::ZERO {
            return None;
        }
        let cos = valid()
            .map(|r| r.dir.dot(axis) * r.dir.length_recip())
            .fold(1.0f32, f32::min);
        // A little wider, for the rounding of the cosines.
        let half = cos.clamp(-1.0, 1.0).acos() + 1e-4;
        (half <= Self::WIDEST).then(|| RayCone {
            apex: rays[0].origin,
            axis,
            half,
        })
    }

    /// False only when no ray of the cone can enter the box `[min, max]`
    /// (tested through the box's bounding sphere).
    fn may_enter(&self, min: Vec3, max: Vec3) -> bool {
        let to = (min + max) * 0.5 - self.apex;
        let radius = (max - min).length() * 0.5;
        let dist = to.length();
        if dist.is_nan() || dist <= radius * (1.0 + 1e-5) {
            return true;
        }
        let off_axis = (to.dot(self.axis) / dist).clamp(-1.0, 1.0).acos();
        off_axis <= self.half + (radius / dist).asin() + 1e-4
    }
}
