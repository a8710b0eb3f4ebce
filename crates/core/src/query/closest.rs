//! Closest point on a triangle mesh's surface and unsigned distance.
//!
//! The point of a triangle closest to a query point is Ericson's ("Real-Time
//! Collision Detection", 2005, 5.1.5): the Voronoi region of the point among
//! the triangle's corners, edges and face from six dot products, then the
//! projection onto that feature, computed for four triangles of a leaf at
//! once without branches, from the leaf's corners kept in structure of
//! arrays (`super::corner_groups`). The tree is searched nearest box first
//! ([`SurfaceBvh::closest_point`]): of a node's children within reach, the
//! nearest is walked next and the others are pushed as they come (sorting
//! them cost more in mispredicted branches than it saved), each one's
//! memory requested when it is pushed, and a box no nearer than the best
//! triangle so far (or than the search radius) is never opened. The search
//! runs in `f32` relative to the query point; the winning triangle is then
//! solved again in `f64` for the reported point, barycentrics and distance.
//! [`closest_point_in`] runs the same search through any [`Accel`]'s
//! regions, and [`closest_point_brute`] tests every triangle in `f64` (the
//! reference of the tests).

use super::batch::answer_coherent;
use super::corner_groups::{Group, LANES};
use super::exact::Triangle64;
use super::point_tree::PointTree;
use super::surface_bvh::{SurfaceBvh, EMPTY, SMALL_STACK, WIDTH};
use crate::accel::bvh::prefetch_lines;
#[cfg(target_arch = "x86_64")]
use crate::accel::bvh::BoxPath;
use crate::accel::Accel;
use crate::mesh::TriangleMesh;
use glam::{DVec3, Vec3};
use std::mem::MaybeUninit;

/// The point of a surface closest to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosestPoint {
    /// The point on the surface.
    pub point: Vec3,
    /// Its distance to the query point.
    pub distance: f32,
    /// The triangle (index in the mesh) holding it.
    pub prim: u32,
    /// Barycentric weight of the triangle's second corner.
    pub u: f32,
    /// Barycentric weight of the triangle's third corner (the point is
    /// `(1-u-v)·v0 + u·v1 + v·v2`).
    pub v: f32,
}

/// Ericson's closest point on triangle `(a, b, c)` to the origin, written
/// once for `f32` and `f64`: returns `(u, v)` with the point `a + u·(b-a) +
/// v·(c-a)`. A degenerate triangle (no positive area within rounding) takes
/// the closest point of its three edges. Where the products of the corners'
/// dot products overflow, `(u, v)` may be NaN.
macro_rules! closest_uv {
    ($name:ident, $v:ty, $f:ty, $thin:expr) => {
        #[inline(always)]
        pub(crate) fn $name(a: $v, b: $v, c: $v) -> ($f, $f) {
            let (ab, ac) = (b - a, c - a);
            let ap = -a;
            let (d1, d2) = (ab.dot(ap), ac.dot(ap));
            if d1 <= 0.0 && d2 <= 0.0 {
                return (0.0, 0.0);
            }
            let bp = -b;
            let (d3, d4) = (ab.dot(bp), ac.dot(bp));
            if d3 >= 0.0 && d4 <= d3 {
                return (1.0, 0.0);
            }
            let vc = d1 * d4 - d3 * d2;
            // Each edge region below divides by its edge's squared length:
            // an edge of length zero (two corners at one point) is left to
            // the degenerate case, where 0/0 would give NaN.
            if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 && d1 - d3 > 0.0 {
                return (d1 / (d1 - d3), 0.0);
            }
            let cp = -c;
            let (d5, d6) = (ab.dot(cp), ac.dot(cp));
            if d6 >= 0.0 && d5 <= d6 {
                return (0.0, 1.0);
            }
            let vb = d5 * d2 - d1 * d6;
            if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 && d2 - d6 > 0.0 {
                return (0.0, d2 / (d2 - d6));
            }
            let va = d3 * d6 - d5 * d4;
            if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 && (d4 - d3) + (d5 - d6) > 0.0 {
                let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
                return (1.0 - w, w);
            }
            let denom = va + vb + vc;
            if !denom.is_finite() {
                // The products overflowed (corners beyond about 1e9 in
                // f32): no answer here, for the caller to solve wider.
                return (<$f>::NAN, <$f>::NAN);
            }
            // `denom` is `|ab × ac|²` (Lagrange's identity): on a thin
            // triangle its rounding swamps the face's barycentrics, so no
            // answer here either.
            if $thin > 0.0 && denom <= $thin * ab.dot(ab) * ac.dot(ac) {
                return (<$f>::NAN, <$f>::NAN);
            }
            if denom <= 0.0 {
                // Degenerate: the best of the three edges.
                let seg = |s: $v, e: $v| -> $f {
                    let d = e - s;
                    let l = d.length_squared();
                    if l > 0.0 {
                        (-s.dot(d) / l).clamp(0.0, 1.0)
                    } else {
                        0.0
                    }
                };
                let (s_ab, s_ac, s_bc) = (seg(a, b), seg(a, c), seg(b, c));
                let cands = [(s_ab, 0.0), (0.0, s_ac), (1.0 - s_bc, s_bc)];
                let mut best = cands[0];
                let mut best_d = <$f>::INFINITY;
                for (u, v) in cands {
                    let d = (a + ab * u + ac * v).length_squared();
                    if d < best_d {
                        best_d = d;
                        best = (u, v);
                    }
                }
                return best;
            }
            let u = (vb / denom).clamp(0.0, 1.0);
            let v = (vc / denom).clamp(0.0, 1.0 - u);
            (u, v)
        }
    };
}

