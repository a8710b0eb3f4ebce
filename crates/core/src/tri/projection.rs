//! Placeholder: delegates to Möller–Trumbore until the real test lands.

use super::{Moller, TriHit, TriangleTest};
use crate::ray::Ray;
use glam::Vec3;

/// Placeholder.
#[derive(Clone, Copy, Debug, Default)]
pub struct Projection;

impl TriangleTest for Projection {
    const NAME: &'static str = "projection";
    type Tri = <Moller as TriangleTest>::Tri;
    type RayData = ();
    fn precompute(a: Vec3, b: Vec3, c: Vec3) -> Self::Tri {
        Moller::precompute(a, b, c)
    }
    fn prepare(_ray: &Ray) {}
    fn intersect(tri: &Self::Tri, ray: &Ray, rd: &(), tfar: f32) -> Option<TriHit> {
        Moller::intersect(tri, ray, rd, tfar)
    }
}
