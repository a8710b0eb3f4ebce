//! The one predicate of Kim's (2013) T-junction search, "the vertex lies on
//! the edge: distance to the edge line ≈ 0 and within the segment", in f64,
//! shared by the naive and the fast finders (so they agree exactly) and by the
//! classification of degenerate triangles.

use super::TJunctionOptions;
use crate::mesh::TriangleMesh;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// f32 machine epsilon, 2^-23: one ulp of a number in [1, 2).
const F32_EPS: f64 = f32::EPSILON as f64;

/// The two distances of the test, fixed for a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Tolerance {
    /// Allowed distance from an edge's line per unit of edge length.
    pub rel: f64,
    /// Rounding allowance: `ulps · 2^-23 · M`, with `M` the largest
    /// coordinate magnitude of the mesh's positions. Points closer than this
    /// are at the same place.
    pub abs: f64,
}

impl Tolerance {
    /// The tolerance for `mesh` under `opts`.
    pub fn of(mesh: &TriangleMesh, opts: &TJunctionOptions) -> Tolerance {
        let m = mesh
            .positions
            .iter()
            .fold(0.0f32, |m, p| m.max(p.abs().max_element()));
        Tolerance {
            rel: opts.tolerance,
            abs: opts.ulps * F32_EPS * m as f64,
        }
    }
}

/// An edge AB prepared for testing many points against it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EdgeTest {
    a: DVec3,
    b: DVec3,
    ab: DVec3,
    len2: f64,
    /// Largest accepted distance from the line AB.
    reach: f64,
    /// Distance within which a point is at an end.
    abs2: f64,
}

impl EdgeTest {
    /// The test for edge `pa → pb`; `None` when the edge has no interior
    /// (its ends are at the same place: no farther apart than `tol.abs`).
    #[inline]
    pub fn new(pa: Vec3, pb: Vec3, tol: Tolerance) -> Option<EdgeTest> {
        let (a, b) = (pa.as_dvec3(), pb.as_dvec3());
        let ab = b - a;
        let len2 = ab.length_squared();
        let abs2 = tol.abs * tol.abs;
        if len2 <= abs2 {
            return None;
        }
        Some(EdgeTest {
            a,
            b,
            ab,
            len2,
            reach: tol.rel * len2.sqrt() + tol.abs,
            abs2,
        })
    }

    /// Largest distance from the line AB at which a point can pass
    /// [`EdgeTest::test`].
    #[inline]
    pub fn reach(&self) -> f64 {
        self.reach
    }

    /// The ends of the edge in f64.
    #[inline]
    pub fn ends(&self) -> (DVec3, DVec3) {
        (self.a, self.b)
    }

    /// `Some(t)` when point `pv` lies on the edge: not at the place of
    /// either end, projected parameter `t` strictly inside (0, 1), and
    /// distance to the line at most [`EdgeTest::reach`].
    #[inline]
    pub fn test(&self, pv: Vec3) -> Option<f64> {
        let v = pv.as_dvec3();
        let w = v - self.a;
        let s = w.dot(self.ab);
        if !(s > 0.0 && s < self.len2) {
            return None;
        }
        // distance² · |AB|² = |w × AB|²
        let c2 = w.cross(self.ab).length_squared();
        if c2 > self.reach * self.reach * self.len2
            || w.length_squared() <= self.abs2
            || (v - self.b).length_squared() <= self.abs2
        {
            return None;
        }
        let t = s / self.len2;
        (t > 0.0 && t < 1.0).then_some(t)
    }
}

/// True when the triangle has no usable area: two corners at the same place
/// (within `tol.abs`), or a corner on the opposite edge by [`EdgeTest::test`]
/// (flat within the tolerance; every exactly collinear triple is caught,
/// since one of its points lies between the other two).
pub(crate) fn is_degenerate(tri: [Vec3; 3], tol: Tolerance) -> bool {
    (0..3).any(|k| {
        let (a, b, c) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
        match EdgeTest::new(a, b, tol) {
            None => true,
            Some(e) => e.test(c).is_some(),
        }
    })
}

