//! Whether a packet's rays lie close enough together to be traced as one.
//!
//! Sharing an octant makes each lane's box test the single-ray one, but it
//! does not make the rays coherent. Rays in one direction from points
//! scattered over the scene (a sun's shadow rays from unordered sample
//! points), or rays of one octant in random directions (a batch sorted by
//! octant), share an octant and part at the root: the packet then visits
//! the union of their paths with few lanes active. On the full dragon
//! such packets ran 1.6-2.6x slower than the same rays one by one
//! (BENCHMARKS.md). A full packet is traced together only when its rays
//! start, or end, within a small part of the scene, as a camera's
//! primaries and the shadow rays of their hits do (Wald et al. 2001 trace
//! the packets of neighbouring pixels). A batch's last, partial packet is
//! not checked.

use crate::ray::Ray;
use glam::Vec3;

/// Farthest a packet's origins (or ends) lie from its first ray's, per
/// axis, as a fraction of the largest side of the tree's box.
const ORIGIN_SPREAD: f32 = 1.0 / 4.0;

/// Whether `rays`, a full packet, are close enough together to be traced
/// as one through a tree whose box's largest side is `extent`, judged by
/// the middle and last rays against the first: their origins, or the ends
/// of their segments, within [`ORIGIN_SPREAD`] of it of the first's on
/// every axis. Shadow rays towards a point light start apart where a tile
/// of pixels crosses an edge, and end together; a camera's rays start
/// together and part slowly. Rays that are not finite fail. Three rays
/// stand for the packet because the test runs on every packet, before it
/// is formed: a batch whose order puts rays apart puts these apart too.
#[inline(always)]
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
pub(crate) fn close_together(rays: &[Ray], extent: f32) -> bool {
    let limit = ORIGIN_SPREAD * extent;
    let close = |a: Vec3, b: Vec3| {
        // NaN and infinite differences fail.
        let d = (a - b).abs();
        d.x <= limit && d.y <= limit && d.z <= limit
    };
    let first = &rays[0];
    [rays.len() / 2, rays.len() - 1].iter().all(|&l| {
        let r = &rays[l];
        close(r.origin, first.origin) || close(r.at(r.tfar), first.at(first.tfar))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(rays: &[Ray], extent: f32) -> bool {
        assert_eq!(rays.len(), 16);
        close_together(rays, extent)
    }

    /// A camera's neighbouring rays, a fan from one point and segments to
    /// one light are close together; rays in one direction, or in
    /// scattered directions, from scattered points are not, unless the
    /// scene is much larger; an origin that is not finite fails.
    #[test]
    fn neighbouring_rays_are_close_and_scattered_ones_not() {
        let eye = Vec3::new(0.5, 0.5, 3.0);
        let camera: Vec<Ray> = (0..16)
            .map(|k| {
                let (x, y) = ((k % 4) as f32, (k / 4) as f32);
                Ray::new(eye, Vec3::new(0.01 * x, 0.01 * y, -1.0))
            })
            .collect();
        assert!(close(&camera, 1.0));
        // A row of sixteen pixels, 40 degrees over 128.
        let row: Vec<Ray> = (0..16)
            .map(|k| {
                let a = (k as f32 / 128.0 * 40.0).to_radians();
                Ray::new(eye, Vec3::new(a.sin(), 0.0, -a.cos()))
            })
            .collect();
        assert!(close(&row, 1.0));
        let sun: Vec<Ray> = (0..16)
            .map(|k| {
                Ray::new(
                    Vec3::new(k as f32 / 16.0, 0.3, 0.2),
                    Vec3::new(0.3, 0.8, 0.5),
                )
            })
            .collect();
        assert!(!close(&sun, 1.0));
        // The same rays in a scene sixteen times larger are close.
        assert!(close(&sun, 16.0));
        // Segments from scattered points to one light end together.
        let light = Vec3::new(0.3, 20.0, 0.2);
        let shadow: Vec<Ray> = (0..16)
            .map(|k| {
                let o = Vec3::new(k as f32 / 16.0, 0.1 * (k % 3) as f32, 0.5);
                Ray::segment(o, light - o, 1e-4, 1.0)
            })
            .collect();
        assert!(close(&shadow, 1.0));
        // Rays of one octant from scattered points in scattered directions.
        let mut rng = crate::rng::Pcg32::new(3);
        let scattered: Vec<Ray> = (0..16)
            .map(|_| {
                let o = rng.in_box(Vec3::ZERO, Vec3::ONE);
                Ray::new(o, rng.in_box(Vec3::splat(0.1), Vec3::ONE))
            })
            .collect();
        assert!(!close(&scattered, 1.0));
        // A fan from one point starts together.
        let fan: Vec<Ray> = (0..16)
            .map(|k| Ray::new(eye, Vec3::new(0.1 + k as f32 / 16.0, 0.2, 1.0)))
            .collect();
        assert!(close(&fan, 1.0));
        let mut broken = camera.clone();
        broken[8] = Ray::new(Vec3::NAN, Vec3::Z);
        assert!(!close(&broken, 1.0));
    }
}
