//! Plücker-coordinate ray/triangle test (Jones 2000, after Shoemake's Plücker
//! coordinates): a sign test of the ray against the three precomputed edge
//! lines first, distance and barycentrics second; shadow rays stop after the
//! sign test and the distance check; the three signs are combined without a
//! branch per edge.
//!
//! # Data
//!
//! - Per triangle ([`PluckerTri`], 112 bytes, 28 floats): for each directed
//!   edge `a→b`, `b→c`, `c→a` its Plücker coordinates `(e_i, M_i) =
//!   (q - p, p × q)` (18 floats), both computed in `f64` from the shared `f32`
//!   corners, scaled by the power of two `2^-k_i` that brings `max|e_i|` into
//!   `[1, 2)`, and rounded once; the normal `n = (b - a) × (c - a)` (`f64`,
//!   rounded once) and the corner `a` for the distance (6 floats); the two
//!   scales `2^k_0`, `2^k_2` that turn sides back into barycentrics and the
//!   tolerance coefficient `16u · max|M_i|` (3 floats; `u = 2^-24`).
//! - Per ray ([`PluckerRay`], 32 bytes): the ray's Plücker coordinates
//!   `(d, o × d)` (the moment computed in `f64`, rounded once), `|d|_1`, and
//!   the moment's share of the tolerance, `32u · |o × d|_1`.
//!
//! Why not the compact record of GPU kd-tree tracers (9 floats + 3 ints: the
//! normal reduced to two components along its dominant axis, projected vertex
//! and edge terms, an axis-aligned flag)? It normalises every triangle by its
//! own dominant normal component, so the two triangles sharing an edge no
//! longer hold exactly negated edge data, and exact negation is what makes the
//! test watertight. The world-frame edge lines keep it; the power-of-two scale
//! depends on `|q - p|` only and is exact, so it keeps it too while letting one
//! tolerance coefficient serve long and short edges alike. The normal and
//! corner (instead of that record's plane offset `n·a`) make `t = n·(a - o) /
//! n·d` relative to the triangle, precise far from the world origin.
//!
//! # Hit convention
//!
//! Side `i` is the permuted inner product `d·M_i + e_i·(o × d)`.
//! Stage 1: the ray passes the triangle when all three sides are `>= -eps`
//! or all are `<= eps` (both faces hit), combined with bit operations on
//! three comparisons each, so a NaN side never passes. Stage 2: `n·d` must
//! exceed its rounding error `8u · max|n_i| · |d|_1` (otherwise the ray is
//! parallel, and zero-area triangles, with `n = 0`, always end here), `t =
//! n·(a - o) / n·d` must lie in `[ray.tnear, tfar]`, and the barycentrics are
//! `u = side_2 · 2^k_2 / n·d` (weight of `b`) and `v = side_0 · 2^k_0 / n·d`
//! (weight of `c`); in exact arithmetic the sides sum to `n·d`, and dividing
//! by `n·d` keeps `u, v` finite even where all three sides are within the
//! tolerance. They may lie outside `[0, 1]` by the tolerance.
//! [`occluded`](TriangleTest::occluded) runs stage 1 and the distance check
//! of stage 2 and skips the barycentrics; it agrees with `intersect` always.
//!
//! # Watertightness
//!
//! Shared edges: the neighbour across edge `p→q` holds the edge `q→p`, whose
//! data is exactly `(-e_i, -M_i)`: `f64` products of `f32` numbers are
//! exact, IEEE subtraction and rounding are symmetric, the scale depends on
//! `|q - p|` only, and the side is evaluated in the same order. Its side is
//! therefore exactly the negated value, so for a ray through the shared edge
//! one of the two triangles sees that side `>= 0` and the other `<= 0`, and
//! (away from the other edges) one of them accepts: the plain test
//! ([`Plucker::intersect_strict`], no tolerance) never lets a ray through the
//! inside of a shared edge. Measured in `tests/triangle_tests.rs` on closed
//! meshes (icospheres, a 12-triangle cube, tori, randomly placed up to 10^4
//! sizes from the origin): 5 of 50,066 rays aimed exactly at shared-edge
//! points slipped, all on the meshes placed 10^3 and 10^4 sizes from the
//! origin, at 28 to 130 `u (R + |o|)` from a corner (`R`, `|o|` the
//! coordinates' magnitudes), that is, where the corner decides.
//!
//! Shared corners: the sides of the different edges around a corner are
//! rounded independently, and a ray through the corner makes all of them
//! nearly zero, so they can all come out with the sign that every triangle
//! of the fan rejects. Measured for the plain test: 99 of 39,587 rays aimed
//! exactly at shared corners slipped (0.25%; 0 of 5,318 on the icosphere at
//! the origin, up to 22 of 1,421 = 1.5% on the cube 10^3 sizes away).
//!
//! The fix is the smallest one that closes every gap: a conservative side
//! tolerance `eps = |d|_1 · 16u max|M_i| + 32u |o × d|_1`, twice a bound on
//! the rounding error of each side relative to exact arithmetic on the `f32`
//! corners and ray (`7u` times the magnitudes of its six products, with
//! `max|e_i| < 2`). Whenever exact arithmetic says the ray meets the closed
//! triangle the uncapped test hits (for the cap, see below), and exact
//! arithmetic leaves no gap at edges or
//! corners of a closed mesh. Measured: 0 slips on the 50,066 edge rays,
//! 39,587 corner rays and 10,000 random rays through mesh interiors (entry
//! and exit), and not one reference hit missed among 2,000,000 random
//! ray/triangle pairs and 400,000 rays aimed at edges and corners. It costs
//! one multiply-add per test (the sign test stays branch-free; no measurable
//! difference in a micro-benchmark). The price: near an edge both neighbours
//! may report the hit (the accelerators keep the nearest `t`), and points up
//! to about `54u (R + |o| + size) / cos` beyond an edge (`cos` between ray
//! and normal), or that distance over `sin(angle / 2)` beyond a sharp corner,
//! count as hits.
//!
//! # The cap
//!
//! The bound above grows without limit for rays nearly parallel to the
//! triangle or starting far from it relative to its size: on the full
//! Stanford dragon the uncapped test ([`Plucker::intersect_uncapped`])
//! accepted
//! hits hundreds of triangle widths outside the triangle, which a BVH culls
//! by its boxes and brute force does not. The shipped test therefore caps the
//! tolerance at [`MAX_EDGE_TOLERANCE`] (2^-8 of the triangle, in barycentric
//! units), so a false hit never lies more than that band outside the
//! triangle; the BVHs pad their boxes by the same fraction, and on the full
//! dragon every structure then agrees with brute force. What the cap costs,
//! measured by `tests/triangle_tests.rs`: no slip up to 10^2 mesh sizes from
//! the origin; 1 slip at 10^3 and 5 at 10^4 sizes (of ~90,000 rays aimed at
//! shared edges and corners); 7,892 of 2,000,000 random pairs (0.4%) plus
//! 1,968 + 9,549 rays aimed at edges and corners (1-5%) miss a reference hit
//! that the uncapped test finds, all within the f32 band around the edges.
//!
//! # Accuracy
//!
//! The sides are world-frame quantities: their error is about
//! `u (R + |o|) / cos` as a distance in the plane, independent of the
//! triangle's shape (each edge is its own line) but growing with the
//! distance from the world origin, unlike Möller's. Against the `f64`
//! reference on 2,000,000 random pairs, the plain test disagrees on
//! hit/miss only within `1.3 u (R + |o| + size) / cos` of the boundary; `t`
//! (relative to the corner `a`) is within `1e-5 t + 0.9` such units.

