//! Every crossing of a ray with the triangles of a wide BVH over Möller
//! triangles, not just the nearest: the walk behind hit counts, hit lists
//! and the crossing parity of the point queries.
//!
//! The walk is the single-ray traversal of `wide_bvh.rs` (the same box
//! kernels, compiled for the same CPUs) with a leaf test that hands every
//! crossing to a visitor instead of keeping the nearest. Each triangle is
//! classified by [`Moller::crossing`]: the textbook test's answer, and
//! whether exact arithmetic on the `f32` inputs agrees with it.

use super::walk::WALKS;
use super::{BoxPath, LeafTest, Leaves, WideBvh, LARGE_STACK, SMALL_STACK};
use crate::accel::bvh::node_width::NodeWidth;
use crate::accel::bvh::tri4::{Ray4, Tri4Leaves};
use crate::accel::leaf::LeafTriangles;
use crate::hit::Hit;
use crate::ray::Ray;
use crate::tri::moller::{Crossing, MollerTri};
use crate::tri::{Moller, TriangleTest};
use std::cell::RefCell;

/// What the crossing walk does with each crossing: `visit(crossing, prim,
/// reach)` with `prim` the mesh triangle; it may lower `reach` (boxes
/// entered beyond it are then skipped) and returns false to stop the walk.
/// A visitor can be a closure or a state read after the walk.
pub(crate) trait CrossingVisitor {
    fn visit(&mut self, c: &Crossing, prim: u32, reach: &mut f32) -> bool;
}

impl<F: FnMut(&Crossing, u32, &mut f32) -> bool> CrossingVisitor for F {
    #[inline(always)]
    fn visit(&mut self, c: &Crossing, prim: u32, reach: &mut f32) -> bool {
        self(c, prim, reach)
    }
}

/// Where a leaf's Möller triangles are: packs of four or one by one.
#[derive(Clone, Copy)]
enum Source<'a> {
    Packed(&'a Tri4Leaves),
    Single(&'a LeafTriangles<Moller>),
}

/// The leaf test of the crossing walk: every triangle the ray may cross
/// goes to the visitor, classified by [`Moller::crossing`] (`SURE`: with
/// its certainty; otherwise `sure` is left true, for the walks that need
/// only the textbook answer).
struct CrossingLeaf<'a, V, const SURE: bool> {
    source: Source<'a>,
    ray: &'a Ray,
    r4: Ray4,
    scale: f32,
    visitor: RefCell<V>,
}

impl<V: CrossingVisitor, const SURE: bool> CrossingLeaf<'_, V, SURE> {
    #[inline(always)]
    fn one(&self, tri: &MollerTri, prim: u32, tfar: &mut f32) -> bool {
        match Moller::crossing::<SURE>(tri, self.ray, self.scale, *tfar) {
            Some(c) => self.visitor.borrow_mut().visit(&c, prim, tfar),
            None => true,
        }
    }
}

impl<V: CrossingVisitor, const SURE: bool> LeafTest for CrossingLeaf<'_, V, SURE> {
    /// The walk tests every pack of the leaves it enters, in either order.
    const EVERY_PACK: bool = true;

    /// Every pack of the leaf, as the nearest-hit leaves fetch them.
    #[inline(always)]
    fn prefetch(&self, first: usize, count: usize) {
        if let Source::Packed(packs) = self.source {
            for k in 0..count.div_ceil(4) {
                crate::accel::bvh::prefetch::prefetch_pack(packs.packs(), first + k);
            }
        }
    }

    /// True (stop) when the visitor says so.
    #[inline(always)]
    fn test<const ANY: bool>(
        &self,
        first: usize,
        count: usize,
        tfar: &mut f32,
        _best: &mut Option<Hit>,
    ) -> bool {
        match self.source {
            Source::Packed(packs) => {
                let packs = &packs.packs()[first..first + count.div_ceil(4)];
                let mut left = count;
                for p in packs {
                    let lanes = if left >= 4 { 0xf } else { (1u32 << left) - 1 };
                    left = left.saturating_sub(4);
                    // Most lanes are dismissed four at a time; the rest
                    // are classified one by one.
                    let mut live = p.crossing_candidates::<SURE>(&self.r4, lanes);
                    while live != 0 {
                        let lane = live.trailing_zeros() as usize;
                        live &= live - 1;
                        if !self.one(&p.get(lane), p.prim[lane], tfar) {
                            return true;
                        }
                    }
                }
            }
            Source::Single(tris) => {
                for i in first..first + count {
                    if !self.one(tris.tri(i), tris.prim(i), tfar) {
                        return true;
                    }
                }
            }
        }
        false
    }
}

