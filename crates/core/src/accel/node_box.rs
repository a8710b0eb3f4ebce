//! The box part of a flattened BVH node and its ray test.

use crate::aabb::Aabb;
use crate::ray::Ray;
use crate::tri::MAX_EDGE_TOLERANCE;
use glam::Vec3;

/// Box corners stored as plain arrays so that a node packs into 32 bytes.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C)]
pub struct NodeBox {
    pub min: [f32; 3],
    pub max: [f32; 3],
}

impl From<Aabb> for NodeBox {
    /// The box padded by `4 · MAX_EDGE_TOLERANCE` of its largest extent, so
    /// that it contains every point a triangle test may report as a hit on a
    /// triangle inside it (the tests accept hits up to that fraction of the
    /// triangle beyond its edges). A child's padded box stays inside its
    /// parent's, since the child's extent is the smaller.
    fn from(b: Aabb) -> Self {
        let pad = Vec3::splat(4.0 * MAX_EDGE_TOLERANCE * b.extent().max_element().max(0.0));
        NodeBox {
            min: (b.min - pad).to_array(),
            max: (b.max + pad).to_array(),
        }
    }
}

impl NodeBox {
    /// `b` stored as it is, with no padding added: for boxes that already
    /// hold their triangles' reach ([`crate::tri::TriangleTest::reach`]).
    #[inline]
    pub fn exact(b: Aabb) -> NodeBox {
        NodeBox {
            min: b.min.to_array(),
            max: b.max.to_array(),
        }
    }

    /// 1 + 2·gamma(3) with gamma(n) = n·eps/(1 - n·eps), eps = 2^-24: the
    /// factor that widens a slab test's exit distance past its rounding.
    pub const ROBUST_EXIT: f32 =
        1.0 + 2.0 * 3.0 * f32::EPSILON * 0.5 / (1.0 - 3.0 * f32::EPSILON * 0.5);

    /// Entry distance of the ray into the box if it enters within
    /// `[tnear, tfar]`, else `f32::INFINITY`.
    ///
    /// Slab test with the reciprocal direction; `min`/`max` written so that a
    /// NaN from 0·inf (origin on a slab plane of an axis-parallel ray)
    /// drops out instead of poisoning the interval.
    #[inline(always)]
    pub fn entry(&self, ray: &Ray, tnear: f32, tfar: f32) -> f32 {
        let o = ray.origin;
        let id = ray.inv_dir;
        let tx0 = (self.min[0] - o.x) * id.x;
        let tx1 = (self.max[0] - o.x) * id.x;
        let ty0 = (self.min[1] - o.y) * id.y;
        let ty1 = (self.max[1] - o.y) * id.y;
        let tz0 = (self.min[2] - o.z) * id.z;
        let tz1 = (self.max[2] - o.z) * id.z;
        let enter = tx0.min(tx1).max(ty0.min(ty1)).max(tz0.min(tz1)).max(tnear);
        // Widen the exit by 3 ulps (pbrt-v4's 1 + 2·gamma(3)) so rounding can
        // never cull a box whose triangle the triangle test would report hit.
        let exit = (tx0.max(tx1).min(ty0.max(ty1)).min(tz0.max(tz1)) * Self::ROBUST_EXIT).min(tfar);
        if enter <= exit {
            enter
        } else {
            f32::INFINITY
        }
    }
}