use super::{TriHit, TriangleTest, MAX_EDGE_TOLERANCE};
use crate::ray::Ray;
use glam::{DVec3, Vec3};

/// Unit roundoff of `f32` (half an ulp of 1).
const U: f32 = f32::EPSILON * 0.5;

/// Multiple of the rounding-error bound used as the side tolerance. The bound
/// of `d·M + e·m` with rounded `M`, `e`, `m` is `7u` times the sum of the
/// magnitudes of its six products; 16 leaves room for the rounding of the
/// tolerance itself.
const K_SIDE: f32 = 16.0;

/// The Plücker test (Jones 2000): per triangle the Plücker
/// coordinates of its three edge lines, per ray the ray's Plücker
/// coordinates; branch-free sign test first, distance and barycentrics
/// second; watertight on shared edges and corners by a conservative
/// tolerance (see the module documentation).
#[derive(Clone, Copy, Debug, Default)]
pub struct Plucker;

/// Precomputed triangle data for [`Plucker`] (112 bytes): the Plücker
/// coordinates `(e_i, M_i)` of the three directed edge lines `a→b`, `b→c`,
/// `c→a`, each scaled by a power of two so that `max|e_i|` lies in `[1, 2)`,
/// the normal and first corner for the distance, the two scales that turn
/// sides back into barycentrics, and the triangle's tolerance coefficient
/// (Jones 2000).
#[derive(Clone, Copy, Debug)]
pub struct PluckerTri {
    /// Edge directions `e_i = (v_{i+1} - v_i) / 2^k_i`.
    e: [Vec3; 3],
    /// Edge moments `M_i = (v_i × v_{i+1}) / 2^k_i`, computed in `f64`,
    /// rounded once.
    m: [Vec3; 3],
    /// Normal `(b - a) × (c - a)`, computed in `f64`, rounded once.
    n: Vec3,
    /// First corner, for the distance `t = n·(a - o) / n·d`.
    a: Vec3,
    /// `2^k_0` and `2^k_2`: side 0 times `2^k_0` over `n·d` is `v`, side 2
    /// times `2^k_2` over `n·d` is `u`.
    scale_v: f32,
    scale_u: f32,
    /// `K_SIDE · u · max|M_i|` (per component, over the three edges).
    tol_m: f32,
    /// `MAX_EDGE_TOLERANCE / max 2^k_i`: times `|n·d|`, the largest side
    /// tolerance that stays within [`MAX_EDGE_TOLERANCE`] in barycentric
    /// units on every edge.
    cap: f32,
}

