//! The queries of an instanced scene for many rays at once, in parallel
//! over the rayon pool.

use super::hit::SceneHit;
use super::scene::InstancedScene;
use crate::accel::BATCH_GRAIN;
use crate::query::batch::answer_each;
use crate::ray::Ray;
use glam::Affine3A;
use rayon::prelude::*;

impl InstancedScene {
    /// [`InstancedScene::intersect`] for every ray, in parallel.
    pub fn intersect_batch(&self, rays: &[Ray], mask: u32, hits: &mut [Option<SceneHit>]) {
        answer_each(rays, hits, |r| self.intersect(r, mask));
    }

    /// [`InstancedScene::occluded`] for every ray, in parallel.
    pub fn occluded_batch(&self, rays: &[Ray], mask: u32, occluded: &mut [bool]) {
        answer_each(rays, occluded, |r| self.occluded(r, mask));
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
        rays.par_iter()
            .with_min_len(BATCH_GRAIN)
            .map(|r| self.ray_hits(r, mask, max_hits))
            .collect()
    }
}