closest_uv!(closest_uv32, Vec3, f32, THIN);
closest_uv!(closest_uv64, DVec3, f64, 0.0);

/// Below this `sin²` of the angle between a triangle's edges `b - a` and
/// `c - a` (about 0.9°) the triangle is thin: Ericson's face-region
/// barycentrics divide by `|ab × ac|²`, which rounding in `f32` swamps (an
/// error of 500 ulps in the distance was seen), so thin triangles are
/// solved in `f64`.
const THIN: f32 = 1.0 / 4096.0;

/// Squared distance from `p` to triangle `tri`, with the barycentrics of
/// the closest point, in `f32` relative to `p`.
#[inline(always)]
pub(crate) fn triangle_distance2(p: Vec3, tri: &[Vec3; 3]) -> (f32, f32, f32) {
    let (a, b, c) = (tri[0] - p, tri[1] - p, tri[2] - p);
    let (u, v) = closest_uv32(a, b, c);
    if !(u.is_finite() && v.is_finite()) {
        // A thin triangle, whose face region f32 cannot tell from its
        // edges, or overflowed f32 products: the same steps in f64.
        let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
        let (u, v) = closest_uv64(a, b, c);
        let q = a + (b - a) * u + (c - a) * v;
        return (q.length_squared() as f32, u as f32, v as f32);
    }
    let q = a + (b - a) * u + (c - a) * v;
    (q.length_squared(), u, v)
}

/// [`triangle_distance2`]'s squared distances from `p` to the `n` (one
/// to [`LANES`]) triangles of group `g` of `tree`.
#[inline(always)]
fn group_distance2(p: Vec3, tree: &PointTree, g: usize, n: usize) -> [f32; LANES] {
    let (mut d2, degenerate) = distance2_lanes(&tree.groups.corners[g], p);
    if degenerate != 0 {
        let first = tree.groups.first[g] as usize;
        for (k, t) in tree.tris[first..first + n].iter().enumerate() {
            if degenerate & (1 << k) != 0 {
                d2[k] = triangle_distance2(p, t).0;
            }
        }
    }
    d2
}