/// Per-ray data for [`Plucker`] (32 bytes): the ray's Plücker coordinates `(d,
/// o × d)` (the moment computed in `f64` and rounded once), `|d|_1` and the
/// moment's share of the side tolerance.
#[derive(Clone, Copy, Debug)]
pub struct PluckerRay {
    /// Direction `d`.
    d: Vec3,
    /// Moment `o × d`.
    m: Vec3,
    /// `|d|_1`.
    dsum: f32,
    /// `K_SIDE · u · 2 · |o × d|_1` (plus the `f64` rounding of the moment):
    /// the moment's share of the side tolerance, since `max|e_i| < 2`.
    mtol: f32,
}

impl PluckerRay {
    /// The ray's Plücker coordinates `(direction, moment)`.
    pub fn coordinates(&self) -> (Vec3, Vec3) {
        (self.d, self.m)
    }
}

impl PluckerTri {
    /// The three side values `d·M_i + e_i·(o × d)` (the permuted inner
    /// products of the Plücker test) for edges `a→b`, `b→c`, `c→a`: the ray
    /// passes through the triangle when all three have the same sign. Times
    /// the edges' scales `2^k_i` they are the barycentric weights of `c`, `a`
    /// and `b` times `n·d`.
    #[inline]
    pub fn sides(&self, rd: &PluckerRay) -> [f32; 3] {
        let side = |e: Vec3, m: Vec3| {
            (rd.d.x * m.x + rd.d.y * m.y + rd.d.z * m.z)
                + (e.x * rd.m.x + e.y * rd.m.y + e.z * rd.m.z)
        };
        [
            side(self.e[0], self.m[0]),
            side(self.e[1], self.m[1]),
            side(self.e[2], self.m[2]),
        ]
    }

    /// The side tolerance for this ray: twice a bound on the rounding error of
    /// each of [`sides`](Self::sides) relative to exact arithmetic on the
    /// `f32` corners and ray.
    #[inline]
    pub fn side_tolerance(&self, rd: &PluckerRay) -> f32 {
        rd.dsum * self.tol_m + rd.mtol
    }
}

