//! Möller–Trumbore ray/triangle test (Möller & Trumbore 1997), the test of
//! paper 001.

use super::{TriHit, TriangleTest};
use crate::ray::Ray;
use glam::Vec3;

/// Möller–Trumbore: per triangle the first corner and the two edge vectors
/// (9 floats); per ray nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Moller;

/// Precomputed triangle data for [`Moller`].
#[derive(Clone, Copy, Debug)]
pub struct MollerTri {
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
}

impl TriangleTest for Moller {
    const NAME: &'static str = "moller";
    type Tri = MollerTri;
    type RayData = ();

    fn precompute(a: Vec3, b: Vec3, c: Vec3) -> MollerTri {
        MollerTri {
            v0: a,
            e1: b - a,
            e2: c - a,
        }
    }

    #[inline]
    fn prepare(_ray: &Ray) {}

    #[inline]
    fn intersect(tri: &MollerTri, ray: &Ray, _rd: &(), tfar: f32) -> Option<TriHit> {
        let p = ray.dir.cross(tri.e2);
        let det = tri.e1.dot(p);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv_det = 1.0 / det;
        let s = ray.origin - tri.v0;
        let u = s.dot(p) * inv_det;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(tri.e1);
        let v = ray.dir.dot(q) * inv_det;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = tri.e2.dot(q) * inv_det;
        (t >= ray.tnear && t <= tfar).then_some(TriHit { t, u, v })
    }
}
