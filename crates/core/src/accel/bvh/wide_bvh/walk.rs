//! The wide BVH's single-ray traversal as a state advanced one node or
//! leaf at a time, and batches that interleave [`WALKS`] rays (used by the
//! widths that [`NodeWidth::INTERLEAVE`]).
//!
//! An incoherent ray's traversal is one long chain of dependent loads: the
//! next node's address comes out of the current node's box test. A core
//! that runs one such chain waits on memory most of the time. Rays
//! stepped in turn give it independent chains to overlap, as the
//! software-pipelined traversals of Aila & Laine (2009, "Understanding the
//! efficiency of ray traversal on GPUs") overlap rays on a GPU. Each ray
//! gets exactly the single-ray answer: the steps are the same, only their
//! order between the rays changes.
//!
//! Single rays (and the packet path's hand-over) keep the plain loop of
//! `wide_bvh.rs`, whose state stays in registers: run through a `Walk`, shadow
//! rays on the full dragon lost 6% (0.96× → 0.90× Embree). Both share
//! `bvh/enter.rs`, the choice of the next child.

use super::{Leaves, PackedLeaf, Ray4, WideBvh, LARGE_STACK, SMALL_STACK};
use crate::accel::bvh::box_path::BoxPath;
use crate::accel::bvh::enter::enter;
use crate::accel::bvh::enter::prefetch_with;
use crate::accel::bvh::node_width::{NodeWidth, SlotEntries};
use crate::accel::bvh::ray_box::RayBox;
use crate::accel::bvh::stack::Stack;
use crate::accel::bvh::wide_leaf::LeafTest;
use crate::accel::bvh::wide_node::Child4;
use crate::hit::Hit;
use crate::ray::Ray;
use crate::tri::TriangleTest;

/// One ray's traversal state: its box-test data, leaf test, nearest hit so
/// far, the node or leaf to visit next and an `S`-entry stack.
pub(super) struct Walk<'a, L: LeafTest, const S: usize> {
    ray: &'a Ray,
    rb: RayBox,
    leaf: L,
    pub tfar: f32,
    pub best: Option<Hit>,
    cur: Child4,
    sp: usize,
    stack: Stack<S>,
}

impl<'a, L: LeafTest, const S: usize> Walk<'a, L, S> {
    /// The traversal of `ray` from `start` (the root, or a packet's node),
    /// from its current `tfar` and nearest hit.
    #[inline(always)]
    pub fn new(ray: &'a Ray, start: Child4, tfar: f32, best: Option<Hit>, leaf: L) -> Self {
        Walk {
            ray,
            rb: RayBox::new(ray),
            leaf,
            tfar,
            best,
            cur: start,
            sp: 0,
            stack: Stack::new(),
        }
    }

    /// Start over with another ray from the root, keeping the stack's
    /// memory.
    #[inline(always)]
    fn restart(&mut self, ray: &'a Ray, root: Child4, leaf: L) {
        self.ray = ray;
        self.rb = RayBox::new(ray);
        self.leaf = leaf;
        self.tfar = ray.traversal_tfar();
        self.best = None;
        self.cur = root;
        self.sp = 0;
    }
}

impl<N: NodeWidth, T: TriangleTest> WideBvh<N, T> {
    /// Visit the walk's current node or leaf, then pick the next one.
    /// Returns `None` while the traversal goes on, `Some(true)` at an
    /// any-hit query's hit (`ANY`), `Some(false)` when the stack is empty
    /// (the nearest hit is then in `w.best`).
    ///
    /// Entered children are visited near to far: the nearest next, the
    /// others pushed with their entry distances (all fetched at once,
    /// [`crate::accel::bvh::prefetch`]) and skipped on pop when a nearer hit
    /// has been found since; occlusion queries push without sorting. The
    /// root's own box is not tested: its node's test of its children's boxes
    /// culls the same rays (it cost 4% of a ray's instructions, callgrind).
    #[inline(always)]
    pub(super) fn step<const ANY: bool, const S: usize>(
        &self,
        w: &mut Walk<'_, impl LeafTest, S>,
        path: BoxPath,
    ) -> Option<bool> {
        // SAFETY (every access through `st`): the stack never holds more
        // than the unvisited siblings of the current node's ancestors, at
        // most `wide.stack` entries, which `build` checked to be below `S`
        // (vector pushes use the stack's slack beyond); reads are of
        // entries below `sp`, all written by a push.
        let st = w.stack.ptr();
        let cur = w.cur;
        if cur.count > 0 {
            let (first, count) = (cur.index as usize, cur.count as usize);
            if w.leaf.test::<ANY>(first, count, &mut w.tfar, &mut w.best) {
                return Some(true);
            }
        } else {
            debug_assert!((cur.index as usize) < self.nodes.len());
            // SAFETY: inner references are made by `collapse` from the
            // index of a node it pushed, so they are in bounds.
            let node = unsafe { self.nodes.get_unchecked(cur.index as usize) };
            // SAFETY: `path` is a kernel this CPU runs (see `traverse`).
            let h = unsafe { node.entries(path, &w.rb, w.ray.tnear, w.tfar) };
            // SAFETY: as for `st` above.
            let next = unsafe {
                enter::<ANY, _>(
                    &self.nodes,
                    node.children(),
                    h.t(),
                    h.mask(),
                    st,
                    &mut w.sp,
                    &w.leaf,
                    path == BoxPath::Avx512,
                )
            };
            if let Some(next) = next {
                w.cur = next;
                // One child entered (`enter` fetches them all when there
                // are several): request it now, so that the load overlaps
                // the other walk's step instead of waiting behind its
                // mispredicted branches (incoherent rays, full dragon:
                // about +5%, three interleaved runs).
                if h.mask().count_ones() == 1 {
                    prefetch_with::<ANY, _, _>(&self.nodes, next, &w.leaf);
                }
                return None;
            }
        }
        // Pop, skipping entries beyond the nearest hit found since they were
        // pushed.
        loop {
            if w.sp == 0 {
                return Some(false);
            }
            w.sp -= 1;
            let (c, t) = unsafe { st.read(w.sp) };
            if t <= w.tfar {
                w.cur = c;
                return None;
            }
        }
    }

