//! The one-ray API over a whole ray set: each ray through
//! [`Accel::intersect`] or [`Accel::occluded`], as a library user calling
//! the structure once per ray does, with no packets or batch kernels. The
//! rayon pool splits the rays into contiguous runs of [`RUN`] rays; within
//! a run the rays go one call at a time. `raykit trace --one-ray` and the
//! one-ray cells of `raykit bench --compare` time it.

use raykit_core::{Accel, Hit, Ray};
use rayon::prelude::*;

/// Rays per rayon task: enough that scheduling costs nothing beside the
/// traversals, few enough that two threads stay balanced on 1024² rays.
pub const RUN: usize = 1024;

/// Nearest hits of `rays`, one [`Accel::intersect`] call per ray.
pub fn intersect_each(accel: &dyn Accel, rays: &[Ray], hits: &mut [Option<Hit>]) {
    assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
    rays.par_chunks(RUN)
        .zip(hits.par_chunks_mut(RUN))
        .for_each(|(r, h)| {
            for (ray, hit) in r.iter().zip(h) {
                *hit = accel.intersect(ray);
            }
        });
}

/// Occlusion of `rays`, one [`Accel::occluded`] call per ray.
pub fn occluded_each(accel: &dyn Accel, rays: &[Ray], occluded: &mut [bool]) {
    assert_eq!(rays.len(), occluded.len(), "one result per ray");
    rays.par_chunks(RUN)
        .zip(occluded.par_chunks_mut(RUN))
        .for_each(|(r, o)| {
            for (ray, o) in r.iter().zip(o) {
                *o = accel.occluded(ray);
            }
        });
}
