//! Möller–Trumbore ray/triangle test (T. Möller, B. Trumbore, "Fast, minimum
//! storage ray/triangle intersection", 1997), made watertight by a conservative
//! tolerance.
//!
//! # Data
//!
//! - Per triangle ([`MollerTri`], 44 bytes): the first corner `a`, the edges
//!   `e1 = b - a`, `e2 = c - a` (each rounded once from the exact `f64`
//!   difference) and their max norms `max|e1_i|`, `max|e2_i|` (11 floats).
//! - Per ray (4 bytes): `64u · max|d_i|`, the ray's factor of the tolerance
//!   (`u = 2^-24`, the unit roundoff of `f32`).
//!
//! # Hit convention
//!
//! With `p = d × e2`, `det = e1·p`, `s = o - a`, `q = s × e1`:
//! `u = s·p / det`, `v = d·q / det`, `t = e2·q / det`. Both faces hit; `t` must
//! lie in `[ray.tnear, tfar]`; `(u, v)` are the weights of `b` and `c`. The
//! edge tests are `u >= -eps_u`, `v >= -eps_v`, `u + v <= 1 + eps_u + eps_v`,
//! combined without a branch per edge, so `u` and `v` may lie outside
//! `[0, 1]` by the tolerance. The ray counts as parallel, and misses, when
//! `|det|` is within its own rounding-error bound
//! `8u · sum_i |e1_i| (|d_j e2_k| + |d_k e2_j|)`: this rejects every exactly
//! parallel ray and every zero-area triangle (`det` is exactly 0 for both in
//! exact arithmetic), and also rays within about `7u / sin(angle at a)`
//! radians of the plane, where `det` carries no information (the test below
//! met 8 such rays in 400,000 aimed at edges and corners).
//!
//! # Tolerance and watertightness
//!
//! The textbook test ([`Moller::intersect_strict`]: `det != 0`, `u, v >= 0`,
//! `u + v <= 1`) computes the barycentrics of the two triangles sharing an
//! edge from different corners and edge vectors, so their rounding errors are
//! unrelated and a ray can pass between them. Measured in
//! `tests/triangle_tests.rs` on closed meshes (icospheres, a 12-triangle cube,
//! tori, randomly placed up to 10^4 sizes from the origin): 1,411 of 50,066
//! rays aimed exactly at shared-edge points (2.8%) and 3,708 of 39,587 rays
//! aimed exactly at shared corners (9.4%) slip through; it also reports hits
//! on 508 of 150,000 exactly degenerate triangles (from a `det` made of
//! rounding noise).
//!
//! The shipped test widens the edges by the rounding-error bound of `u` and
//! `v` relative to exact arithmetic on the `f32` corners and ray:
//! `eps_u = 64u · max|d| · max|e2| · (max|s| + max|e1|) / |det|` and
//! `eps_v` with `e1` and `e2` swapped (the error is at most `42u` times the
//! same product). So whenever exact arithmetic says the ray meets the closed
//! triangle, the uncapped test hits (for the cap, see below); and since exact
//! arithmetic leaves no gap in a
//! closed mesh, no ray slips through edges or corners. Measured: 0 slips on
//! the 50,066 edge rays, 39,587 corner rays and 10,000 random rays through
//! mesh interiors (entry and exit), and not one reference hit missed among
//! 2,000,000 random ray/triangle pairs and 400,000 rays aimed at edges and
//! corners (outside the parallel cone above). The price: near an edge both
//! neighbours may report the hit (the nearest-`t` rule of the accelerators
//! picks one), and points up to about `57u (R + |o| + size) / cos` beyond the
//! boundary count as hits (`R` the corners' magnitude, `cos` between ray and
//! normal; times `(|ab| + |ac|) / |bc|` near the edge `bc`, see below). The
//! tolerance costs a few multiplies per test (about 20-30% in a
//! micro-benchmark).
//!
//! # The cap
//!
//! The bound above grows without limit for rays nearly parallel to the
//! triangle or starting far from it relative to its size: on the full
//! Stanford dragon the uncapped test ([`Moller::intersect_uncapped`]) accepted
//! hits hundreds of triangle widths outside the triangle, which a BVH culls
//! by its boxes and brute force does not. The shipped test therefore caps the
//! tolerance at [`MAX_EDGE_TOLERANCE`] (2^-8 of the triangle, in barycentric
//! units), so a false hit never lies more than that band outside the
//! triangle; the BVHs pad their boxes by the same fraction, and on the full
//! dragon every structure then agrees with brute force. What the cap costs,
//! measured by `tests/triangle_tests.rs`: no slip on any closed mesh (up to
//! 10^4 sizes from the origin), and 318 of 2,000,000 random pairs (0.02%)
//! plus 289 + 270 of ~200,000 rays aimed at edges and corners miss a
//! reference hit that the uncapped test finds; all of them lie within the f32
//! band around the edges.
//!
//! # Accuracy
//!
//! Errors are relative to the ray origin (`s = o - a`), not the world
//! origin. The edge `bc` is measured as `1 - u - v` from barycentrics taken
//! relative to `a`, so its error grows by `(|ab| + |ac|) / |bc|` (needles
//! whose short edge is `bc`), and `t`'s error by `1 / sin(angle at a)`
//! (slivers with a sharp corner at `a`). Against the `f64` reference on
//! 2,000,000 random pairs (slivers, needles, scales 1e-3..1e3, up to 10^4
//! sizes from the origin), the textbook test's hit/miss disagreements all lie
//! within `0.6 u (R + |o| + size) / cos` (times those shape factors) of the
//! boundary; `t` is within `1e-5 t + 1.5` such units.