/// Indices of the triangles that are not degenerate, ascending.
pub(crate) fn kept_triangles(mesh: &TriangleMesh, tol: Tolerance) -> Vec<u32> {
    (0..mesh.num_triangles() as u32)
        .into_par_iter()
        .filter(|&i| !is_degenerate(mesh.triangle(i as usize), tol))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default relative tolerance, and the rounding allowance of a mesh
    /// whose largest coordinate is `m`.
    fn tol(m: f32) -> Tolerance {
        let o = TJunctionOptions::default();
        Tolerance::of(&TriangleMesh::new(vec![Vec3::splat(m)], vec![]), &o)
    }

    #[test]
    fn midpoint_is_on_the_edge_and_ends_are_not() {
        let e = EdgeTest::new(Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), tol(2.0)).unwrap();
        assert_eq!(e.test(Vec3::new(1.0, 0.0, 0.0)), Some(0.5));
        assert_eq!(e.test(Vec3::ZERO), None);
        assert_eq!(e.test(Vec3::new(2.0, 0.0, 0.0)), None);
        assert_eq!(e.test(Vec3::new(-0.5, 0.0, 0.0)), None);
        assert_eq!(e.test(Vec3::new(2.5, 0.0, 0.0)), None);
        // -0.0 is the same position as 0.0; a point within the rounding
        // allowance of an end is at that end.
        assert_eq!(e.test(Vec3::new(-0.0, 0.0, -0.0)), None);
        assert_eq!(e.test(Vec3::new(5e-7, 0.0, 0.0)), None);
        assert_eq!(e.test(Vec3::new(2.0 - 5e-7, 0.0, 0.0)), None);
        assert!(e.test(Vec3::new(1e-5, 0.0, 0.0)).is_some());
    }

    #[test]
    fn distance_is_relative_to_the_edge_plus_f32_rounding() {
        let t = tol(1.0);
        assert_eq!(t.abs, 4.0 * F32_EPS);
        let e = EdgeTest::new(Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), t).unwrap();
        // reach = 1e-6 · 1 + 4 · 2^-23 · 1 ≈ 1.477e-6
        assert_eq!(e.reach(), 1e-6 + 4.0 * F32_EPS);
        assert!(e.test(Vec3::new(0.3, 1.4e-6, 0.0)).is_some());
        assert!(e.test(Vec3::new(0.3, 0.0, -1.4e-6)).is_some());
        assert!(e.test(Vec3::new(0.3, 1.6e-6, 0.0)).is_none());
        // Far from the origin the rounding term dominates.
        let t = tol(1000.0);
        let (a, b) = (Vec3::splat(1000.0), Vec3::new(1000.01, 1000.0, 1000.0));
        let e = EdgeTest::new(a, b, t).unwrap();
        let v = Vec3::new(1000.005, 1000.0, 1000.0002);
        assert!(e.test(v).is_some(), "reach {}", e.reach());
        assert!(EdgeTest::new(a, a, t).is_none());
        assert!(EdgeTest::new(a, a + Vec3::splat(1e-4), t).is_none());
    }

    #[test]
    fn degenerate_triangles() {
        let t = tol(3.0);
        let (a, b) = (Vec3::ZERO, Vec3::X);
        assert!(is_degenerate([a, a, b], t));
        assert!(is_degenerate([a, b, Vec3::new(1e-7, 0.0, 1e-7)], t));
        assert!(is_degenerate([a, b, Vec3::new(0.5, 0.0, 0.0)], t));
        assert!(is_degenerate([a, b, Vec3::new(2.0, 0.0, 0.0)], t));
        assert!(is_degenerate([a, b, Vec3::new(3.0, 1e-7, 0.0)], t));
        assert!(!is_degenerate([a, b, Vec3::new(3.0, 1e-3, 0.0)], t));
        assert!(!is_degenerate([a, b, Vec3::Y], t));
    }
}