    /// The answers of `rays` from the root, [`WALKS`] rays stepped in turn (see
    /// the module notes): `done(i, any, best)` receives ray `i`'s any-hit
    /// answer (`ANY`) or nearest hit. Needs packed leaves and a tree with
    /// triangles; one ray at a time otherwise.
    pub(in crate::accel::bvh) fn interleaved<const ANY: bool>(
        &self,
        rays: &[Ray],
        done: impl FnMut(usize, bool, Option<Hit>),
    ) {
        match self.path {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `path` is Avx2 only where `BoxPath::detect` found AVX2
            // and FMA on this CPU.
            BoxPath::Avx2 => unsafe { self.interleaved_avx2::<ANY>(rays, done) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `path` is Avx512 only where `BoxPath::detect` found
            // every feature `interleaved_avx512` is compiled for.
            BoxPath::Avx512 => unsafe { self.interleaved_avx512::<ANY>(rays, done) },
            path => self.interleaved_on::<ANY>(rays, path, done),
        }
    }

    /// [`WideBvh::interleaved`] compiled for AVX-512 (see `BoxPath::Avx512`).
    ///
    /// # Safety
    /// The CPU must support every feature named.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,avx512f,avx512vl,avx512bw,avx512dq,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn interleaved_avx512<const ANY: bool>(
        &self,
        rays: &[Ray],
        done: impl FnMut(usize, bool, Option<Hit>),
    ) {
        self.interleaved_on::<ANY>(rays, BoxPath::Avx512, done)
    }

    /// [`WideBvh::interleaved`] compiled for AVX2 and FMA.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn interleaved_avx2<const ANY: bool>(
        &self,
        rays: &[Ray],
        done: impl FnMut(usize, bool, Option<Hit>),
    ) {
        self.interleaved_on::<ANY>(rays, BoxPath::Avx2, done)
    }

    #[inline(always)]
    fn interleaved_on<const ANY: bool>(
        &self,
        rays: &[Ray],
        path: BoxPath,
        mut done: impl FnMut(usize, bool, Option<Hit>),
    ) {
        let packs = match &self.leaves {
            Leaves::Packed(packs) if self.stats.triangle_refs > 0 && rays.len() >= WALKS => packs,
            _ => {
                for (i, ray) in rays.iter().enumerate() {
                    let (best, any) = self.traverse::<ANY>(ray);
                    done(i, any, best);
                }
                return;
            }
        };
        let leaf = |ray| PackedLeaf {
            packs,
            ray,
            r4: Ray4::new(ray),
        };
        let done = move |i, any, best, _: &PackedLeaf<'_>| done(i, any, best);
        if self.small_stack {
            self.group::<ANY, SMALL_STACK, _>(rays, path, leaf, done)
        } else {
            self.group::<ANY, LARGE_STACK, _>(rays, path, leaf, done)
        }
    }

    /// [`WALKS`] walks over `rays` (at least [`WALKS`]), each taking the
    /// next ray when its own is done: `done(i, any, best, leaf)` gets ray
    /// `i`'s answer and its leaf test (which may hold the ray's state).
    #[inline(always)]
    pub(super) fn group<'a, const ANY: bool, const S: usize, L: LeafTest>(
        &self,
        rays: &'a [Ray],
        path: BoxPath,
        leaf: impl Fn(&'a Ray) -> L,
        mut done: impl FnMut(usize, bool, Option<Hit>, &L),
    ) {
        let start = |r: &'a Ray| Walk::<L, S>::new(r, self.root, r.traversal_tfar(), None, leaf(r));
        let mut walks: [Walk<L, S>; WALKS] = std::array::from_fn(|k| start(&rays[k]));
        let mut index: [usize; WALKS] = std::array::from_fn(|k| k);
        let mut live = [true; WALKS];
        let mut next = WALKS;
        let mut running = WALKS;
        while running > 0 {
            for k in 0..WALKS {
                if !live[k] {
                    continue;
                }
                if let Some(any) = self.step::<ANY, S>(&mut walks[k], path) {
                    done(index[k], any, walks[k].best, &walks[k].leaf);
                    if let Some(ray) = rays.get(next) {
                        walks[k].restart(ray, self.root, leaf(ray));
                        index[k] = next;
                        next += 1;
                    } else {
                        live[k] = false;
                        running -= 1;
                    }
                }
            }
        }
    }
}

