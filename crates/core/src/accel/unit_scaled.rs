//! [`UnitScaled`]: a structure built over a tiny model at unit scale
//! ([`crate::unit_scale`]), answering in the model's units.

use super::{Accel, AccelStats, PersistError, RefitError, RefitReport};
use crate::aabb::Aabb;
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::unit_scale::UnitScale;

/// A structure built over a model scaled by [`UnitScale`], so that the
/// triangle tests' products of coordinates (Möller and Trumbore 1997) stay
/// in `f32`'s normal range; rays are scaled in and hits, regions and saved
/// files scaled back, so that it answers exactly as the same structure
/// over the model at unit size, in the model's units. [`super::build_accel`]
/// and [`super::load_accel`] wrap a structure in it when the model is
/// smaller than [`crate::unit_scale::SCALED_BELOW`]; an instanced scene's
/// geometries hold their [`super::Bvh8`] in it.
pub struct UnitScaled<A: Accel + ?Sized = dyn Accel> {
    scale: UnitScale,
    inner: Box<A>,
}

impl UnitScaled {
    /// `inner`, built over a model scaled by `scale`; itself when `scale`
    /// is one.
    pub fn wrap(inner: Box<dyn Accel>, scale: UnitScale) -> Box<dyn Accel> {
        if scale.is_one() {
            return inner;
        }
        Box::new(UnitScaled { scale, inner })
    }
}

impl<A: Accel> UnitScaled<A> {
    /// `inner`, built over a model scaled by `scale` (one for a model of
    /// ordinary size).
    pub fn new(inner: A, scale: UnitScale) -> Self {
        UnitScaled {
            scale,
            inner: Box::new(inner),
        }
    }

    /// The scale the structure was built at.
    pub fn scale(&self) -> UnitScale {
        self.scale
    }
}

impl<A: Accel + ?Sized> Accel for UnitScaled<A> {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let hit = self.inner.intersect(&self.scale.ray(ray))?;
        Some(self.scale.hit_to_model(hit))
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.inner.occluded(&self.scale.ray(ray))
    }

    fn stats(&self) -> AccelStats {
        self.inner.stats()
    }

    fn visit_regions(&self, enter: &mut dyn FnMut(&Aabb) -> bool, leaf: &mut dyn FnMut(&[u32])) {
        let scale = self.scale;
        self.inner
            .visit_regions(&mut |b| enter(&scale.aabb_to_model(b)), leaf);
    }

    /// Saved over the model at unit scale, as [`super::load_accel`] loads
    /// it again.
    fn save(&self, path: &std::path::Path, mesh: &TriangleMesh) -> Result<(), PersistError> {
        self.inner
            .save_at_scale(path, &self.scale.mesh(mesh), self.scale)
    }

    /// Refit at the scale the structure was built at.
    fn refit(&mut self, mesh: &TriangleMesh) -> Result<RefitReport, RefitError> {
        self.inner.refit(&self.scale.mesh(mesh))
    }

    /// The rays scaled a run at a time, in parallel: a copy of the whole
    /// batch, made on one thread, cost a far model's Plücker primaries
    /// (1024², one thread) about a fifth of their speed.
    fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        in_runs(rays, hits, self.scale, |r, h| {
            self.inner.intersect_batch(r, h);
            self.scale.hits_to_model(h);
        });
    }

    fn occluded_batch(&self, rays: &[Ray], occluded: &mut [bool]) {
        in_runs(rays, occluded, self.scale, |r, o| {
            self.inner.occluded_batch(r, o)
        });
    }
}

/// Rays scaled in runs of [`RUN`] (a run's copy stays below the
/// allocator's threshold for mapping fresh pages), each run answered by
/// `answer` into its part of `out`, the runs in parallel; at scale one
/// (an instanced geometry of ordinary size), the rays as they are, in one
/// call.
fn in_runs<T: Send>(
    rays: &[Ray],
    out: &mut [T],
    scale: UnitScale,
    answer: impl Fn(&[Ray], &mut [T]) + Sync,
) {
    use rayon::prelude::*;
    if scale.is_one() {
        return answer(rays, out);
    }
    rays.par_chunks(RUN)
        .zip(out.par_chunks_mut(RUN))
        .for_each(|(r, o)| answer(&scale.rays(r), o));
}

/// Rays scaled at a time by a batch: 32 KiB of rays, four of the batches'
/// parallel grains ([`super::BATCH_GRAIN`]).
const RUN: usize = 4 * super::BATCH_GRAIN;
