//! The Purcell-style stream tracer's stream organisation of the Whitted integrator: instead of
//! following each path depth-first, every stage runs as one batch over a
//! queue of rays:
//!
//! ```text
//! generate → intersect → miss/environment → shade → next-bounce queue → intersect → …
//! ```
//!
//! Each queue entry carries its pixel, the weight of what it brings back
//! (the product of the reflection/refraction weights along its path) and its
//! depth. After intersection a ray is in one of the paper's states:
//! [`RayState::Missed`] (−1) goes to the environment stage, which leaves it
//! [`RayState::DoneByEnvironment`] (−2); a hit is shaded and either spawns
//! next-bounce rays ([`RayState::Bounced`]) or ends on a surface with no
//! further bounce ([`RayState::Diffuse`], −3). Contributions are added to
//! the pixels in queue order. The shading kernel is the one the recursive
//! integrator uses ([`super::Tracer::scatter`]), so both give the same image
//! up to the order of floating-point additions.

use super::tracer::Tracer;
use raykit_core::glam::Vec3;
use raykit_core::{Hit, Ray};
use rayon::prelude::*;

/// Rays per parallel batch of the intersect stage.
const BATCH: usize = 4096;

/// The state of a queued ray after a stage, numbered as in the Purcell-style stream tracer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayState {
    /// Waiting for intersection.
    Active,
    /// Missed every triangle (−1): the environment stage takes it.
    Missed,
    /// Finished by the environment stage (−2).
    DoneByEnvironment,
    /// Ended on a surface that spawns no further ray (−3).
    Diffuse,
    /// Shaded, and spawned reflection or refraction rays.
    Bounced,
}

impl RayState {
    /// The paper's code: −1, −2, −3 for the finished states, 0 for active
    /// and 1 for bounced.
    pub fn code(self) -> i32 {
        match self {
            RayState::Active => 0,
            RayState::Missed => -1,
            RayState::DoneByEnvironment => -2,
            RayState::Diffuse => -3,
            RayState::Bounced => 1,
        }
    }
}

/// One queued ray.
#[derive(Clone, Copy, Debug)]
struct QueuedRay {
    ray: Ray,
    pixel: u32,
    weight: Vec3,
    depth: u32,
    state: RayState,
}

/// One sample of every pixel through the stages; adds the radiance to `sum`
/// and returns the first hits. `primary` holds rasterized first hits, if the
/// caller rasterized them.
pub fn wavefront_pass(
    tracer: &Tracer,
    width: u32,
    height: u32,
    ray_of: &(dyn Fn(u32, u32) -> Ray + Sync),
    primary: Option<Vec<Option<Hit>>>,
    sum: &mut [Vec3],
) -> Vec<Option<Hit>> {
    // Stage 1: ray generation.
    let mut queue: Vec<QueuedRay> = (0..height)
        .into_par_iter()
        .flat_map_iter(|y| {
            (0..width).map(move |x| QueuedRay {
                ray: ray_of(x, y),
                pixel: y * width + x,
                weight: Vec3::ONE,
                depth: 1,
                state: RayState::Active,
            })
        })
        .collect();
    let mut first_hits = None;
    let mut primary = primary;
    while !queue.is_empty() {
        // Stage 2: intersection (or the rasterized visibility buffer).
        let hits = match primary.take() {
            Some(vis) => vis,
            None => intersect_stage(tracer, &queue),
        };
        for (q, h) in queue.iter_mut().zip(&hits) {
            if h.is_none() {
                q.state = RayState::Missed;
            }
        }
        // Stages 3 and 4: environment for the missed rays, shading for the
        // hits; both produce a contribution, shading also next-bounce rays.
        let shaded: Vec<(Vec3, RayState, [Option<QueuedRay>; 2])> = queue
            .par_iter()
            .zip(&hits)
            .map(|(q, h)| match h {
                None => (
                    q.weight * tracer.miss(&q.ray),
                    RayState::DoneByEnvironment,
                    [None; 2],
                ),
                Some(hit) => {
                    let sc = tracer.scatter(&q.ray, hit, q.depth);
                    let next = sc.secondary.map(|s| {
                        s.map(|s| QueuedRay {
                            ray: s.ray,
                            pixel: q.pixel,
                            weight: q.weight * s.weight,
                            depth: q.depth + 1,
                            state: RayState::Active,
                        })
                    });
                    let state = if next.iter().any(Option::is_some) {
                        RayState::Bounced
                    } else {
                        RayState::Diffuse
                    };
                    (q.weight * sc.local, state, next)
                }
            })
            .collect();
        if first_hits.is_none() {
            first_hits = Some(hits);
        }
        // Stage 5: accumulate in queue order, and build the next queue.
        let mut next = Vec::new();
        for (q, (contribution, state, spawned)) in queue.iter_mut().zip(shaded) {
            sum[q.pixel as usize] += contribution;
            q.state = state;
            next.extend(spawned.into_iter().flatten());
        }
        tracer.counts.secondary.add(next.len() as u64);
        queue = next;
    }
    first_hits.unwrap_or_default()
}

/// Intersect every queued ray, in parallel batches.
fn intersect_stage(tracer: &Tracer, queue: &[QueuedRay]) -> Vec<Option<Hit>> {
    let rays: Vec<Ray> = queue.iter().map(|q| q.ray).collect();
    let mut hits = vec![None; rays.len()];
    if queue.first().is_some_and(|q| q.depth == 1) {
        tracer.counts.primary.add(rays.len() as u64);
    }
    rays.par_chunks(BATCH)
        .zip(hits.par_chunks_mut(BATCH))
        .for_each(|(r, h)| tracer.accel.intersect_batch(r, h));
    hits
}
