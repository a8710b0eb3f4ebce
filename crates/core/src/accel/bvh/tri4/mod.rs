//! Leaves of [`super::Bvh4`] as packs of four Möller triangles in
//! structure-of-arrays layout, tested four at once.
//!
//! This is the idea of Embree's `triangle4` leaves (Wald, Woop, Benthin,
//! Johnson, Ernst, "Embree: a kernel framework for efficient CPU ray
//! tracing", SIGGRAPH 2014): a leaf's triangles are stored lane by lane, so
//! one ray meets four of them with the same SIMD instructions a scalar test
//! spends on one. The arithmetic is [`Moller::intersect`]'s, operation for
//! operation and in the same order (no fused multiply-adds), so every lane
//! gives bit for bit the hit, `t`, `u` and `v` of the scalar test, with its
//! conservative tolerance capped at [`crate::tri::MAX_EDGE_TOLERANCE`]; the
//! SSE kernel is in [`sse`], the scalar fallback here.
//!
//! A leaf of `n` triangles takes `ceil(n / 4)` consecutive packs, the
//! triangles in the binary build's leaf order; the unused lanes of the last
//! pack hold a zero triangle, which the test never hits (its determinant is
//! 0 or NaN for every ray) and which the lane mask excludes besides.

#[cfg(target_arch = "x86_64")]
mod sse;
mod unhittable;

pub(crate) use unhittable::{never_hit, Unhittable};

use super::wide_node::Child4;
use crate::aabb::Aabb;
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::moller::MollerTri;
use crate::tri::{Moller, TriangleTest, MAX_EDGE_TOLERANCE};
use glam::Vec3;
use rayon::prelude::*;

/// Four Möller triangles (first corner, edge vectors, their max norms) in
/// structure-of-arrays layout, with their mesh triangle indices: Embree's
/// `triangle4` (Wald et al. 2014) with [`Moller`]'s record. 192 bytes, three
/// cache lines.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct Tri4 {
    /// First corner, `v0[axis][lane]`.
    pub v0: [[f32; 4]; 3],
    /// `b - a`, per axis.
    pub e1: [[f32; 4]; 3],
    /// `c - a`, per axis.
    pub e2: [[f32; 4]; 3],
    /// `max |e1_i|` per lane.
    pub e1_max: [f32; 4],
    /// `max |e2_i|` per lane.
    pub e2_max: [f32; 4],
    /// Mesh triangle index per lane (`u32::MAX` in unused lanes).
    pub prim: [u32; 4],
}

impl Tri4 {
    /// Four unused lanes (zero triangles, never hit).
    pub const EMPTY: Tri4 = Tri4 {
        v0: [[0.0; 4]; 3],
        e1: [[0.0; 4]; 3],
        e2: [[0.0; 4]; 3],
        e1_max: [0.0; 4],
        e2_max: [0.0; 4],
        prim: [u32::MAX; 4],
    };

    /// Store `tri` (mesh triangle `prim`) in lane `lane`.
    pub fn set(&mut self, lane: usize, tri: &MollerTri, prim: u32) {
        for a in 0..3 {
            self.v0[a][lane] = tri.v0[a];
            self.e1[a][lane] = tri.e1[a];
            self.e2[a][lane] = tri.e2[a];
        }
        self.e1_max[lane] = tri.e1_max;
        self.e2_max[lane] = tri.e2_max;
        self.prim[lane] = prim;
    }

    /// Store mesh triangle `prim` of `mesh` in lane `lane`, and return its
    /// reach ([`TriangleTest::reach`]), taken while its corners are at
    /// hand: the packing and the refit both fit boxes to it.
    #[inline]
    pub(crate) fn load(&mut self, lane: usize, mesh: &TriangleMesh, prim: u32) -> Aabb {
        let [a, b, c] = mesh.triangle(prim as usize);
        self.set(lane, &Moller::precompute(a, b, c), prim);
        Moller::reach(a, b, c)
    }

