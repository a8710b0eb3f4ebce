//! Wald's projection ray/triangle test (I. Wald, "Realtime Ray Tracing and
//! Interactive Global Illumination", PhD thesis, 2004, section 7.1), the
//! usual yardstick for the Plücker test, made watertight by a conservative
//! tolerance.
//!
//! # Data
//!
//! - Per triangle ([`ProjectionTri`], 48 bytes, Wald's `TriAccel` layout):
//!   the dominant axis `k` of the normal `N = (b - a) × (c - a)` (`u = k+1`,
//!   `v = k+2` mod 3), the plane `x_k + n_u x_u + n_v x_v = n_d` with
//!   `n_u = N_u / N_k`, `n_v = N_v / N_k`, `n_d = N·a / N_k`, and the 2D edge
//!   equations of the weights of `b` and `c` in the `(u, v)` projection
//!   plane, `(b_nu, b_nv, b_d)` and `(c_nu, c_nv, c_d)`; 9 floats, the axis
//!   and 2 words of padding to 16-byte alignment. All are computed in `f64`
//!   from the corners and rounded once. A zero-area triangle gets NaN data.
//! - Per ray: nothing.
//!
//! # Hit convention
//!
//! `den = d_k + n_u d_u + n_v d_v` must exceed its rounding error
//! `16u (|d_k| + |n_u d_u| + |n_v d_v|)` (`u = 2^-24`; otherwise the ray is
//! parallel; NaN data fails here too); `t = (n_d - o_k - n_u o_u - n_v o_v) /
//! den` must lie in `[ray.tnear, tfar]`; with the hit point `(hu, hv) =
//! (o_u + t d_u, o_v + t d_v)` the weights are `u = hu b_nu + hv b_nv + b_d`
//! (of `b`) and `v = hu c_nu + hv c_nv + c_d` (of `c`), accepted when
//! `u >= -eps_u`, `v >= -eps_v`, `u + v <= 1 + eps_u + eps_v`. The distance
//! and edge tests are combined without a branch each (Wald's early exits
//! cost more in mispredicted branches than they save here). Both faces hit;
//! `u, v` may lie outside `[0, 1]` by the tolerance.
//!
//! # Tolerance and watertightness
//!
//! The published test ([`Projection::intersect_strict`]) projects each
//! triangle along its own dominant axis and normalises its edge equations by
//! its own `N_k`, and computes its own hit point, so the two triangles
//! sharing an edge round independently and rays pass between them. Measured
//! in `tests/triangle_tests.rs` on closed meshes (icospheres, a 12-triangle
//! cube, tori, randomly placed up to 10^4 sizes from the origin): 3,474 of
//! 50,066 rays aimed exactly at shared-edge points (6.9%), 2,467 of 39,587
//! rays aimed exactly at shared corners (6.2%) and 4 of 10,000 random rays
//! through mesh interiors slip through; it also hits 369 of 148,165 rays
//! exactly parallel to the triangle (it only rejects `den == 0`).
//!
//! The shipped test widens the edges by a bound on the rounding error of
//! `u` and `v` relative to exact arithmetic on the `f32` corners and ray:
//! `eps_u = 16u (|b_nu| A_u + |b_nv| A_v + |b_d|)`, `eps_v` alike with the
//! `c` coefficients, where `A_u = |o_u| + |d_u| (|t| + F)`, `A_v` alike and
//! `F = (|n_d| + |o_k| + |n_u o_u| + |n_v o_v| + |t| (|d_k| + |n_u d_u| +
//! |n_v d_v|)) / |den|` carries the error of `t` into the hit point (the
//! bound itself is about `6u` times those terms). Whenever exact arithmetic
//! says the ray meets the closed triangle, the uncapped test hits (for the
//! cap, see below), so a closed mesh
//! has no gaps. Measured: 0 slips on the 50,066 edge rays, 39,587 corner rays
//! and 10,000 interior rays; not one reference hit missed among 2,000,000
//! random ray/triangle pairs and 400,000 rays aimed at edges and corners
//! (one corner ray at a grazing angle far from the origin, whose `t` is
//! within rounding of `tnear = 0`, aside). The price: near an edge both
//! neighbours may report the hit, points up to about
//! `80u (R + |o| + size) / cos` beyond the boundary count as hits (`R` the
//! corners' magnitude, `cos` between ray and normal; times
//! `(|ab| + |ac|) / |bc|` near the edge `bc`), and the tolerance's ~30 extra
//! operations make the test about twice as slow as the published one in a
//! micro-benchmark (still branch-free).
//!
//! # The cap
//!
//! The bound above grows without limit for rays nearly parallel to the
//! triangle or starting far from it relative to its size: on the full
//! Stanford dragon the uncapped test ([`Projection::intersect_uncapped`])
//! accepted
//! hits hundreds of triangle widths outside the triangle, which a BVH culls
//! by its boxes and brute force does not. The shipped test therefore caps the
//! tolerance at [`MAX_EDGE_TOLERANCE`] (2^-8 of the triangle, in barycentric
//! units), so a false hit never lies more than that band outside the
//! triangle; the BVHs pad their boxes by the same fraction, and on the full
//! dragon every structure then agrees with brute force. What the cap costs,
//! measured by `tests/triangle_tests.rs`: no slip up to 10^3 mesh sizes from
//! the origin; 3 slips at 10^4 sizes (of ~90,000 rays aimed at shared edges
//! and corners); 10,933 of 2,000,000 random pairs (0.55%) plus 1,624 + 7,146
//! rays aimed at edges and corners (1-4%) miss a reference hit that the
//! uncapped test finds, all within the f32 band around the edges.
//!
//! # Accuracy
//!
//! `n_d`, `b_d` and `c_d` are world-frame offsets and the hit point is a
//! world-frame point, so `t`, `u` and `v` carry errors of about
//! `u (R + |o|) / cos` (as distances), growing with the distance from the
//! world origin; the edge `bc`, measured as `1 - u - v`, has them times
//! `(|ab| + |ac|) / |bc|`. For a ray that starts near a triangle far from the
//! origin the relative error of `t` grows accordingly; at grazing angles it
//! can exceed `t` itself. Against the `f64` reference on 2,000,000 random
//! pairs, the published test disagrees on hit/miss only within
//! `1.4 u (R + |o| + size) / cos` (times that shape factor) of the boundary;
//! `t` is within `1e-5 t + 1.0` such units.