/// [`triangle_distance2`] in [`LANES`] lanes without branches, so that each
/// lane-wise step compiles to one vector operation: lane `k` holds the
/// corners `g[corner][axis][k]` of a triangle, taken relative to `p` lane
/// by lane so that no step spans more than one vector of [`LANES`] (a
/// subtraction of the whole group at once compiles to 512-bit operations
/// where AVX-512 is enabled, which lower the clock).
/// Every region's candidate is computed and the one of Ericson's order
/// selected, so each distance is [`triangle_distance2`]'s bit for bit.
/// Thin and degenerate triangles, and triangles whose products overflow,
/// are not solved: their lanes' bits are set in the returned mask, for the caller
/// to answer with [`triangle_distance2`].
#[inline(always)]
#[allow(clippy::needless_range_loop)] // lanes of structure-of-arrays
#[allow(clippy::manual_clamp)] // `clamp` panics on a NaN bound
fn distance2_lanes(g: &Group, p: Vec3) -> ([f32; LANES], u32) {
    let [a, b, c] = g;
    let mut d2 = [0f32; LANES];
    let mut degenerate = 0u32;
    for k in 0..LANES {
        let (ax, ay, az) = (a[0][k] - p.x, a[1][k] - p.y, a[2][k] - p.z);
        let (bx, by, bz) = (b[0][k] - p.x, b[1][k] - p.y, b[2][k] - p.z);
        let (cx, cy, cz) = (c[0][k] - p.x, c[1][k] - p.y, c[2][k] - p.z);
        let (abx, aby, abz) = (bx - ax, by - ay, bz - az);
        let (acx, acy, acz) = (cx - ax, cy - ay, cz - az);
        let dot = |vx: f32, vy: f32, vz: f32| {
            (
                abx * vx + aby * vy + abz * vz,
                acx * vx + acy * vy + acz * vz,
            )
        };
        let (d1, d2_) = dot(-ax, -ay, -az);
        let (d3, d4) = dot(-bx, -by, -bz);
        let (d5, d6) = dot(-cx, -cy, -cz);
        let vc = d1 * d4 - d3 * d2_;
        let vb = d5 * d2_ - d1 * d6;
        let va = d3 * d6 - d5 * d4;
        let denom = va + vb + vc;
        // The thin-triangle test of `closest_uv32`, in its order of
        // operations (glam's dot), so that both agree bit for bit.
        let aa = abx * abx + aby * aby + abz * abz;
        let cc = acx * acx + acy * acy + acz * acz;
        let wide = denom > THIN * aa * cc;
        // The face, then each region overriding in reverse order of
        // precedence. `max` then `min` rather than `clamp`: the bounds of a
        // lane that ends up degenerate are NaN.
        let fu = (vb / denom).max(0.0).min(1.0);
        let (mut u, mut v) = (fu, (vc / denom).max(0.0).min(1.0 - fu));
        let on_bc = va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0;
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        (u, v) = if on_bc { (1.0 - w, w) } else { (u, v) };
        let on_ac = vb <= 0.0 && d2_ >= 0.0 && d6 <= 0.0;
        (u, v) = if on_ac {
            (0.0, d2_ / (d2_ - d6))
        } else {
            (u, v)
        };
        let at_c = d6 >= 0.0 && d5 <= d6;
        (u, v) = if at_c { (0.0, 1.0) } else { (u, v) };
        let on_ab = vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0;
        (u, v) = if on_ab { (d1 / (d1 - d3), 0.0) } else { (u, v) };
        let at_b = d3 >= 0.0 && d4 <= d3;
        (u, v) = if at_b { (1.0, 0.0) } else { (u, v) };
        let at_a = d1 <= 0.0 && d2_ <= 0.0;
        (u, v) = if at_a { (0.0, 0.0) } else { (u, v) };
        let (qx, qy, qz) = (
            ax + abx * u + acx * v,
            ay + aby * u + acy * v,
            az + abz * u + acz * v,
        );
        d2[k] = qx * qx + qy * qy + qz * qz;
        // Overflowed products (an infinite or NaN `denom`, a NaN region
        // answer) go to the scalar kernel too, which solves them in f64.
        let solved = (at_a || at_b || on_ab || at_c || on_ac || on_bc)
            || (denom > 0.0 && denom < f32::INFINITY);
        let solved = solved && wide && d2[k].is_finite();
        degenerate |= u32::from(!solved) << k;
    }
    (d2, degenerate)
}

/// The closest point of triangle `tri` to `p` in `f64`: `(point, u, v)`.
pub fn closest_on_triangle64(p: DVec3, tri: &Triangle64) -> (DVec3, f64, f64) {
    let (a, b, c) = (tri[0] - p, tri[1] - p, tri[2] - p);
    let (u, v) = closest_uv64(a, b, c);
    let q = a + (b - a) * u + (c - a) * v;
    (q + p, u, v)
}

/// The answer for triangle `prim` with corners `tri`, solved in `f64`.
fn answer(p: Vec3, tri: &[Vec3; 3], prim: u32) -> ClosestPoint {
    let p64 = p.as_dvec3();
    let t64 = tri.map(|c| c.as_dvec3());
    let (q, u, v) = closest_on_triangle64(p64, &t64);
    ClosestPoint {
        point: q.as_vec3(),
        distance: q.distance(p64) as f32,
        prim,
        u: u as f32,
        v: v as f32,
    }
}