    /// Every used lane loaded again from `mesh` (its vertices moved; the
    /// same triangles), returning the union of their reach: the refit's
    /// step for one pack.
    pub(crate) fn reload(&mut self, mesh: &TriangleMesh) -> Aabb {
        let tris = mesh.num_triangles();
        let mut reach = Aabb::EMPTY;
        for lane in 0..4 {
            let prim = self.prim[lane];
            if (prim as usize) < tris {
                reach = reach.union(self.load(lane, mesh, prim));
            }
        }
        reach
    }

    /// The triangle in lane `lane`.
    pub fn get(&self, lane: usize) -> MollerTri {
        let at = |v: &[[f32; 4]; 3]| Vec3::new(v[0][lane], v[1][lane], v[2][lane]);
        MollerTri {
            v0: at(&self.v0),
            e1: at(&self.e1),
            e2: at(&self.e2),
            e1_max: self.e1_max[lane],
            e2_max: self.e2_max[lane],
        }
    }

    /// Test the lanes in `lanes` (bit `i` for lane `i`) against the ray over
    /// `[ray.tnear, tfar]`: with SSE on x86_64 (part of its baseline), one
    /// lane after the other elsewhere. `EARLY` rejects certain misses
    /// before the division (same answers; see `sse::hits`).
    #[inline(always)]
    pub fn hits<const EARLY: bool>(&self, ray: &Ray, r: &Ray4, tfar: f32, lanes: u32) -> TriHits4 {
        #[cfg(target_arch = "x86_64")]
        {
            let _ = ray;
            sse::hits::<EARLY>(self, r, tfar, lanes)
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            self.hits_scalar(ray, r, tfar, lanes)
        }
    }

    /// The lanes of `lanes` that [`Moller::crossing`] might not dismiss
    /// (see `sse::crossing_candidates`); all of them off x86_64.
    #[inline(always)]
    pub fn crossing_candidates<const SURE: bool>(&self, r: &Ray4, lanes: u32) -> u32 {
        #[cfg(target_arch = "x86_64")]
        {
            sse::crossing_candidates::<SURE>(self, r, lanes)
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = r;
            lanes
        }
    }

    /// [`Tri4::hits`] one lane at a time with [`Moller::intersect`] (the
    /// fallback off x86_64, and the reference of the unit tests).
    #[cfg_attr(target_arch = "x86_64", allow(dead_code))]
    pub fn hits_scalar(&self, ray: &Ray, r: &Ray4, tfar: f32, lanes: u32) -> TriHits4 {
        let mut out = TriHits4::default();
        for lane in 0..4 {
            if lanes & (1 << lane) == 0 {
                continue;
            }
            if let Some(h) = Moller::intersect(&self.get(lane), ray, &r.scale[0], tfar) {
                out.mask |= 1 << lane;
                out.t[lane] = h.t;
                out.u[lane] = h.u;
                out.v[lane] = h.v;
            }
        }
        out
    }
}

/// Which lanes of a [`Tri4`] a ray hits, and where (`t`, `u`, `v` are
/// meaningful only in lanes set in `mask`).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct TriHits4 {
    pub mask: u32,
    pub t: [f32; 4],
    pub u: [f32; 4],
    pub v: [f32; 4],
}

/// A ray prepared once for [`Tri4`] tests: origin, direction and its
/// absolute value broadcast to four lanes, [`Moller`]'s tolerance factor
/// `64u · max|d_i|` and its cheap determinant bound `0.75` times that, and
/// `tnear`.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(crate) struct Ray4 {
    pub origin: [[f32; 4]; 3],
    pub dir: [[f32; 4]; 3],
    pub dir_abs: [[f32; 4]; 3],
    pub scale: [f32; 4],
    pub clear_scale: [f32; 4],
    pub tnear: [f32; 4],
}