use super::{TriHit, TriangleTest, MAX_EDGE_TOLERANCE};
use crate::aabb::Aabb;
use crate::ray::Ray;
use glam::{DVec3, Vec3};

/// Unit roundoff of `f32` (half an ulp of 1).
const U: f32 = f32::EPSILON * 0.5;

/// Multiple of `u` in the tolerances: the rounding-error bounds of the
/// denominator, of the distance and of the barycentrics are at most about
/// `6u` times the magnitudes of their terms; 16 leaves room.
const K_PROJ: f32 = 16.0;

/// Wald's projection test (Wald 2004, section 7.1): the triangle's plane as
/// `x_k + n_u x_u + n_v x_v = n_d` along the dominant normal axis `k`, and the
/// barycentrics as 2D edge equations in the `(u, v)` projection plane;
/// watertight by a conservative tolerance (see the module documentation).
#[derive(Clone, Copy, Debug, Default)]
pub struct Projection;

/// Precomputed triangle data for [`Projection`]: Wald's 48-byte `TriAccel`
/// record (Wald 2004, section 7.1: 9 floats, the axis `k` and 2 words of
/// padding to 16-byte alignment).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct ProjectionTri {
    /// Plane: `n_u = N_u / N_k`.
    n_u: f32,
    /// Plane: `n_v = N_v / N_k`.
    n_v: f32,
    /// Plane: `n_d = N·a / N_k`.
    n_d: f32,
    /// Dominant axis of the normal (0, 1, 2); `u = k+1`, `v = k+2` mod 3.
    k: u32,
    /// Weight of corner `b`: `hu b_nu + hv b_nv + b_d`.
    b_nu: f32,
    /// See `b_nu`.
    b_nv: f32,
    /// See `b_nu`.
    b_d: f32,
    _pad0: u32,
    /// Weight of corner `c`: `hu c_nu + hv c_nv + c_d`.
    c_nu: f32,
    /// See `c_nu`.
    c_nv: f32,
    /// See `c_nu`.
    c_d: f32,
    _pad1: u32,
}