/// Squared distances from `p` to the eight boxes of a node (`+inf` for
/// unused slots, NaN for a NaN point).
#[inline(always)]
fn box_distance2(min: &[[f32; WIDTH]; 3], max: &[[f32; WIDTH]; 3], p: Vec3) -> [f32; WIDTH] {
    let mut d2 = [0.0f32; WIDTH];
    for a in 0..3 {
        let pa = p[a];
        for k in 0..WIDTH {
            let (below, above) = (min[a][k] - pa, pa - max[a][k]);
            let d = if below > above { below } else { above };
            let d = if d > 0.0 { d } else { 0.0 };
            d2[k] += d * d;
        }
    }
    d2
}

impl SurfaceBvh {
    /// The point of the surface closest to `p` no farther than `max_distance`
    /// (`f32::INFINITY` for no limit), or `None` when there is none or `p`
    /// is not finite. Ties between triangles at the same distance (a shared
    /// edge or corner) go to either.
    pub fn closest_point(&self, p: Vec3, max_distance: f32) -> Option<ClosestPoint> {
        let q = self.scale.point(p);
        let tree = self.points();
        tree.nearest_triangle(q, self.scale.length(max_distance), None)
            .map(|t| self.closest_on(tree, q, t))
    }

    /// The closest point of triangle `t` (in `tree`'s leaf order) to `q`
    /// (both at [`SurfaceBvh::scale`]), in the mesh's units.
    fn closest_on(&self, tree: &PointTree, q: Vec3, t: usize) -> ClosestPoint {
        let c = answer(q, &tree.tris[t], tree.prims[t]);
        ClosestPoint {
            point: self.scale.point_to_model(c.point),
            distance: self.scale.to_model(c.distance),
            ..c
        }
    }

    /// Unsigned distance from `p` to the surface: `+inf` for an empty mesh,
    /// NaN for a point that is not finite.
    pub fn distance(&self, p: Vec3) -> f32 {
        if !p.is_finite() {
            return f32::NAN;
        }
        self.closest_point(p, f32::INFINITY)
            .map_or(f32::INFINITY, |c| c.distance)
    }

    /// [`SurfaceBvh::closest_point`] for many points, in parallel over the
    /// rayon pool. The points are searched in Morton order, each search
    /// bounded from the start by the previous point's triangle, which is
    /// what makes a grid or cloud of points several times faster per point
    /// than single queries; the answers are the same.
    pub fn closest_points(
        &self,
        points: &[Vec3],
        max_distance: f32,
        out: &mut [Option<ClosestPoint>],
    ) {
        let max_distance = self.scale.length(max_distance);
        let tree = self.points();
        answer_coherent(points, out, |p, hint: &mut Option<usize>| {
            let q = self.scale.point(p);
            let found = tree.nearest_triangle(q, max_distance, *hint);
            *hint = found.or(*hint);
            found.map(|t| self.closest_on(tree, q, t))
        });
    }

    /// [`SurfaceBvh::distance`] for many points, in parallel over the rayon
    /// pool, searched as [`SurfaceBvh::closest_points`] does.
    pub fn distances(&self, points: &[Vec3], out: &mut [f32]) {
        self.points();
        answer_coherent(points, out, |p, hint| self.distance_hinted(p, hint));
    }

    /// [`SurfaceBvh::distance`] with the search bounded from the start by
    /// triangle `hint` (the point tree's leaf order), which becomes the
    /// nearest triangle.
    pub(crate) fn distance_hinted(&self, p: Vec3, hint: &mut Option<usize>) -> f32 {
        if !p.is_finite() {
            return f32::NAN;
        }
        let q = self.scale.point(p);
        let tree = self.points();
        let found = tree.nearest_triangle(q, f32::INFINITY, *hint);
        *hint = found.or(*hint);
        found.map_or(f32::INFINITY, |t| self.closest_on(tree, q, t).distance)
    }
}

/// An entry of the search's stack: a child reference, its triangle count
/// (zero for an inner node) and its box's squared distance.
type Entry = (u32, u32, f32);

