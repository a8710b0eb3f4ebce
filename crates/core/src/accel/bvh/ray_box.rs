//! A ray prepared for the slab tests of the wide nodes' boxes: origin,
//! reciprocal direction and the plane row met first along each axis, so
//! that a box test picks the near and far plane without a `min`/`max`
//! (see [`super::box4`]).

use crate::ray::Ray;

/// A ray prepared for the box tests of [`super::box4`] and [`super::box8`]: origin, reciprocal direction and, per
/// axis, the plane row met first.
#[derive(Clone, Copy, Debug)]
pub struct RayBox {
    pub(super) origin: [f32; 3],
    pub(super) inv_dir: [f32; 3],
    pub(super) near: [usize; 3],
}

impl RayBox {
    /// Prepare `ray`: a negative reciprocal direction (including `-∞` from
    /// `-0`) meets the maximum plane first.
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        let id = ray.inv_dir.to_array();
        RayBox {
            origin: ray.origin.to_array(),
            inv_dir: id,
            // Spelled out: `array::map`'s closure became a call inside
            // the traversals compiled for AVX2 (BENCHMARKS.md).
            near: [
                id[0].is_sign_negative() as usize,
                2 + id[1].is_sign_negative() as usize,
                4 + id[2].is_sign_negative() as usize,
            ],
        }
    }
}