impl<N: NodeWidth> WideBvh<N, Moller> {
    fn source(&self) -> Source<'_> {
        match &self.leaves {
            Leaves::Packed(p) => Source::Packed(p),
            Leaves::Single(t) => Source::Single(t),
        }
    }

    fn crossing_leaf<'a, V, const SURE: bool>(
        &'a self,
        ray: &'a Ray,
        visitor: V,
    ) -> CrossingLeaf<'a, V, SURE> {
        CrossingLeaf {
            source: self.source(),
            ray,
            r4: Ray4::new(ray),
            scale: Moller::prepare(ray),
            visitor: RefCell::new(visitor),
        }
    }

    /// Walk every triangle `ray` may cross over `[ray.tnear, reach]`,
    /// handing each to `visitor` (see [`CrossingVisitor`]; `reach` starts
    /// at `ray.tfar`); returns the visitor. `NEAR_FIRST` walks as nearest
    /// hits do (children nearest first), for visitors that lower the
    /// reach; otherwise as occlusion rays do (children unsorted), cheaper.
    /// Either way every pack of an entered leaf is fetched, since every
    /// one is tested. `SURE` classifies each crossing's certainty. A ray
    /// that is not valid crosses nothing.
    pub(crate) fn crossings<const NEAR_FIRST: bool, const SURE: bool, V: CrossingVisitor>(
        &self,
        ray: &Ray,
        visitor: V,
    ) -> V {
        if self.stats.triangle_refs == 0 || !ray.is_valid() {
            return visitor;
        }
        let leaf = self.crossing_leaf::<V, SURE>(ray, visitor);
        let leaf = match self.path {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `path` is Avx2 only where `BoxPath::detect` found AVX2
            // and FMA on this CPU.
            BoxPath::Avx2 => unsafe { self.crossings_avx2::<NEAR_FIRST, _>(ray, leaf) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `path` is Avx512 only where `BoxPath::detect` found
            // every feature `crossings_avx512` is compiled for.
            BoxPath::Avx512 => unsafe { self.crossings_avx512::<NEAR_FIRST, _>(ray, leaf) },
            path => self.crossings_on::<NEAR_FIRST, _>(ray, path, leaf),
        };
        leaf.visitor.into_inner()
    }

    /// [`WideBvh::crossings`] compiled for AVX-512, as `traverse_avx512`.
    ///
    /// # Safety
    /// The CPU must support every feature named (`BoxPath::Avx512`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,avx512f,avx512vl,avx512bw,avx512dq,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn crossings_avx512<const NEAR_FIRST: bool, L: LeafTest>(
        &self,
        ray: &Ray,
        leaf: L,
    ) -> L {
        self.crossings_on::<NEAR_FIRST, L>(ray, BoxPath::Avx512, leaf)
    }

    /// [`WideBvh::crossings`] compiled for AVX2 and FMA, as `traverse_avx2`.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn crossings_avx2<const NEAR_FIRST: bool, L: LeafTest>(&self, ray: &Ray, leaf: L) -> L {
        self.crossings_on::<NEAR_FIRST, L>(ray, BoxPath::Avx2, leaf)
    }

    #[inline(always)]
    fn crossings_on<const NEAR_FIRST: bool, L: LeafTest>(
        &self,
        ray: &Ray,
        path: BoxPath,
        leaf: L,
    ) -> L {
        let (mut tfar, mut best) = (ray.traversal_tfar(), None);
        // The any-hit walk pushes the entered children unsorted; the leaf
        // test never reports an any-hit, so it walks on to the end.
        if NEAR_FIRST {
            self.walk::<false>(self.root, ray, path, &leaf, &mut tfar, &mut best);
        } else {
            self.walk::<true>(self.root, ray, path, &leaf, &mut tfar, &mut best);
        }
        leaf
    }

    /// [`WideBvh::crossings`] for each of `rays`, [`WALKS`] rays stepped in
    /// turn (`walk.rs`) in the occlusion walk's order (children unsorted:
    /// the visitors of a batch never lower the reach, so sorting would only
    /// cost), every pack of an entered leaf fetched: `visitor(ray)` makes
    /// each ray's visitor and `done(i, visitor)` receives ray `i`'s when
    /// its walk ends (to read or take its state).
    pub(crate) fn crossings_batch<const SURE: bool, V: CrossingVisitor>(
        &self,
        rays: &[Ray],
        visitor: impl Fn(&Ray) -> V,
        done: impl FnMut(usize, &mut V),
    ) {
        match self.path {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as in `crossings`.
            BoxPath::Avx2 => unsafe { self.crossings_batch_avx2::<SURE, V>(rays, visitor, done) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as in `crossings`.
            BoxPath::Avx512 => unsafe {
                self.crossings_batch_avx512::<SURE, V>(rays, visitor, done)
            },
            path => self.crossings_batch_on::<SURE, V>(rays, path, visitor, done),
        }
    }

    /// # Safety
    /// The CPU must support every feature named (`BoxPath::Avx512`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,avx512f,avx512vl,avx512bw,avx512dq,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn crossings_batch_avx512<const SURE: bool, V: CrossingVisitor>(
        &self,
        rays: &[Ray],
        visitor: impl Fn(&Ray) -> V,
        done: impl FnMut(usize, &mut V),
    ) {
        self.crossings_batch_on::<SURE, V>(rays, BoxPath::Avx512, visitor, done)
    }

    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn crossings_batch_avx2<const SURE: bool, V: CrossingVisitor>(
        &self,
        rays: &[Ray],
        visitor: impl Fn(&Ray) -> V,
        done: impl FnMut(usize, &mut V),
    ) {
        self.crossings_batch_on::<SURE, V>(rays, BoxPath::Avx2, visitor, done)
    }

    #[inline(always)]
    fn crossings_batch_on<'a, const SURE: bool, V: CrossingVisitor>(
        &'a self,
        rays: &'a [Ray],
        path: BoxPath,
        visitor: impl Fn(&Ray) -> V,
        mut done: impl FnMut(usize, &mut V),
    ) {
        if self.stats.triangle_refs == 0 || rays.len() < WALKS {
            for (i, ray) in rays.iter().enumerate() {
                let mut v = self.crossings::<false, SURE, V>(ray, visitor(ray));
                done(i, &mut v);
            }
            return;
        }
        // An invalid ray walks nothing: its tfar is NaN (`traversal_tfar`),
        // which every box test rejects.
        let leaf = |ray: &'a Ray| self.crossing_leaf::<V, SURE>(ray, visitor(ray));
        let done =
            |i, _, _, leaf: &CrossingLeaf<'_, V, SURE>| done(i, &mut leaf.visitor.borrow_mut());
        if self.small_stack {
            self.group::<true, SMALL_STACK, _>(rays, path, leaf, done)
        } else {
            self.group::<true, LARGE_STACK, _>(rays, path, leaf, done)
        }
    }
}
