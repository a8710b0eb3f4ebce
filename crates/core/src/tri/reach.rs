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
//!   `4 · MAX_EDGE_TOLERANCE` on each barycentric coordinate. A test that
//!   widens the barycentrics of the point where the ray meets the plane
//!   (Möller and Trumbore 1997; Wald 2004's projection) reports hits there
//!   only, so a triangle square to an axis keeps a box flat on that axis
//!   instead of one as thick as a fraction of its length. Across
//!   computer-aided-design meshes, whose faces are mostly square to the
//!   axes, that thickness is what rays grazing or parallel to the faces
//!   paid for.

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

/// The box of `a`, `b`, `c` grown in their plane: every barycentric
/// coordinate down to `-4 · MAX_EDGE_TOLERANCE`, which is the triangle
/// scaled by `1 + 12 · MAX_EDGE_TOLERANCE` about its centroid. Computed in
/// `f32`, whose rounding here stays within an ulp of the largest coordinate
/// on each axis, and widened by four such ulps.
#[inline]
pub fn in_plane(a: Vec3, b: Vec3, c: Vec3) -> Aabb {
    const GROW: f32 = 12.0 * MAX_EDGE_TOLERANCE;
    let centroid = (a + b + c) * (1.0 / 3.0);
    let grown = |v: Vec3| v + (v - centroid) * GROW;
    let [p, q, r] = [grown(a), grown(b), grown(c)];
    let (lo, hi) = (p.min(q).min(r), p.max(q).max(r));
    let slack = lo.abs().max(hi.abs()) * (4.0 * f32::EPSILON) + Vec3::splat(f32::MIN_POSITIVE);
    Aabb::new(lo - slack, hi + slack)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    /// `in_plane` holds the triangle grown by its band, checked on points
    /// of the grown triangle in `f64`, small and large, near and far from
    /// the origin; across a triangle square to an axis it is flat, where
    /// `around` is not.
    #[test]
    fn in_plane_holds_the_band_and_is_flat_across_a_flat_triangle() {
        let mut rng = Pcg32::new(5);
        let beta = 4.0 * MAX_EDGE_TOLERANCE as f64;
        for i in 0..3000 {
            let scale = [1e-3f32, 1.0, 1e3][i % 3];
            let shift = [0.0f32, 1.0, 1e4][(i / 3) % 3];
            let [a, mut b, mut c] =
                [(); 3].map(|_| rng.in_box(Vec3::splat(shift), Vec3::splat(shift + scale)));
            if i % 2 == 0 {
                (b.z, c.z) = (a.z, a.z);
            }
            let reach = in_plane(a, b, c);
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
                // Flat but for rounding: within 8 ulps of the plane, where
                // the tube is as thick as a fraction of the triangle.
                let ulp = a.z.abs() * f32::EPSILON;
                assert!(reach.max.z - reach.min.z <= 16.0 * ulp + 1e-37, "{reach:?}");
                let tube = around(a, b, c);
                if (b - a).length() > 1e4 * ulp {
                    assert!(tube.max.z - tube.min.z > 1e-3 * (b - a).length());
                }
            }
        }
    }
}