impl Ray4 {
    /// Prepare `ray`.
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        let scale = Moller::prepare(ray);
        let o = ray.origin.to_array();
        let d = ray.dir.to_array();
        // Spelled out: `array::map`'s closures became calls inside the
        // traversals compiled for AVX2 (BENCHMARKS.md).
        let a = [d[0].abs(), d[1].abs(), d[2].abs()];
        Ray4 {
            origin: [[o[0]; 4], [o[1]; 4], [o[2]; 4]],
            dir: [[d[0]; 4], [d[1]; 4], [d[2]; 4]],
            dir_abs: [[a[0]; 4], [a[1]; 4], [a[2]; 4]],
            scale: [scale; 4],
            // The scalar test's `0.75 * scale * e1_max * e2_max` multiplies
            // left to right, so this first product is the same.
            clear_scale: [0.75 * scale; 4],
            tnear: [ray.tnear; 4],
        }
    }
}

/// The packed leaves of a [`super::Bvh4`] over [`Moller`]: Embree-style
/// `triangle4` packs (Wald et al. 2014), a leaf's packs consecutive, and
/// the mesh triangles left out of them because no ray can hit them
/// ([`Unhittable`]).
pub(crate) struct Tri4Leaves {
    packs: super::mapped::Store<Tri4>,
    /// The triangles in no pack.
    pub unhittable: Unhittable,
}

impl Tri4Leaves {
    /// Pack the leaves of a collapsed wide tree: `order` is the build's
    /// triangle order, and `refs` yields every child reference (the root
    /// first, then node by node); each leaf among them (`count > 0`,
    /// triangle range `index..index + count` of `order`) is packed in that
    /// order and rewritten to start at its first pack instead; `count` stays
    /// the number of triangles. Packs follow the nodes' order, so a node's
    /// leaves lie side by side.
    ///
    /// First the packs' triangle ranges (first position in `order`, lanes
    /// used) are assigned leaf by leaf, rewriting the references; then the
    /// packs are built in parallel straight from the mesh, with no
    /// intermediate array of all triangles (the packing took
    /// 115–150 ms of the full dragon's build on one thread, sequential).
    /// Returns the packs and each pack's reach (the union of its
    /// triangles' [`TriangleTest::reach`], for `fit`).
    pub(crate) fn from_refs<'a>(
        mesh: &TriangleMesh,
        order: &[u32],
        refs: impl Iterator<Item = &'a mut Child4>,
    ) -> (Self, Vec<Aabb>) {
        let mut ranges: Vec<(u32, u32)> =
            Vec::with_capacity(order.len().div_ceil(4) + order.len() / 4);
        for leaf in refs.filter(|c| c.count > 0) {
            let (first, count) = (leaf.index as usize, leaf.count as usize);
            leaf.index = ranges.len() as u32;
            for start in (first..first + count).step_by(4) {
                ranges.push((start as u32, (first + count - start).min(4) as u32));
            }
        }
        let mut packs = super::huge_pages::with_capacity(ranges.len());
        let mut reach = Vec::with_capacity(ranges.len());
        ranges
            .par_iter()
            .with_min_len(1024)
            .map(|&(start, lanes)| {
                let (mut p, mut r) = (Tri4::EMPTY, Aabb::EMPTY);
                for lane in 0..lanes as usize {
                    r = r.union(p.load(lane, mesh, order[start as usize + lane]));
                }
                (p, r)
            })
            .unzip_into_vecs(&mut packs, &mut reach);
        (
            Tri4Leaves {
                packs: packs.into(),
                unhittable: Unhittable::none(),
            },
            reach,
        )
    }

    /// The packs, for the packet traversal of [`super::packet`].
    pub(crate) fn packs(&self) -> &[Tri4] {
        &self.packs
    }

    /// Packs made elsewhere (a saved structure, `super::persist`).
    pub(crate) fn from_packs(packs: super::mapped::Store<Tri4>, unhittable: Unhittable) -> Self {
        Tri4Leaves { packs, unhittable }
    }

    /// The packs, to rewrite their triangles in place (`super::refit`).
    pub(crate) fn packs_mut(&mut self) -> &mut [Tri4] {
        &mut self.packs
    }

    /// Bytes held: the packs and the left-out triangles' indices.
    pub fn bytes(&self) -> usize {
        std::mem::size_of_val(&self.packs[..]) + std::mem::size_of_val(&self.unhittable.prims[..])
    }

    /// Mesh triangle indices of the leaf `leaf`, appended to `out`.
    pub fn prims(&self, leaf: Child4, out: &mut Vec<u32>) {
        let first = leaf.index as usize;
        let count = leaf.count as usize;
        for (k, p) in self.packs[first..first + count.div_ceil(4)]
            .iter()
            .enumerate()
        {
            out.extend_from_slice(&p.prim[..(count - 4 * k).min(4)]);
        }
    }

    /// Test the `count` triangles of the leaf whose packs start at `first`,
    /// with exactly the answers of the scalar leaf loop
    /// ([`crate::accel::leaf::LeafTriangles::test`] over [`Moller`]):
    /// nearest-hit mode (`ANY = false`) keeps the nearest hit in `best` and
    /// shrinks `tfar` to it, the earlier triangle winning at equal `t`;
    /// any-hit mode returns true at the first pack with a hit.
    #[inline(always)]
    pub fn test<const ANY: bool>(
        &self,
        first: usize,
        count: usize,
        ray: &Ray,
        r: &Ray4,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        let mut left = count;
        for p in &self.packs[first..first + count.div_ceil(4)] {
            let lanes = if left >= 4 { 0xf } else { (1u32 << left) - 1 };
            left = left.saturating_sub(4);
            // Early rejection pays for nearest-hit queries only.
            let h = match ANY {
                true => p.hits::<false>(ray, r, *tfar, lanes),
                false => p.hits::<true>(ray, r, *tfar, lanes),
            };
            if h.mask == 0 {
                continue;
            }
            if ANY {
                return true;
            }
            // Nearest lane, the earliest at equal t: what the scalar loop
            // keeps, since all four were tested against the same tfar and
            // it accepts a later triangle only when strictly nearer.
            let mut m = h.mask;
            let mut k = m.trailing_zeros() as usize;
            m &= m - 1;
            while m != 0 {
                let i = m.trailing_zeros() as usize;
                m &= m - 1;
                if h.t[i] < h.t[k] {
                    k = i;
                }
            }
            if best.is_none_or(|b| h.t[k] < b.t) {
                *tfar = h.t[k];
                *best = Some(Hit {
                    t: h.t[k],
                    u: h.u[k],
                    v: h.v[k],
                    prim: p.prim[k],
                });
            }
        }
        false
    }
}