use super::{TriHit, TriangleTest, MAX_EDGE_TOLERANCE};
use crate::aabb::Aabb;
use crate::ray::Ray;
use glam::Vec3;

/// Unit roundoff of `f32` (half an ulp of 1).
const U: f32 = f32::EPSILON * 0.5;

/// Multiple of `u` in the barycentric tolerance: the rounding error of `u`
/// is at most `42u · |d| |e2| (|s| + |u| |e1|) / |det|` (max norms, to first
/// order; `v` alike with `e1`, `e2` swapped); 64 leaves room for the
/// second-order terms.
const K_BARY: f32 = 64.0;

/// What [`Moller`]'s per-ray constant multiplies the largest direction
/// component's magnitude by (`K_BARY · u`; exact, a power of two), for
/// the packet path that forms eight of them at once (`accel/bvh/packet/`).
pub(crate) const PREPARE_FACTOR: f32 = K_BARY * U;

/// Möller–Trumbore (Möller & Trumbore 1997) with a conservative
/// tolerance: per triangle the first corner, the two edge vectors and their
/// max norms (11 floats, 44 bytes); per ray the tolerance scale
/// `64u · max|d_i|`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Moller;

/// Precomputed triangle data for [`Moller`] (44 bytes): first corner, edge
/// vectors and their max norms (Möller & Trumbore 1997).
#[derive(Clone, Copy, Debug)]
pub struct MollerTri {
    pub(crate) v0: Vec3,
    pub(crate) e1: Vec3,
    pub(crate) e2: Vec3,
    /// `max |e1_i|`.
    pub(crate) e1_max: f32,
    /// `max |e2_i|`.
    pub(crate) e2_max: f32,
}

#[inline(always)]
fn max_abs(v: Vec3) -> f32 {
    v.x.abs().max(v.y.abs()).max(v.z.abs())
}

/// Möller–Trumbore with (`TOL`) or without the conservative tolerance.
#[inline(always)]
fn test<const TOL: bool>(
    tri: &MollerTri,
    ray: &Ray,
    scale: f32,
    tfar: f32,
    cap: f32,
) -> Option<TriHit> {
    let d = ray.dir;
    let p = d.cross(tri.e2);
    let det = tri.e1.dot(p);
    if TOL {
        // Parallel when |det| is within its rounding-error bound: a cheap
        // bound first, the tight one (8u · sum |e1_i| (|d_j e2_k| + |d_k e2_j|))
        // only when the cheap one does not clear det.
        // (`clear` is false for NaN too.)
        let clear = det.abs() > 0.75 * scale * tri.e1_max * tri.e2_max;
        if !clear {
            let (ad, a2) = (d.abs(), tri.e2.abs());
            let pc = Vec3::new(
                ad.y * a2.z + ad.z * a2.y,
                ad.z * a2.x + ad.x * a2.z,
                ad.x * a2.y + ad.y * a2.x,
            );
            let clear = det.abs() > 8.0 * U * tri.e1.abs().dot(pc);
            if !clear {
                return None;
            }
        }
    } else if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = ray.origin - tri.v0;
    let u = s.dot(p) * inv_det;
    let q = s.cross(tri.e1);
    let v = d.dot(q) * inv_det;
    let (eu, ev) = if TOL {
        let c = scale * inv_det.abs();
        let sm = max_abs(s);
        (
            (c * tri.e2_max * (sm + tri.e1_max)).min(cap),
            (c * tri.e1_max * (sm + tri.e2_max)).min(cap),
        )
    } else {
        (0.0, 0.0)
    };
    let t = tri.e2.dot(q) * inv_det;
    // One combined test of the three edges and the distance, no branch each.
    let inside = (u >= -eu) & (v >= -ev) & (u + v <= 1.0 + (eu + ev));
    let in_range = (t >= ray.tnear) & (t <= tfar) & (t < f32::INFINITY);
    (inside & in_range).then_some(TriHit { t, u, v })
}

