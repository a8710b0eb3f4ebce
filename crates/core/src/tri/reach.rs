//! The reach of a triangle test: a box holding every point at which the
//! test may report a hit on a triangle, its tolerance band included
//! ([`super::MAX_EDGE_TOLERANCE`]). The wide BVHs store every box as the
//! union of its triangles' reach (`accel/bvh/fit.rs`), so box culling never
//! loses a hit the test would report.
//!
//! Two shapes, by how a test's band lies:
//! - [`around`]: the triangle's box padded on every axis by
//!   `4 · MAX_EDGE_TOLERANCE` of its largest extent. A test whose band is a
//!   tube around the triangle needs it: the Plücker test (Jones 2000)
//!   widens the signs of the ray's line against the edges, and a line
//!   grazing the plane can pass that test within the tube while meeting
//!   the plane well outside the triangle.
//! - [`in_plane`]: the triangle grown in its own plane, by
//!   `4 · MAX_EDGE_TOLERANCE` on each barycentric coordinate, then padded
//!   on every axis by [`CLEARANCE`] of its largest extent, and cut to the
//!   tube (both hold every point the test reports). A test that
//!   widens the barycentrics of the point where the ray meets the plane
//!   (Möller and Trumbore 1997; Wald 2004's projection) reports hits there
//!   only, so a triangle square to an axis keeps a box 64 times thinner on
//!   that axis than the tube. Across computer-aided-design meshes, whose
//!   faces are mostly square to the axes, the tube's thickness is what
//!   rays grazing or parallel to the faces paid for.
//!
//! The clearance keeps a box's entry distance below the distance the test
//! reports on a triangle inside it. The walks prune a box whose entry lies
//! beyond the nearest hit so far; a box flat in a face's plane has its
//! entry equal to its triangles' hit distance up to rounding, and could be
//! pruned for a coplanar hit an ulp farther, answering that hit instead of
//! the nearer one. With the clearance the entry lies at least `CLEARANCE`
//! of the triangle's size before it along the ray, many ulps of the
//! distance for a triangle seen from less than a few hundred of its sizes.

use super::MAX_EDGE_TOLERANCE;
use crate::aabb::Aabb;
use glam::Vec3;

/// The box of `a`, `b`, `c` padded by `4 · MAX_EDGE_TOLERANCE` of its
/// largest extent on every axis.
#[inline]
pub fn around(a: Vec3, b: Vec3, c: Vec3) -> Aabb {
    let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
    let pad = Vec3::splat(4.0 * MAX_EDGE_TOLERANCE * (hi - lo).max_element().max(0.0));
    Aabb::new(lo - pad, hi + pad)
}

/// The padding of [`in_plane`] across the triangle's plane, relative to
/// the triangle's largest extent: 2^-12, a sixty-fourth of the tube's
/// `4 · MAX_EDGE_TOLERANCE`.
pub const CLEARANCE: f32 = MAX_EDGE_TOLERANCE / 16.0;