/// `(v_k, v_u, v_v)` for the axis `k`.
#[inline(always)]
fn perm(v: Vec3, k: u32) -> (f32, f32, f32) {
    match k {
        0 => (v.x, v.y, v.z),
        1 => (v.y, v.z, v.x),
        _ => (v.z, v.x, v.y),
    }
}

/// The projection test with (`TOL`) or without the conservative tolerance.
#[inline(always)]
fn test<const TOL: bool>(tri: &ProjectionTri, ray: &Ray, tfar: f32, cap: f32) -> Option<TriHit> {
    let (ok, ou, ov) = perm(ray.origin, tri.k);
    let (dk, du, dv) = perm(ray.dir, tri.k);
    let (nu_du, nv_dv) = (tri.n_u * du, tri.n_v * dv);
    let den = dk + nu_du + nv_dv;
    let den_mag = dk.abs() + nu_du.abs() + nv_dv.abs();
    if TOL {
        // Parallel when den is within its rounding error; NaN data (a
        // zero-area triangle) fails here too.
        let clear = den.abs() > K_PROJ * U * den_mag; // false for NaN too
        if !clear {
            return None;
        }
    } else if den == 0.0 {
        return None;
    }
    let (nu_ou, nv_ov) = (tri.n_u * ou, tri.n_v * ov);
    let num = tri.n_d - ok - nu_ou - nv_ov;
    let inv = 1.0 / den;
    let f = num * inv;
    let hu = ou + f * du;
    let hv = ov + f * dv;
    let u = hu * tri.b_nu + hv * tri.b_nv + tri.b_d;
    let v = hu * tri.c_nu + hv * tri.c_nv + tri.c_d;
    let (eu, ev) = if TOL {
        // The rounding-error bounds of u and v: the error of f (relative to
        // |den|) carried into the hit point (hu, hv), plus the rounding of
        // the edge equations themselves.
        let fm = f.abs()
            + (tri.n_d.abs() + ok.abs() + nu_ou.abs() + nv_ov.abs() + f.abs() * den_mag)
                * inv.abs();
        let au = ou.abs() + du.abs() * fm;
        let av = ov.abs() + dv.abs() * fm;
        let k = K_PROJ * U;
        (
            (k * (tri.b_nu.abs() * au + tri.b_nv.abs() * av + tri.b_d.abs())).min(cap),
            (k * (tri.c_nu.abs() * au + tri.c_nv.abs() * av + tri.c_d.abs())).min(cap),
        )
    } else {
        (0.0, 0.0)
    };
    // One combined test of the distance and the three edges, no branch each.
    let in_range = (f >= ray.tnear) & (f <= tfar) & (f < f32::INFINITY);
    (in_range & (u >= -eu) & (v >= -ev) & (u + v <= 1.0 + (eu + ev))).then_some(TriHit {
        t: f,
        u,
        v,
    })
}

impl Projection {
    /// Wald's test as published, without the tolerance (`den != 0`,
    /// `u, v >= 0`, `u + v <= 1`): not watertight on shared edges (see the
    /// module documentation); kept for comparison and measurement.
    #[inline]
    pub fn intersect_strict(tri: &ProjectionTri, ray: &Ray, tfar: f32) -> Option<TriHit> {
        test::<false>(tri, ray, tfar, 0.0)
    }

    /// The test with its rounding-error tolerance not capped at
    /// [`MAX_EDGE_TOLERANCE`]: watertight whenever exact arithmetic on the
    /// `f32` inputs says the ray meets the triangle, but for grazing rays, or
    /// origins far from a small triangle, it may accept hits far outside the
    /// triangle (many triangle widths). Used by the tests to tell the pairs
    /// f32 cannot resolve within the cap from real misses.
    #[inline]
    pub fn intersect_uncapped(tri: &ProjectionTri, ray: &Ray, tfar: f32) -> Option<TriHit> {
        test::<true>(tri, ray, tfar, f32::INFINITY)
    }
}

impl TriangleTest for Projection {
    const NAME: &'static str = "projection";
    type Tri = ProjectionTri;
    type RayData = ();
    const WORDS: usize = 12;