/// Sign test (branch-free) and, when `FULL`, distance and barycentrics.
/// `TOL` selects the conservative side tolerance.
#[inline(always)]
fn test<const TOL: bool, const FULL: bool>(
    tri: &PluckerTri,
    ray: &Ray,
    rd: &PluckerRay,
    tfar: f32,
    cap_scale: f32,
) -> Option<TriHit> {
    // Stage 1: the three permuted inner products and their signs, combined
    // with bit operations (no branch per edge).
    let [s0, s1, s2] = tri.sides(rd);
    let n = tri.n;
    let den = n.x * rd.d.x + n.y * rd.d.y + n.z * rd.d.z;
    let eps = if TOL {
        tri.side_tolerance(rd).min(tri.cap * cap_scale * den.abs())
    } else {
        0.0
    };
    let all_ge = (s0 >= -eps) & (s1 >= -eps) & (s2 >= -eps);
    let all_le = (s0 <= eps) & (s1 <= eps) & (s2 <= eps);
    if !(all_ge | all_le) {
        return None;
    }
    // Stage 2: distance from the plane. A direction whose dot with the normal
    // is within its rounding error (4u per product) counts as parallel; this
    // also rejects zero-area triangles, whose normal is exactly zero.
    let nmax = n.x.abs().max(n.y.abs()).max(n.z.abs());
    let clear = den.abs() > 8.0 * U * nmax * rd.dsum; // false for NaN too
    if !clear {
        return None;
    }
    let inv = 1.0 / den;
    let w = tri.a - ray.origin;
    let t = (n.x * w.x + n.y * w.y + n.z * w.z) * inv;
    if !(t >= ray.tnear && t <= tfar && t < f32::INFINITY) {
        return None;
    }
    if !FULL {
        return Some(TriHit { t, u: 0.0, v: 0.0 });
    }
    // The sides sum to d·n in exact arithmetic; dividing by the more accurate
    // d·n keeps u, v finite even when all three sides are within tolerance.
    Some(TriHit {
        t,
        u: s2 * tri.scale_u * inv,
        v: s0 * tri.scale_v * inv,
    })
}

impl Plucker {
    /// The plain sign test without the vertex tolerance: hit when the three
    /// sides are all `>= 0` or all `<= 0`. Watertight on shared edges, but rays
    /// through a shared vertex can slip (see the module documentation); kept
    /// for comparison and measurement.
    #[inline]
    pub fn intersect_strict(
        tri: &PluckerTri,
        ray: &Ray,
        rd: &PluckerRay,
        tfar: f32,
    ) -> Option<TriHit> {
        test::<false, true>(tri, ray, rd, tfar, 1.0)
    }

    /// The test with its rounding-error tolerance not capped at
    /// [`MAX_EDGE_TOLERANCE`]: watertight whenever exact arithmetic on the
    /// `f32` inputs says the ray meets the triangle, but for grazing rays, or
    /// origins far from a small triangle, it may accept hits far outside the
    /// triangle (many triangle widths). Used by the tests to tell the pairs
    /// f32 cannot resolve within the cap from real misses.
    #[inline]
    pub fn intersect_uncapped(
        tri: &PluckerTri,
        ray: &Ray,
        rd: &PluckerRay,
        tfar: f32,
    ) -> Option<TriHit> {
        test::<true, true>(tri, ray, rd, tfar, f32::INFINITY)
    }
}

impl TriangleTest for Plucker {
    const NAME: &'static str = "plucker";
    type Tri = PluckerTri;
    type RayData = PluckerRay;

    fn precompute(a: Vec3, b: Vec3, c: Vec3) -> PluckerTri {
        let v = [a.as_dvec3(), b.as_dvec3(), c.as_dvec3()];
        let mut e = [Vec3::ZERO; 3];
        let mut m = [Vec3::ZERO; 3];
        let mut scale = [1.0f32; 3];
        let mut mmax = 0.0f64;
        for i in 0..3 {
            let (p, q) = (v[i], v[(i + 1) % 3]);
            // Both are exactly antisymmetric in (p, q): f64 products of f32
            // numbers are exact, IEEE subtraction and rounding are symmetric,
            // and the power-of-two scale depends on |q - p| only, so the
            // neighbour sharing this edge stores exactly the negated values.
            let ed = q - p;
            let md = p.cross(q);
            let emax = ed.abs().max_element();
            let k = if emax > 0.0 && emax.is_finite() {
                (emax.log2().floor() as i32).clamp(-126, 127)
            } else {
                0
            };
            let s = 2f64.powi(-k);
            e[i] = (ed * s).as_vec3();
            m[i] = (md * s).as_vec3();
            scale[i] = 2f32.powi(k);
            // |M| plus the f64 rounding of the cross product (2^-53 of its
            // products), in units of the f32 roundoff.
            let prod = DVec3::new(
                (p.y * q.z).abs() + (p.z * q.y).abs(),
                (p.z * q.x).abs() + (p.x * q.z).abs(),
                (p.x * q.y).abs() + (p.y * q.x).abs(),
            );
            let mb = (md.abs() + prod * 2f64.powi(-29)) * s;
            mmax = mmax.max(mb.max_element());
        }
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        PluckerTri {
            e,
            m,
            n: n.as_vec3(),
            a,
            scale_v: scale[0],
            scale_u: scale[2],
            tol_m: ((K_SIDE * U) as f64 * mmax) as f32,
            cap: MAX_EDGE_TOLERANCE / scale[0].max(scale[1]).max(scale[2]),
        }
    }