/// The box of `a`, `b`, `c` grown in their plane: every barycentric
/// coordinate down to `-4 · MAX_EDGE_TOLERANCE` (twice what the tests
/// accept: `u` and `v` down to `-MAX_EDGE_TOLERANCE`, `1 - u - v` down to
/// twice that), which is the triangle scaled by `1 + 12 ·
/// MAX_EDGE_TOLERANCE` about its centroid, padded by [`CLEARANCE`] of the
/// triangle's largest extent on every axis, and cut to the tube
/// [`around`], which holds the same points: grown in its plane, a tilted
/// triangle's corners can move further along an axis than the tube's
/// padding. Computed in `f32`, whose rounding here stays within an ulp of
/// the largest coordinate on each axis, and widened by four such ulps
/// after the cut (a tube around a triangle a few ulps wide is no wider).
#[inline]
pub fn in_plane(a: Vec3, b: Vec3, c: Vec3) -> Aabb {
    const GROW: f32 = 12.0 * MAX_EDGE_TOLERANCE;
    let centroid = (a + b + c) * (1.0 / 3.0);
    let grown = |v: Vec3| v + (v - centroid) * GROW;
    let [p, q, r] = [grown(a), grown(b), grown(c)];
    let tube = around(a, b, c);
    let lo = p.min(q).min(r).max(tube.min);
    let hi = p.max(q).max(r).min(tube.max);
    let extent = (a.max(b).max(c) - a.min(b).min(c)).max_element().max(0.0);
    let slack = lo.abs().max(hi.abs()) * (4.0 * f32::EPSILON)
        + Vec3::splat(CLEARANCE * extent + f32::MIN_POSITIVE);
    Aabb::new(lo - slack, hi + slack)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    /// `in_plane` holds the triangle grown by the band the tests accept
    /// (every barycentric coordinate down to `-2 · MAX_EDGE_TOLERANCE`),
    /// checked on points of the grown triangle in `f64`, small and large,
    /// near and far from the origin, and is nowhere larger than `around` but
    /// for the clearance and rounding;
    /// across a triangle square to an axis it is as thin as the clearance,
    /// where `around` is 64 times thicker.
    #[test]
    fn in_plane_holds_the_band_and_is_flat_across_a_flat_triangle() {
        let mut rng = Pcg32::new(5);
        let beta = 2.0 * MAX_EDGE_TOLERANCE as f64;
        for i in 0..3000 {
            let scale = [1e-3f32, 1.0, 1e3][i % 3];
            let shift = [0.0f32, 1.0, 1e4][(i / 3) % 3];
            let [a, mut b, mut c] =
                [(); 3].map(|_| rng.in_box(Vec3::splat(shift), Vec3::splat(shift + scale)));
            if i % 2 == 0 {
                (b.z, c.z) = (a.z, a.z);
            }
            let reach = in_plane(a, b, c);
            let tube = around(a, b, c);
            let size = (a.max(b).max(c) - a.min(b).min(c)).max_element();
            let ulps = tube.min.abs().max(tube.max.abs()) * (5.0 * f32::EPSILON)
                + Vec3::splat(CLEARANCE * size * 1.0001);
            assert!((tube.min - ulps).cmple(reach.min).all());
            assert!(reach.max.cmple(tube.max + ulps).all());
            for _ in 0..20 {
                // Barycentrics down to -beta: the unit triangle's point
                // scaled by 1 + 3 beta about its centroid.
                let (u, v) = (rng.next_f64(), rng.next_f64());
                let (u, v) = if u + v > 1.0 {
                    (1.0 - u, 1.0 - v)
                } else {
                    (u, v)
                };
                let [u, v, w] = [u, v, 1.0 - u - v].map(|x| x * (1.0 + 3.0 * beta) - beta);
                let p = a.as_dvec3() * w + b.as_dvec3() * u + c.as_dvec3() * v;
                let inside =
                    (0..3).all(|k| reach.min[k] as f64 <= p[k] && p[k] <= reach.max[k] as f64);
                assert!(inside, "{a} {b} {c}: {p} outside {reach:?}");
            }
            if i % 2 == 0 {
                // As thin as the clearance (and rounding) across the plane,
                // where the tube is 64 times thicker; never thinner than the
                // clearance.
                let extent = (a.max(b).max(c) - a.min(b).min(c)).max_element();
                let clear = 2.0 * CLEARANCE * extent;
                let ulp = a.z.abs() * f32::EPSILON;
                let thick = reach.max.z - reach.min.z;
                assert!(thick >= clear, "{reach:?}");
                assert!(thick <= clear * 1.0001 + 16.0 * ulp + 1e-37, "{reach:?}");
                if extent > 1e4 * ulp {
                    assert!(tube.max.z - tube.min.z > 60.0 * clear);
                }
            }
        }
    }
}