impl PointTree {
    /// The search behind [`SurfaceBvh::closest_point`]: the nearest
    /// triangle's index in leaf order, `p` and `max_distance` at the
    /// surface's scale. `hint`, a triangle near `p` (in leaf
    /// order; the answer for a neighbouring point), starts the search with
    /// its distance as the bound, which prunes the tree from the first node
    /// on; the answer is the same with or without it. The search is
    /// compiled once per instruction set ([`PointTree::path`]), so that the
    /// boxes' and triangles' lanes take the widest vectors and VEX's
    /// three-operand forms; the arithmetic is the same, bit for bit (no
    /// fused multiply-adds).
    pub(crate) fn nearest_triangle(
        &self,
        p: Vec3,
        max_distance: f32,
        hint: Option<usize>,
    ) -> Option<usize> {
        #[cfg(target_arch = "x86_64")]
        match self.path {
            // SAFETY: `path` was detected on this CPU.
            BoxPath::Avx512 => return unsafe { self.nearest_avx512(p, max_distance, hint) },
            // SAFETY: as above.
            BoxPath::Avx2 => return unsafe { self.nearest_avx2(p, max_distance, hint) },
            _ => {}
        }
        self.nearest_from(p, max_distance, hint)
    }

    /// [`PointTree::nearest_triangle`] compiled for AVX-512 (F, VL, BW, DQ)
    /// besides AVX2: compares into mask registers, 32 vector registers.
    ///
    /// # Safety
    /// The CPU must support every feature named (`BoxPath::Avx512`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,avx512f,avx512vl,avx512bw,avx512dq,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn nearest_avx512(
        &self,
        p: Vec3,
        max_distance: f32,
        hint: Option<usize>,
    ) -> Option<usize> {
        self.nearest_from(p, max_distance, hint)
    }

    /// [`PointTree::nearest_triangle`] compiled for AVX2: a node's eight
    /// box distances in one vector each step.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn nearest_avx2(
        &self,
        p: Vec3,
        max_distance: f32,
        hint: Option<usize>,
    ) -> Option<usize> {
        self.nearest_from(p, max_distance, hint)
    }

    /// The body of [`PointTree::nearest_triangle`]: of a node's children
    /// within reach (in slot order, from a mask of the eight compares), the
    /// nearest is walked next and the others pushed; a leaf's triangles are
    /// solved a group at a time from their corners in structure of arrays.
    #[inline(always)]
    fn nearest_from(&self, p: Vec3, max_distance: f32, hint: Option<usize>) -> Option<usize> {
        if !p.is_finite() || self.nodes.is_empty() || max_distance.is_nan() || max_distance < 0.0 {
            return None;
        }
        let mut best2 = if max_distance.is_finite() {
            max_distance * max_distance
        } else {
            f32::INFINITY
        };
        let limit2 = best2;
        let mut best: Option<usize> = None;
        if let Some(h) = hint.filter(|&h| h < self.tris.len()) {
            let (dh, _, _) = triangle_distance2(p, &self.tris[h]);
            if dh <= limit2 {
                best2 = dh;
                best = Some(h);
            }
        }
        // Left uninitialised (zeroing it would be a memset per query): only
        // entries below `sp`, each written before, are read.
        let mut small = [const { MaybeUninit::<Entry>::uninit() }; SMALL_STACK];
        let mut big = Vec::new();
        let stack: &mut [MaybeUninit<Entry>] = if self.stack_need <= SMALL_STACK {
            &mut small
        } else {
            big.resize(self.stack_need, MaybeUninit::uninit());
            &mut big
        };
        stack[0] = MaybeUninit::new((0, 0, 0.0));
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            // SAFETY: entries below `sp` have been written.
            let (child, count, d2) = unsafe { stack[sp].assume_init() };
            if d2 > best2 {
                continue;
            }
            if count > 0 {
                let (g0, count) = (child as usize, count as usize);
                for g in 0..count.div_ceil(LANES) {
                    let n = (count - g * LANES).min(LANES);
                    let d = group_distance2(p, self, g0 + g, n);
                    for (k, &dt) in d.iter().enumerate().take(n) {
                        if dt < best2 || (best.is_none() && dt <= limit2) {
                            best2 = dt;
                            best = Some(self.groups.first[g0 + g] as usize + k);
                        }
                    }
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            let d2 = box_distance2(&node.min, &node.max, p);
            let mut within = 0u32;
            for (k, (&d, &c)) in d2.iter().zip(&node.child).enumerate() {
                within |= u32::from(d <= best2 && c != EMPTY) << k;
            }
            let mut nearest = (f32::INFINITY, usize::MAX);
            while within != 0 {
                let k = within.trailing_zeros() as usize;
                within &= within - 1;
                self.prefetch(node.child[k], node.count[k]);
                let d = d2[k];
                if d < nearest.0 {
                    if nearest.1 != usize::MAX && sp < stack.len() {
                        let n = nearest.1;
                        stack[sp] = MaybeUninit::new((node.child[n], node.count[n], nearest.0));
                        sp += 1;
                    }
                    nearest = (d, k);
                } else if sp < stack.len() {
                    stack[sp] = MaybeUninit::new((node.child[k], node.count[k], d));
                    sp += 1;
                }
            }
            if nearest.1 != usize::MAX && sp < stack.len() {
                let n = nearest.1;
                stack[sp] = MaybeUninit::new((node.child[n], node.count[n], nearest.0));
                sp += 1;
            }
        }
        best
    }

    /// Request the memory that child `child` (of `count` triangles) will
    /// read when it is visited: a node's boxes and references (its first
    /// four cache lines; the triangle ranges after them are not read), or a
    /// leaf's first group of corners. Its lines then arrive while the
    /// nearer children are searched, as the ray traversal prefetches
    /// (`accel::bvh::prefetch`).
    #[inline(always)]
    fn prefetch(&self, child: u32, count: u32) {
        if count == 0 {
            let node = self.nodes.as_ptr().wrapping_add(child as usize);
            prefetch_lines(node as *const u8, 4);
        } else {
            let group = self.groups.corners.as_ptr().wrapping_add(child as usize) as *const u8;
            prefetch_lines(group, 2);
            prefetch_lines(group.wrapping_add(std::mem::size_of::<Group>() - 1), 1);
        }
    }
}