/// A ray meeting a triangle, or passing too close to its boundary to tell,
/// as [`Moller::crossing`] classifies it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// Distance along the ray.
    pub t: f32,
    /// Weight of the second corner.
    pub u: f32,
    /// Weight of the third corner.
    pub v: f32,
    /// `e1 · (d × e2)`: negative when the ray leaves through the
    /// triangle's front (the side its corners turn counter-clockwise).
    pub det: f32,
    /// The textbook test ([`Moller::intersect_strict`]) counts this hit.
    pub hit: bool,
    /// Exact arithmetic on the `f32` corners and ray agrees with `hit`:
    /// `det` clears its rounding-error bound and `u`, `v`, `1 - u - v` and
    /// `t - tnear` clear theirs (the bounds of the module documentation,
    /// uncapped). When false, the crossing lies within rounding error of an
    /// edge, a corner, the ray's start, or the ray lies in the triangle's
    /// plane.
    pub sure: bool,
}

impl Moller {
    /// Textbook Möller–Trumbore without the tolerance (`0 <= u, v`,
    /// `u + v <= 1`, `det != 0`): not watertight on shared edges (see the
    /// module documentation); kept for comparison and measurement.
    #[inline]
    pub fn intersect_strict(tri: &MollerTri, ray: &Ray, tfar: f32) -> Option<TriHit> {
        test::<false>(tri, ray, 0.0, tfar, 0.0)
    }

    /// The textbook test ([`Moller::intersect_strict`]) with how sure its
    /// answer is: `None` when exact arithmetic on the `f32` inputs surely
    /// misses the triangle over `[ray.tnear, tfar]`, else the crossing with
    /// `hit` (the textbook answer) and `sure` (exact arithmetic agrees).
    /// Counting crossings by their sides is then exact whenever every
    /// crossing reported is sure: no ray slips between two neighbours, and
    /// none is counted by both. `scale` is [`Moller::prepare`]'s. Without
    /// `SURE`, only the textbook answer: `None` exactly when it misses,
    /// `sure` left true.
    #[inline(always)]
    pub fn crossing<const SURE: bool>(
        tri: &MollerTri,
        ray: &Ray,
        scale: f32,
        tfar: f32,
    ) -> Option<Crossing> {
        let d = ray.dir();
        let p = d.cross(tri.e2);
        let det = tri.e1.dot(p);
        if !det.is_finite() || (!SURE && det == 0.0) {
            return None;
        }
        let det_sure = SURE && {
            let (ad, a2) = (d.abs(), tri.e2.abs());
            let pc = Vec3::new(
                ad.y * a2.z + ad.z * a2.y,
                ad.z * a2.x + ad.x * a2.z,
                ad.x * a2.y + ad.y * a2.x,
            );
            det.abs() > 8.0 * U * tri.e1.abs().dot(pc)
        };
        if det == 0.0 {
            // Exactly parallel in f32: the textbook test misses; unsure,
            // since the exact determinant may differ from zero, unless a
            // zero edge makes the triangle degenerate.
            let degenerate = tri.e1 == Vec3::ZERO || tri.e2 == Vec3::ZERO;
            return (!degenerate).then_some(Crossing {
                t: f32::NAN,
                u: f32::NAN,
                v: f32::NAN,
                det,
                hit: false,
                sure: false,
            });
        }
        let inv_det = 1.0 / det;
        let s = ray.origin - tri.v0;
        let u = s.dot(p) * inv_det;
        let q = s.cross(tri.e1);
        let v = d.dot(q) * inv_det;
        let t = tri.e2.dot(q) * inv_det;
        let hit = (u >= 0.0)
            & (v >= 0.0)
            & (u + v <= 1.0)
            & (t >= ray.tnear)
            & (t <= tfar)
            & (t < f32::INFINITY);
        if !SURE {
            return hit.then_some(Crossing {
                t,
                u,
                v,
                det,
                hit,
                sure: true,
            });
        }
        let c = scale * inv_det.abs();
        let sm = max_abs(s);
        let eu = c * tri.e2_max * (sm + tri.e1_max);
        let ev = c * tri.e1_max * (sm + tri.e2_max);
        // `c / max|d|` is `64u · |inv_det|`: no division.
        let et = 3.0
            * PREPARE_FACTOR
            * inv_det.abs()
            * tri.e1_max
            * tri.e2_max
            * (sm + tri.e1_max + tri.e2_max)
            + 1e-5 * t.abs();
        let near = (u >= -eu) & (v >= -ev) & (u + v <= 1.0 + (eu + ev));
        let in_reach = (t >= ray.tnear - et) & (t <= tfar) & (t < f32::INFINITY);
        if !(near & in_reach) && det_sure {
            return None;
        }
        // Here `det` is unsure, or the crossing lies near the triangle and
        // within reach: sure only when clearly inside and clearly beyond
        // the start.
        let inside = (u >= eu) & (v >= ev) & (u + v <= 1.0 - (eu + ev));
        let sure = det_sure & inside & (t >= ray.tnear + et);
        Some(Crossing {
            t,
            u,
            v,
            det,
            hit,
            sure,
        })
    }