/// How many rays are stepped in turn. The walks get a whole task's rays
/// (`packet::in_groups`), and twelve were faster than six by 11% on the
/// dragon, 18% on the terrain and 3% on the scatter (incoherent rays, 1 and
/// 2 threads; 8, 10 and 16 in between or below; BENCHMARKS.md). Handed
/// sixteen rays at a time, so that they ran dry every sixteen rays, three
/// or four walks were no faster than two on the full dragon on an AMD EPYC,
/// and six were 1.1-1.3x faster than two on an Intel Xeon (AVX-512, the
/// sorted child order of `sort8.rs`).
pub(super) const WALKS: usize = 12;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::BuildOptions;
    use crate::accel::Accel;
    use crate::mesh::TriangleMesh;
    use crate::rng::Pcg32;
    use crate::tri::Moller;
    use glam::Vec3;

    fn bits(h: Option<Hit>) -> Option<(u32, u32, u32, u32)> {
        h.map(|h| (h.t.to_bits(), h.u.to_bits(), h.v.to_bits(), h.prim))
    }

    /// Rays stepped in turn give every ray exactly its single-ray
    /// answer (the same `t`, `u`, `v` bits and triangle; the same
    /// occlusion), each ray answered once, for batches of 0 to 9 and 1500
    /// rays (full and bounded), with every box kernel this CPU runs, both
    /// stack sizes and both widths.
    #[test]
    fn interleaved_rays_equal_single_rays() {
        let hits = interleaved_rays_equal_single_rays_on::<crate::accel::bvh::node8::Node8>()
            + interleaved_rays_equal_single_rays_on::<crate::accel::bvh::node4::Node4>();
        assert!(hits > 2000, "too few hits to test: {hits}");
    }

    fn interleaved_rays_equal_single_rays_on<N: NodeWidth>() -> usize {
        let mut rng = Pcg32::new(77);
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for i in 0..3000u32 {
            let c = rng.in_box(Vec3::ZERO, Vec3::ONE);
            let s = 0.01 + 0.05 * rng.next_f32();
            for _ in 0..3 {
                positions.push(c + rng.unit_vector() * s);
            }
            indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        let mesh = TriangleMesh::new(positions, indices);
        let rays: Vec<Ray> = (0..1500)
            .map(|i| {
                let o = Vec3::splat(0.5) + rng.unit_vector() * 1.5;
                let d = rng.in_box(Vec3::ZERO, Vec3::ONE) - o;
                if i % 5 == 0 {
                    Ray::segment(o, d, 0.2, rng.range_f32(0.3, 1.2))
                } else {
                    Ray::new(o, d)
                }
            })
            .collect();
        let mut hits = 0;
        for leaf in [1, 16] {
            let opts = BuildOptions {
                max_leaf_size: leaf,
                packed_leaf_size: leaf,
                ..Default::default()
            };
            for path in BoxPath::available() {
                let bvh = WideBvh::<N, Moller>::build(&mesh, &opts).with_path(path);
                for n in [
                    0,
                    1,
                    2,
                    3,
                    5,
                    WALKS - 1,
                    WALKS,
                    WALKS + 1,
                    2 * WALKS + 3,
                    1500,
                ] {
                    let rs = &rays[..n];
                    let mut got = vec![None; n];
                    let mut occ = vec![false; n];
                    let mut seen = vec![0; n];
                    bvh.interleaved::<false>(rs, |i, _, best| {
                        got[i] = best;
                        seen[i] += 1;
                    });
                    bvh.interleaved::<true>(rs, |i, any, _| {
                        occ[i] = any;
                        seen[i] += 1;
                    });
                    assert!(seen.iter().all(|&s| s == 2), "{path:?}, {n} rays");
                    for (i, ray) in rs.iter().enumerate() {
                        let one = bvh.intersect(ray);
                        assert_eq!(bits(got[i]), bits(one), "{path:?}, ray {i} of {n}");
                        assert_eq!(occ[i], bvh.occluded(ray), "{path:?}, ray {i} of {n}");
                        hits += one.is_some() as usize;
                    }
                }
            }
        }
        hits
    }
}