    #[inline]
    fn prepare(ray: &Ray) -> PluckerRay {
        let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
        let m = o.cross(d);
        let prod = DVec3::new(
            (o.y * d.z).abs() + (o.z * d.y).abs(),
            (o.z * d.x).abs() + (o.x * d.z).abs(),
            (o.x * d.y).abs() + (o.y * d.x).abs(),
        );
        PluckerRay {
            d: ray.dir,
            m: m.as_vec3(),
            dsum: ray.dir.abs().element_sum(),
            mtol: (2.0 * (K_SIDE * U) as f64 * (m.abs() + prod * 2f64.powi(-29)).element_sum())
                as f32,
        }
    }

    const WORDS: usize = 28;

    /// `e0, m0, e1, m1, e2, m2, n, a, scale_v, scale_u, tol_m, cap`.
    fn write_words(tri: &PluckerTri, out: &mut Vec<u32>) {
        for i in 0..3 {
            out.extend(tri.e[i].to_array().map(f32::to_bits));
            out.extend(tri.m[i].to_array().map(f32::to_bits));
        }
        out.extend(tri.n.to_array().map(f32::to_bits));
        out.extend(tri.a.to_array().map(f32::to_bits));
        out.extend([tri.scale_v, tri.scale_u, tri.tol_m, tri.cap].map(f32::to_bits));
    }

    #[inline]
    fn intersect(tri: &PluckerTri, ray: &Ray, rd: &PluckerRay, tfar: f32) -> Option<TriHit> {
        test::<true, true>(tri, ray, rd, tfar, 1.0)
    }

    #[inline]
    fn occluded(tri: &PluckerTri, ray: &Ray, rd: &PluckerRay, tfar: f32) -> bool {
        test::<true, false>(tri, ray, rd, tfar, 1.0).is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    #[test]
    fn hits_inside_misses_outside_both_faces() {
        let t = Plucker::precompute(Vec3::ZERO, Vec3::X, Vec3::Y);
        let ray = Ray::new(Vec3::new(0.25, 0.5, 1.0), Vec3::NEG_Z * 2.0);
        let h = Plucker::intersect(&t, &ray, &Plucker::prepare(&ray), f32::INFINITY).unwrap();
        assert!((h.t - 0.5).abs() < 1e-6 && (h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6);
        let back = Ray::new(Vec3::new(0.25, 0.5, -1.0), Vec3::Z);
        assert!(Plucker::occluded(
            &t,
            &back,
            &Plucker::prepare(&back),
            f32::INFINITY
        ));
        let out = Ray::new(Vec3::new(0.75, 0.5, 1.0), Vec3::NEG_Z);
        assert!(Plucker::intersect(&t, &out, &Plucker::prepare(&out), f32::INFINITY).is_none());
        assert!(Plucker::intersect(&t, &ray, &Plucker::prepare(&ray), 0.4).is_none());
    }

    /// The neighbour across an edge stores exactly the negated edge line, so
    /// its side value is exactly the negated one.
    #[test]
    fn shared_edges_are_exactly_negated() {
        let mut rng = Pcg32::new(9);
        for _ in 0..10_000 {
            let s = 10f32.powf(rng.range_f32(-3.0, 3.0));
            let off = rng.unit_vector() * s * 10f32.powf(rng.range_f32(0.0, 4.0));
            let [a, b, c, d] = [(); 4].map(|_| rng.in_box(Vec3::splat(-s), Vec3::splat(s)) + off);
            let (t1, t2) = (Plucker::precompute(a, b, c), Plucker::precompute(b, a, d));
            // Edge a→b of t1 is edge 0; edge b→a of t2 is edge 0 too.
            assert_eq!(t1.e[0], -t2.e[0]);
            assert_eq!(t1.m[0], -t2.m[0]);
            let ray = Ray::new(rng.unit_vector() * s * 5.0 + off, rng.unit_vector());
            let rd = Plucker::prepare(&ray);
            assert_eq!(t1.sides(&rd)[0].to_bits(), (-t2.sides(&rd)[0]).to_bits());
        }
    }
}