/// The closest point through any structure's regions
/// ([`Accel::visit_regions`], `accel` built over `mesh`): a region farther
/// than the best triangle so far is pruned; triangles are solved in `f64`.
/// Same contract as [`SurfaceBvh::closest_point`].
pub fn closest_point_in(
    accel: &dyn Accel,
    mesh: &TriangleMesh,
    p: Vec3,
    max_distance: f32,
) -> Option<ClosestPoint> {
    if !p.is_finite() || max_distance.is_nan() || max_distance < 0.0 {
        return None;
    }
    let p64 = p.as_dvec3();
    let mut best2 = (max_distance as f64).powi(2);
    let mut best: Option<(u32, DVec3, f64, f64)> = None;
    let n = mesh.num_triangles();
    let best_cell = std::cell::Cell::new(best2);
    accel.visit_regions(
        &mut |region| {
            let (lo, hi) = (region.min.as_dvec3(), region.max.as_dvec3());
            let q = p64.clamp(lo, hi);
            // Slack for the regions' f32 rounding.
            q.distance_squared(p64) <= best_cell.get() * (1.0 + 1e-6) + 1e-30
        },
        &mut |prims| {
            for &t in prims {
                if (t as usize) >= n {
                    continue;
                }
                let tri = mesh.triangle(t as usize).map(|c| c.as_dvec3());
                let (q, u, v) = closest_on_triangle64(p64, &tri);
                let d2 = q.distance_squared(p64);
                let better = match best {
                    Some((bt, ..)) => d2 < best2 || (d2 == best2 && t < bt),
                    None => d2 <= best2,
                };
                if better {
                    best2 = d2;
                    best_cell.set(d2);
                    best = Some((t, q, u, v));
                }
            }
        },
    );
    best.map(|(prim, q, u, v)| ClosestPoint {
        point: q.as_vec3(),
        distance: q.distance(p64) as f32,
        prim,
        u: u as f32,
        v: v as f32,
    })
}