    /// The 48-byte record as it lies in memory (`k` as an integer).
    fn write_words(tri: &ProjectionTri, out: &mut Vec<u32>) {
        out.extend([
            tri.n_u.to_bits(),
            tri.n_v.to_bits(),
            tri.n_d.to_bits(),
            tri.k,
        ]);
        out.extend([tri.b_nu, tri.b_nv, tri.b_d].map(f32::to_bits));
        out.push(0);
        out.extend([tri.c_nu, tri.c_nv, tri.c_d].map(f32::to_bits));
        out.push(0);
    }

    fn precompute(a: Vec3, b: Vec3, c: Vec3) -> ProjectionTri {
        let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
        let n = (b - a).cross(c - a);
        if n == DVec3::ZERO || !n.is_finite() {
            let nan = f32::NAN;
            return ProjectionTri {
                n_u: nan,
                n_v: nan,
                n_d: nan,
                k: 0,
                b_nu: nan,
                b_nv: nan,
                b_d: nan,
                _pad0: 0,
                c_nu: nan,
                c_nv: nan,
                c_d: nan,
                _pad1: 0,
            };
        }
        let an = n.abs();
        let k = if an.x >= an.y && an.x >= an.z {
            0
        } else if an.y >= an.z {
            1
        } else {
            2
        };
        // Same axis order as `perm`.
        let p = |v: DVec3| match k {
            0 => (v.x, v.y, v.z),
            1 => (v.y, v.z, v.x),
            _ => (v.z, v.x, v.y),
        };
        let (nk, nu, nv) = p(n);
        let (_, au, av) = p(a);
        let (_, bu, bv) = p(b);
        let (_, cu, cv) = p(c);
        // 2D edges from a; their 2D cross product is N_k.
        let (ebu, ebv) = (bu - au, bv - av);
        let (ecu, ecv) = (cu - au, cv - av);
        let inv = 1.0 / nk;
        ProjectionTri {
            n_u: (nu * inv) as f32,
            n_v: (nv * inv) as f32,
            n_d: (n.dot(a) * inv) as f32,
            k,
            b_nu: (ecv * inv) as f32,
            b_nv: (-ecu * inv) as f32,
            b_d: ((av * ecu - au * ecv) * inv) as f32,
            _pad0: 0,
            c_nu: (-ebv * inv) as f32,
            c_nv: (ebu * inv) as f32,
            c_d: ((au * ebv - av * ebu) * inv) as f32,
            _pad1: 0,
        }
    }

    /// The band lies in the plane: the test widens the barycentrics of
    /// the point where the ray meets it.
    #[inline]
    fn reach(a: Vec3, b: Vec3, c: Vec3) -> Aabb {
        super::reach::in_plane(a, b, c)
    }

    #[inline]
    fn prepare(_ray: &Ray) {}

    #[inline]
    fn intersect(tri: &ProjectionTri, ray: &Ray, _rd: &(), tfar: f32) -> Option<TriHit> {
        test::<true>(tri, ray, tfar, MAX_EDGE_TOLERANCE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_inside_misses_outside_every_axis() {
        for k in 0..3 {
            let rot = |v: Vec3| match k {
                0 => v,
                1 => Vec3::new(v.z, v.x, v.y),
                _ => Vec3::new(v.y, v.z, v.x),
            };
            let t = Projection::precompute(rot(Vec3::ZERO), rot(Vec3::X), rot(Vec3::Y));
            let ray = Ray::new(rot(Vec3::new(0.25, 0.5, 1.0)), rot(Vec3::NEG_Z * 2.0));
            let h = Projection::intersect(&t, &ray, &(), f32::INFINITY).unwrap();
            assert!(
                (h.t - 0.5).abs() < 1e-6 && (h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6
            );
            let back = Ray::new(rot(Vec3::new(0.25, 0.5, -1.0)), rot(Vec3::Z));
            assert!(Projection::occluded(&t, &back, &(), f32::INFINITY));
            let out = Ray::new(rot(Vec3::new(0.75, 0.5, 1.0)), rot(Vec3::NEG_Z));
            assert!(Projection::intersect(&t, &out, &(), f32::INFINITY).is_none());
        }
        let degenerate = Projection::precompute(Vec3::ZERO, Vec3::X, Vec3::X * 2.0);
        let ray = Ray::new(Vec3::new(0.5, 0.0, 1.0), Vec3::NEG_Z);
        assert!(Projection::intersect(&degenerate, &ray, &(), f32::INFINITY).is_none());
    }
}