/// The cap of the scalar test, for the SIMD kernel.
pub(crate) const CAP: f32 = MAX_EDGE_TOLERANCE;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::leaf::LeafTriangles;
    use crate::rng::Pcg32;

    /// A triangle of random shape, size and place, or now and then a
    /// degenerate one (all corners equal, two equal, or collinear), or one
    /// with a non-finite corner.
    fn corners(rng: &mut Pcg32) -> [Vec3; 3] {
        // Now and then tiny or huge, so that det nears the ends of the f32
        // range (the early rejection's thresholds, `sse::early_miss`).
        let scale = if rng.below(16) == 0 {
            10f32.powf(rng.range_f32(-19.0, 19.0))
        } else {
            10f32.powf(rng.range_f32(-3.0, 3.0))
        };
        let centre =
            rng.in_box(Vec3::splat(-1.0), Vec3::splat(1.0)) * 10f32.powf(rng.range_f32(-1.0, 4.0));
        let a = centre + rng.unit_vector() * scale;
        let b = centre + rng.unit_vector() * scale;
        let c = centre + rng.unit_vector() * scale;
        match rng.below(16) {
            0 => [a, a, a],
            1 => [a, b, b],
            2 => [a, b, a + (b - a) * rng.range_f32(-2.0, 2.0)],
            3 => {
                let mut t = [a, b, c];
                t[rng.below(3) as usize][rng.below(3) as usize] =
                    [f32::NAN, f32::INFINITY, f32::NEG_INFINITY][rng.below(3) as usize];
                t
            }
            _ => [a, b, c],
        }
    }

    /// Random packs and rays: rays aimed at a lane's triangle (inside, on an
    /// edge shared with the next lane, or just outside), parallel to its
    /// plane, random, or with NaN and infinite components; tnear and tfar
    /// random, or tfar exactly at a hit.
    #[test]
    fn sse_pack_equals_scalar_moller_bit_for_bit() {
        let mut rng = Pcg32::new(2014);
        let (mut hits, mut misses, mut edge_hits) = (0usize, 0usize, 0usize);
        for n in 0..250_000 {
            let mut tri = [[Vec3::ZERO; 3]; 4];
            for t in &mut tri {
                *t = corners(&mut rng);
            }
            // Lanes 0 and 1 share the edge b-c now and then (as in a mesh,
            // in opposite orientation).
            let shared = rng.below(3) == 0;
            if shared {
                let [_, b, c] = tri[0];
                let d = (b + c) * 0.5 + rng.unit_vector() * (b - c).length();
                tri[1] = [c, b, d];
            }
            let mut pack = Tri4::EMPTY;
            let used = 1 + rng.below(4) as usize;
            let pre: Vec<MollerTri> = tri
                .iter()
                .map(|&[a, b, c]| Moller::precompute(a, b, c))
                .collect();
            for (lane, t) in pre.iter().enumerate().take(used) {
                pack.set(lane, t, lane as u32);
            }
            let lanes = if rng.below(4) == 0 {
                rng.below(16)
            } else {
                (1u32 << used) - 1
            };
            let aim_lane = rng.below(used as u32) as usize;
            let [a, b, c] = tri[aim_lane];
            let (u, v) = match rng.below(4) {
                0 if shared => {
                    let s = rng.next_f32();
                    (1.0 - s, s)
                }
                1 => (rng.range_f32(-0.01, 1.01), rng.range_f32(-0.01, 1.01)),
                _ => {
                    let (u, v) = (rng.next_f32(), rng.next_f32());
                    if u + v > 1.0 {
                        (1.0 - u, 1.0 - v)
                    } else {
                        (u, v)
                    }
                }
            };
            let target = a + (b - a) * u + (c - a) * v;
            let mut origin = target + rng.unit_vector() * 10f32.powf(rng.range_f32(-2.0, 3.0));
            let mut dir = match rng.below(8) {
                // In the triangle's plane.
                0 => (b - a) * rng.range_f32(-1.0, 1.0) + (c - a) * rng.range_f32(-1.0, 1.0),
                1 => rng.unit_vector(),
                2 => (target - origin) * 10f32.powf(rng.range_f32(-19.0, 19.0)),
                _ => (target - origin) * rng.range_f32(0.1, 10.0),
            };
            if rng.below(32) == 0 {
                let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 0.0][rng.below(4) as usize];
                if rng.below(2) == 0 {
                    origin[rng.below(3) as usize] = bad;
                } else {
                    dir[rng.below(3) as usize] = bad;
                }
            }
            let tnear = if rng.below(4) == 0 {
                rng.range_f32(0.0, 2.0)
            } else {
                0.0
            };
            let mut tfar = match rng.below(4) {
                0 => rng.range_f32(0.0, 3.0),
                1 => f32::NAN,
                _ => f32::INFINITY,
            };
            let ray = Ray::segment(origin, dir, tnear, f32::INFINITY);
            let r = Ray4::new(&ray);
            if rng.below(4) == 0 {
                // tfar exactly at the aimed lane's hit, the edge of the interval.
                if let Some(h) = Moller::intersect(&pre[aim_lane], &ray, &r.scale[0], tfar) {
                    tfar = h.t;
                }
            }
            let ray = Ray { tfar, ..ray };
            let simd = pack.hits::<true>(&ray, &r, tfar, lanes);
            let plain = pack.hits::<false>(&ray, &r, tfar, lanes);
            assert_eq!(plain.mask, simd.mask);
            // The independent reference: the scalar test on each lane's own
            // precomputed record.
            for (lane, t) in pre.iter().enumerate() {
                let want = if lane < used && lanes & (1 << lane) != 0 {
                    Moller::intersect(t, &ray, &r.scale[0], tfar)
                } else {
                    None
                };
                let got = simd.mask & (1 << lane) != 0;
                assert_eq!(
                    got,
                    want.is_some(),
                    "pack {n} lane {lane}: {ray:?} {:?}",
                    tri[lane]
                );
                match want {
                    Some(h) => {
                        let g = (simd.t[lane], simd.u[lane], simd.v[lane]);
                        assert_eq!(
                            [g.0.to_bits(), g.1.to_bits(), g.2.to_bits()],
                            [h.t.to_bits(), h.u.to_bits(), h.v.to_bits()],
                            "pack {n} lane {lane}: {ray:?} {g:?} {h:?}"
                        );
                        hits += 1;
                    }
                    None => misses += 1,
                }
            }
            // Both neighbours of a shared edge hit (the edge band).
            edge_hits += (shared && simd.mask & 3 == 3) as usize;
            // The portable fallback too.
            let scalar = pack.hits_scalar(&ray, &r, tfar, lanes);
            assert_eq!(scalar.mask, simd.mask);
        }
        assert!(
            hits > 50_000 && misses > 500_000,
            "{hits} hits, {misses} misses"
        );
        assert!(
            edge_hits > 1000,
            "{edge_hits} rays hit both sides of an edge"
        );
    }

    /// Rays that pass just beyond an edge of small triangles seen from far
    /// away, where the edge tolerances reach their cap: `u` or `v` within
    /// 1% of `-CAP`, or `u + v` within 1% of `1 + 2·CAP`. The SSE pack,
    /// which rejects lanes early from the undivided barycentrics
    /// (`sse::early_miss`), agrees with the scalar test on every lane,
    /// including the hits that a margin of `2^-8` too small would reject
    /// (counted, so the test fails if it stops reaching them).
    #[test]
    fn early_rejection_keeps_the_hits_at_the_capped_tolerance() {
        let mut rng = Pcg32::new(256);
        let (mut near_edge, mut near_sum) = (0, 0);
        for n in 0..100_000 {
            let mut pack = Tri4::EMPTY;
            let mut pre = Vec::new();
            let centre = rng.in_box(Vec3::splat(-100.0), Vec3::splat(100.0));
            for lane in 0..4 {
                let size = 10f32.powf(rng.range_f32(-3.0, -1.0));
                let [a, b, c] = [0; 3].map(|_| centre + rng.unit_vector() * size);
                let t = Moller::precompute(a, b, c);
                pack.set(lane, &t, lane as u32);
                pre.push((t, [a, b, c]));
            }
            let (_, [a, b, c]) = pre[rng.below(4) as usize];
            let x = rng.range_f32(-0.01, 0.01);
            let w = rng.range_f32(0.1, 0.8);
            let (u, v) = match rng.below(3) {
                0 => (-CAP * (1.0 + x), w),
                1 => (w, -CAP * (1.0 + x)),
                _ => {
                    let sum = (1.0 + 2.0 * CAP) * (1.0 + x);
                    (sum * w, sum * (1.0 - w))
                }
            };
            let target = a + (b - a) * u + (c - a) * v;
            let origin = target + rng.unit_vector() * 10f32.powf(rng.range_f32(2.0, 4.0));
            let ray = Ray::new(origin, target - origin);
            let r = Ray4::new(&ray);
            let simd = pack.hits::<true>(&ray, &r, ray.tfar, 0xf);
            for (lane, (t, _)) in pre.iter().enumerate() {
                let want = Moller::intersect(t, &ray, &r.scale[0], ray.tfar);
                assert_eq!(
                    simd.mask & (1 << lane) != 0,
                    want.is_some(),
                    "ray {n} lane {lane}: {ray:?}"
                );
                if let Some(h) = want {
                    let margin = 1.0 - 1.0 / 256.0;
                    near_edge += (h.u.min(h.v) < -CAP * margin) as usize;
                    near_sum += (h.u + h.v > (1.0 + 2.0 * CAP) * margin) as usize;
                }
            }
        }
        assert!(
            near_edge > 100 && near_sum > 100,
            "{near_edge} hits beyond -CAP·(1 - 2^-8), {near_sum} with u + v beyond (1 + 2·CAP)·(1 - 2^-8)"
        );
    }

    /// Whole leaves of 1 to 13 triangles, with duplicates (equal `t` on
    /// different triangles): the packed leaf keeps exactly the scalar leaf
    /// loop's nearest hit, tie rule and shrunk `tfar`, and the same
    /// occlusion answer.
    #[test]
    fn packed_leaf_equals_scalar_leaf_loop() {
        let mut rng = Pcg32::new(4);
        let mut ties = 0;
        for _ in 0..20_000 {
            let n = 1 + rng.below(13) as usize;
            let mut positions = Vec::new();
            let mut indices = Vec::new();
            for i in 0..n {
                let t = if i > 0 && rng.below(4) == 0 {
                    // A copy of an earlier triangle (a tie), maybe reordered.
                    let j = rng.below(i as u32) as usize * 3;
                    [positions[j], positions[j + 1], positions[j + 2]]
                } else {
                    let c = rng.in_box(Vec3::splat(-1.0), Vec3::splat(1.0));
                    [0, 1, 2].map(|_| c + rng.unit_vector() * 0.7)
                };
                positions.extend(t);
                indices.push([3 * i as u32, 3 * i as u32 + 1, 3 * i as u32 + 2]);
            }
            let mesh = TriangleMesh::new(positions, indices);
            let order: Vec<u32> = (0..n as u32).collect();
            let scalar = LeafTriangles::<Moller>::new(&mesh, order.clone());
            let mut root = Child4 {
                index: 0,
                count: n as u32,
            };
            let (packed, _) = Tri4Leaves::from_refs(&mesh, &order, std::iter::once(&mut root));
            assert_eq!(root.index, 0);
            let mut prims = Vec::new();
            packed.prims(root, &mut prims);
            assert_eq!(prims, order);

            let origin = rng.in_box(Vec3::splat(-3.0), Vec3::splat(3.0));
            let ray = Ray::new(
                origin,
                rng.in_box(Vec3::splat(-0.5), Vec3::splat(0.5)) - origin,
            );
            let (rd, r4) = (Moller::prepare(&ray), Ray4::new(&ray));
            // Start with no hit, or with a hit found earlier (as in a
            // previous leaf), at a distance that may equal one of these.
            let start = match rng.below(3) {
                0 => None,
                _ => {
                    let [a, b, c] = mesh.triangle(rng.below(n as u32) as usize);
                    let tri = Moller::precompute(a, b, c);
                    Moller::intersect(&tri, &ray, &rd, ray.tfar).map(|h| Hit {
                        t: h.t,
                        u: h.u,
                        v: h.v,
                        prim: 1000,
                    })
                }
            };
            let (mut tf_a, mut best_a) = (start.map_or(ray.tfar, |h| h.t), start);
            let (mut tf_b, mut best_b) = (tf_a, start);
            scalar.test::<false>(0, n, &ray, &rd, &mut tf_a, &mut best_a);
            packed.test::<false>(0, n, &ray, &r4, &mut tf_b, &mut best_b);
            assert_eq!(tf_a.to_bits(), tf_b.to_bits());
            assert_eq!(
                best_a.map(|h| (h.t.to_bits(), h.u.to_bits(), h.v.to_bits(), h.prim)),
                best_b.map(|h| (h.t.to_bits(), h.u.to_bits(), h.v.to_bits(), h.prim))
            );
            if let (Some(a), Some(s)) = (best_a, start) {
                ties += (a.prim != s.prim && a.t == s.t) as usize;
            }
            let tfar = ray.tfar;
            let (mut x, mut y) = (None, None);
            assert_eq!(
                scalar.test::<true>(0, n, &ray, &rd, &mut tfar.clone(), &mut x),
                packed.test::<true>(0, n, &ray, &r4, &mut tfar.clone(), &mut y)
            );
        }
        assert_eq!(ties, 0, "a later equal hit never replaces the earlier one");
    }
}
