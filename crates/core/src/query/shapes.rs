//! The query shapes of Kim's (2013) game queries (frustum, box, ball) behind
//! one trait: a conservative test against a tree region, an exact one
//! against a triangle.

use super::exact::{
    triangle_overlaps_box, triangle_overlaps_polytope, triangle_overlaps_sphere, Triangle64,
};
use super::frustum::Frustum;
use crate::aabb::Aabb;
use glam::{DVec3, Vec3};

/// Relative slack of the region tests: a region is pruned only when it lies
/// outside the shape by more than this fraction of the coordinates involved,
/// so that rounding (ours in f64, a tree's f32 split planes) never prunes a
/// region holding a triangle the exact test accepts.
const REGION_SLACK: f64 = 1.0 / (1u64 << 20) as f64;

/// A volume that trees can be queried with.
pub trait QueryShape {
    /// Conservative region test: false only when no point of `region` lies
    /// in the shape (so no triangle inside it can overlap the shape).
    fn may_overlap_region(&self, region: &Aabb) -> bool;

    /// Exact triangle test: true when the triangle shares at least one point
    /// with the shape, its boundary included.
    fn overlaps_triangle(&self, tri: &Triangle64) -> bool;
}

/// A ball (solid sphere) for proximity and collision queries (Kim 2013).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: DVec3,
    /// Radius; a negative or NaN radius holds nothing.
    pub radius: f64,
}

impl Sphere {
    /// The ball of `radius` around `center`.
    pub fn new(center: Vec3, radius: f32) -> Self {
        Sphere {
            center: center.as_dvec3(),
            radius: radius as f64,
        }
    }
}

/// `region`'s corners in f64, or `None` when it holds no point (an empty
/// box is pruned; a NaN corner is never pruned).
fn corners(region: &Aabb) -> Option<(DVec3, DVec3)> {
    if region.is_empty() {
        return None;
    }
    Some((region.min.as_dvec3(), region.max.as_dvec3()))
}

impl QueryShape for Frustum {
    /// The p-vertex test (Greene 1994; Assarsson & Möller 2000): for each
    /// plane take the box corner farthest inside it; when even that corner
    /// is outside one plane, the box is.
    fn may_overlap_region(&self, region: &Aabb) -> bool {
        let Some((lo, hi)) = corners(region) else {
            return false;
        };
        self.planes().iter().all(|pl| {
            let n = pl.normal;
            let p = DVec3::select(n.cmpge(DVec3::ZERO), hi, lo);
            let scale = (n * p).abs().element_sum() + pl.offset.abs();
            let d = pl.distance(p);
            d.is_nan() || d >= -REGION_SLACK * scale
        })
    }

    fn overlaps_triangle(&self, tri: &Triangle64) -> bool {
        triangle_overlaps_polytope(tri, self.planes())
    }
}

impl QueryShape for Aabb {
    /// Box against box, axis by axis.
    fn may_overlap_region(&self, region: &Aabb) -> bool {
        let Some((lo, hi)) = corners(region) else {
            return false;
        };
        let (qlo, qhi) = (self.min.as_dvec3(), self.max.as_dvec3());
        let below = hi - qlo + REGION_SLACK * (hi.abs() + qlo.abs());
        let above = qhi - lo + REGION_SLACK * (qhi.abs() + lo.abs());
        !(below.cmplt(DVec3::ZERO).any() || above.cmplt(DVec3::ZERO).any())
    }

    fn overlaps_triangle(&self, tri: &Triangle64) -> bool {
        triangle_overlaps_box(tri, self.min.as_dvec3(), self.max.as_dvec3())
    }
}

impl QueryShape for Sphere {
    /// The box's point closest to the centre (the centre clamped to the box)
    /// against the radius.
    fn may_overlap_region(&self, region: &Aabb) -> bool {
        let Some((lo, hi)) = corners(region) else {
            return false;
        };
        let c = self.center;
        let q = c.max(lo).min(hi);
        let scale = c.abs().max_element() + q.abs().max_element() + self.radius.abs();
        let d = q.distance(c);
        let reach = self.radius + REGION_SLACK * scale;
        d.is_nan() || reach.is_nan() || d <= reach
    }

    fn overlaps_triangle(&self, tri: &Triangle64) -> bool {
        triangle_overlaps_sphere(tri, self.center, self.radius)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::query::Plane;

    #[test]
    fn region_tests_prune_only_outside() {
        let region = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let ball = |x: f32, r: f32| Sphere::new(Vec3::new(x, 0.5, 0.5), r);
        assert!(ball(2.0, 1.0).may_overlap_region(&region));
        assert!(!ball(2.0, 0.99).may_overlap_region(&region));
        assert!(!ball(2.0, -1.0).may_overlap_region(&region));
        let q = |lo: f32, hi: f32| Aabb::new(Vec3::splat(lo), Vec3::splat(hi));
        assert!(q(1.0, 2.0).may_overlap_region(&region));
        assert!(!q(1.01, 2.0).may_overlap_region(&region));
        assert!(!q(0.0, 1.0).may_overlap_region(&Aabb::EMPTY));
        // A half-space x + y + z >= 3 (with five planes that hold everything)
        // touches the unit box only at its corner (1, 1, 1).
        let all = Plane::new(DVec3::ZERO, 1.0);
        let corner =
            |d: f64| Frustum::from_planes([Plane::new(DVec3::ONE, -d), all, all, all, all, all]);
        assert!(corner(3.0).may_overlap_region(&region));
        assert!(!corner(3.01).may_overlap_region(&region));
    }
}
