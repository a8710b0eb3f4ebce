//! The queries of an instanced scene for many rays at once, in parallel
//! over the rayon pool.

use super::hit::SceneHit;
use super::scene::InstancedScene;
use crate::accel::BATCH_GRAIN;
use crate::query::batch::answer_each;
use crate::ray::Ray;
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

    /// [`InstancedScene::count_hits`] for every ray, in parallel.
    pub fn count_hits_batch(&self, rays: &[Ray], mask: u32, counts: &mut [u32]) {
        answer_each(rays, counts, |r| self.count_hits(r, mask));
    }

    /// [`InstancedScene::ray_hits`] for every ray, in parallel: one sorted
    /// list per ray.
    pub fn ray_hits_batch(&self, rays: &[Ray], mask: u32, max_hits: usize) -> Vec<Vec<SceneHit>> {
        rays.par_iter()
            .with_min_len(BATCH_GRAIN)
            .map(|r| self.ray_hits(r, mask, max_hits))
            .collect()
    }
}