/// Reference: every triangle of `mesh` in `f64`; the nearest (lowest index
/// on ties) as `(distance, prim, point)`, `None` for an empty mesh. Each
/// triangle's point comes from [`super::exact::closest_point_on_triangle`],
/// written apart from the search's kernel (degenerate triangles handled
/// first, by their edges), so that the reference does not share its faults.
pub fn closest_point_brute(mesh: &TriangleMesh, p: DVec3) -> Option<(f64, u32, DVec3)> {
    let mut best: Option<(f64, u32, DVec3)> = None;
    for t in 0..mesh.num_triangles() {
        let tri = mesh.triangle(t).map(|c| c.as_dvec3());
        let q = super::exact::closest_point_on_triangle(p, &tri);
        let d = q.distance(p);
        if best.is_none_or(|b| d < b.0) {
            best = Some((d, t as u32, q));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::super::corner_groups::group_of;
    use super::*;
    use crate::rng::Pcg32;

    /// The kernel as an instruction set's search compiles it.
    type Kernel = unsafe fn(&Group, Vec3) -> ([f32; LANES], u32);

    /// [`distance2_lanes`] compiled for AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn lanes_avx2(g: &Group, p: Vec3) -> ([f32; LANES], u32) {
        distance2_lanes(g, p)
    }

    /// [`distance2_lanes`] compiled for AVX-512 besides.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,avx512f,avx512vl,avx512bw,avx512dq,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn lanes_avx512(g: &Group, p: Vec3) -> ([f32; LANES], u32) {
        distance2_lanes(g, p)
    }

    /// The wider compilations of the kernel this CPU runs.
    fn kernels() -> Vec<(&'static str, Kernel)> {
        let mut v: Vec<(&'static str, Kernel)> = Vec::new();
        #[cfg(target_arch = "x86_64")]
        {
            let path = BoxPath::detect();
            if matches!(path, BoxPath::Avx2 | BoxPath::Avx512) {
                v.push(("avx2", lanes_avx2));
            }
            if path == BoxPath::Avx512 {
                v.push(("avx512", lanes_avx512));
            }
        }
        v
    }

    /// The four-lane kernel gives the scalar kernel's squared distance bit
    /// for bit (for every lane it solves; the others go to the scalar
    /// kernel), and so does it as compiled for each wider instruction set
    /// this CPU runs, on triangles of every shape (degenerate ones included: a
    /// repeated corner, collinear corners, a point triangle, slivers at the
    /// thin-triangle angle) and points in every Voronoi region of each; and
    /// both are within rounding of the `f64` closest point of the separate
    /// exact kernel, the degenerate and nearly collinear ones too (any two
    /// corners at one point among them).
    #[test]
    fn four_lane_distances_are_the_scalar_ones() {
        let mut rng = Pcg32::new(11);
        let mut r = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
        let mut degenerate = 0;
        for round in 0..20_000 {
            let mut tris = [[Vec3::ZERO; 3]; LANES];
            for t in tris.iter_mut() {
                *t = [r(), r(), r()];
            }
            match round % 6 {
                1 => tris[1][2] = tris[1][0],
                2 => tris[2][2] = tris[2][0] * 0.25 + tris[2][1] * 0.75,
                3 => tris[3] = [tris[3][0]; 3],
                4 => tris[1][1] = tris[1][0],
                5 => tris[2][2] = tris[2][1],
                _ => {}
            }
            // Lane 0 of every round is a sliver at the thin-triangle angle
            // (sin = 1/64) give or take 2%, where the f32 and f64 paths meet.
            let [a, b, _] = tris[0];
            let e = b - a;
            let w = r();
            let across = (w - e * (w.dot(e) / e.length_squared())).normalize_or(Vec3::Z);
            let sin = (1.0 / 64.0) * (0.98 + 0.04 * (round % 101) as f32 / 100.0);
            tris[0][2] = a + e * 0.6 + across * (0.6 * e.length() * sin / (1.0 - sin * sin).sqrt());
            degenerate += usize::from(round % 6 != 0);
            let p = r() * 1.5;
            let n = 1 + round % LANES;
            let group = group_of(&tris[..n]);
            let (lanes, unsolved) = distance2_lanes(&group, p);
            for (kernel, other) in kernels() {
                // SAFETY: `kernels` lists those this CPU runs.
                let (l, u) = unsafe { other(&group, p) };
                let bits = |d: [f32; LANES]| d.map(f32::to_bits);
                assert_eq!(
                    (bits(l), u),
                    (bits(lanes), unsolved),
                    "{kernel}, round {round}"
                );
            }
            for k in 0..n {
                let (d2, _, _) = triangle_distance2(p, &tris[k]);
                if unsolved & (1 << k) == 0 {
                    assert_eq!(lanes[k].to_bits(), d2.to_bits(), "round {round}, lane {k}");
                }

                let t64 = tris[k].map(|c| c.as_dvec3());
                let q = super::super::exact::closest_point_on_triangle(p.as_dvec3(), &t64);
                let exact = q.distance_squared(p.as_dvec3());
                assert!(
                    (d2 as f64 - exact).abs() <= 1e-5 * (1.0 + exact),
                    "round {round}"
                );
            }
        }
        assert!(degenerate > 10_000);
    }
}