    /// The test with its rounding-error tolerance not capped at
    /// [`MAX_EDGE_TOLERANCE`]: watertight whenever exact arithmetic on the
    /// `f32` inputs says the ray meets the triangle, but for grazing rays, or
    /// origins far from a small triangle, it may accept hits far outside the
    /// triangle (many triangle widths). Used by the tests to tell the pairs
    /// f32 cannot resolve within the cap from real misses.
    #[inline]
    pub fn intersect_uncapped(
        tri: &MollerTri,
        ray: &Ray,
        scale: &f32,
        tfar: f32,
    ) -> Option<TriHit> {
        test::<true>(tri, ray, *scale, tfar, f32::INFINITY)
    }
}

impl TriangleTest for Moller {
    const NAME: &'static str = "moller";
    const PACKS_OF_FOUR: bool = true;
    type Tri = MollerTri;
    /// `64u · max |d_i|`, the ray's factor of the barycentric tolerance.
    type RayData = f32;

    fn precompute(a: Vec3, b: Vec3, c: Vec3) -> MollerTri {
        // Edges rounded once from exact f64 differences.
        let e1 = (b.as_dvec3() - a.as_dvec3()).as_vec3();
        let e2 = (c.as_dvec3() - a.as_dvec3()).as_vec3();
        MollerTri {
            v0: a,
            e1,
            e2,
            e1_max: max_abs(e1),
            e2_max: max_abs(e2),
        }
    }

    const WORDS: usize = 11;

    /// `v0, e1, e2, e1_max, e2_max`.
    fn write_words(tri: &MollerTri, out: &mut Vec<u32>) {
        let words = [tri.v0.to_array(), tri.e1.to_array(), tri.e2.to_array()];
        out.extend(words.iter().flatten().map(|x| x.to_bits()));
        out.extend([tri.e1_max.to_bits(), tri.e2_max.to_bits()]);
    }

    /// The band lies in the plane: the test widens the barycentrics of
    /// the point where the ray meets it.
    #[inline]
    fn reach(a: Vec3, b: Vec3, c: Vec3) -> Aabb {
        super::reach::in_plane(a, b, c)
    }

    #[inline]
    fn prepare(ray: &Ray) -> f32 {
        PREPARE_FACTOR * max_abs(ray.dir)
    }

    #[inline]
    fn intersect(tri: &MollerTri, ray: &Ray, scale: &f32, tfar: f32) -> Option<TriHit> {
        test::<true>(tri, ray, *scale, tfar, MAX_EDGE_TOLERANCE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_inside_misses_outside_both_faces() {
        let t = Moller::precompute(Vec3::ZERO, Vec3::X, Vec3::Y);
        let ray = Ray::new(Vec3::new(0.25, 0.5, 1.0), Vec3::NEG_Z * 2.0);
        let h = Moller::intersect(&t, &ray, &Moller::prepare(&ray), f32::INFINITY).unwrap();
        assert!((h.t - 0.5).abs() < 1e-6 && (h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6);
        let back = Ray::new(Vec3::new(0.25, 0.5, -1.0), Vec3::Z);
        assert!(Moller::occluded(
            &t,
            &back,
            &Moller::prepare(&back),
            f32::INFINITY
        ));
        let out = Ray::new(Vec3::new(0.75, 0.5, 1.0), Vec3::NEG_Z);
        assert!(Moller::intersect(&t, &out, &Moller::prepare(&out), f32::INFINITY).is_none());
        let flat = Ray::new(Vec3::new(-1.0, 0.25, 0.0), Vec3::X);
        assert!(Moller::intersect(&t, &flat, &Moller::prepare(&flat), f32::INFINITY).is_none());
    }
}
