//! The wide BVH, written once for every node width: [`Bvh4`] and [`Bvh8`]
//! are its instances over [`Node4`] and [`Node8`], as Embree writes its
//! BVHN once and instantiates it per width (Wald et al. 2014).

use super::box_path::BoxPath;
use super::build::BuildOptions;
use super::enter::enter;
use super::node4::Node4;
use super::node8::Node8;
use super::node_width::{NodeWidth, SlotEntries, LARGE_STACK, SMALL_STACK};
use super::packet::{PacketTree, View};
use super::ray_box::RayBox;
use super::stack::Stack;
use super::tri4::Ray4;
use super::wide_leaf::{LeafTest, Leaves, PackedLeaf, SingleLeaf};
use super::wide_node::{Child4, WideSlots};
use super::wide_parts::{PartsMut, PartsOwned, PartsRef, WideParts};
use super::wide_tree::build_wide;
use crate::aabb::Aabb;
use crate::accel::node_box::NodeBox;
use crate::accel::{Accel, AccelKind, AccelStats};
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::TriangleTest;

mod crossings;
pub(crate) use crossings::CrossingVisitor;
#[cfg(test)]
mod tests;
mod walk;

/// A wide BVH in the style of Embree's (Wald et al. 2014): inner nodes of
/// `N::WIDTH` children whose boxes lie in structure-of-arrays layout and
/// are tested against one ray all at once, built by the binned SAH making
/// wide nodes directly or by collapsing the linear BVH's binary tree
/// (`wide_tree.rs`).
///
/// Each box holds the tolerance band of every triangle below it, the band
/// in which the triangle tests also report hits, so that box culling never
/// disagrees with the triangle test; it is the union of its triangles'
/// bands (`fit.rs`), tighter than [`super::Bvh2`]'s boxes padded by their
/// own extent. The box kernel is chosen once, at build, from the CPU's
/// features (AVX-512, AVX2, SSE, scalar; `box_path.rs`), and the whole
/// traversal is compiled for it. Traversal visits the entered
/// children near to far: the nearest next, the others pushed with their
/// entry distances on a fixed-size stack (farthest deepest) and skipped on
/// pop when a nearer hit has been found since. Occlusion queries do not
/// sort and stop at the first hit.
///
/// Over [`crate::tri::Moller`] the leaves are packs of four triangles
/// tested at once with SSE (Embree's `triangle4`, `tri4/`), with the scalar
/// test's answers bit for bit, and batches of coherent rays take the packet
/// path (Wald et al. 2001; Benthin et al. 2012); the other tests keep one
/// triangle at a time.
pub struct WideBvh<N, T: TriangleTest> {
    pub(super) nodes: Vec<N>,
    pub(super) root_box: NodeBox,
    pub(super) root: Child4,
    pub(super) leaves: Leaves<T>,
    pub(super) stats: AccelStats,
    /// Whether traversal fits in [`SMALL_STACK`] entries.
    pub(super) small_stack: bool,
    /// The box kernel, detected at build.
    pub(super) path: BoxPath,
    /// The SAH measure of the tree as built or loaded (see
    /// `refit::stored_sah`), taken at the first refit or save.
    pub(super) built_sah: Option<f64>,
}

/// What the single-ray traversals compiled for one CPU take and give
/// back: the ray's reach `t` and its nearest hit so far (`prim`
/// [`Reach::NONE`] for none). Sixteen bytes, so that it travels in
/// registers across the call; the hit as an `Option<Hit>` went through
/// memory, and reading it back stalled each call on the stores just made
/// (a quarter of a missing ray's time, perf).
#[derive(Clone, Copy)]
pub(super) struct Reach {
    t: f32,
    u: f32,
    v: f32,
    prim: u32,
}

impl Reach {
    /// The `prim` of no hit (never a triangle: meshes hold fewer).
    const NONE: u32 = u32::MAX;

    /// From the ray's reach and nearest hit so far, whose distance it is
    /// when there is one.
    #[inline(always)]
    fn new(tfar: f32, best: Option<Hit>) -> Self {
        debug_assert!(best.is_none_or(|h| h.t == tfar || tfar.is_nan()));
        match best {
            Some(h) => Reach {
                t: tfar,
                ..Reach::from(h)
            },
            None => Reach {
                t: tfar,
                u: 0.0,
                v: 0.0,
                prim: Reach::NONE,
            },
        }
    }

    /// The nearest hit, `t` being its distance.
    #[inline(always)]
    fn hit(self) -> Option<Hit> {
        (self.prim != Reach::NONE).then_some(Hit {
            t: self.t,
            u: self.u,
            v: self.v,
            prim: self.prim,
        })
    }
}

impl From<Hit> for Reach {
    #[inline(always)]
    fn from(h: Hit) -> Self {
        Reach {
            t: h.t,
            u: h.u,
            v: h.v,
            prim: h.prim,
        }
    }
}

/// The 4-wide BVH: four box tests at once with SSE.
pub type Bvh4<T> = WideBvh<Node4, T>;

/// The 8-wide BVH, as Embree uses on AVX machines for single rays: eight
/// box tests at once with AVX where the CPU has AVX2 and FMA, else two SSE
/// halves or a scalar loop.
pub type Bvh8<T> = WideBvh<Node8, T>;

impl<N: NodeWidth, T: TriangleTest> WideBvh<N, T> {
    /// Build over all triangles of `mesh`.
    ///
    /// # Panics
    /// When a triangle refers to a vertex the mesh does not have
    /// ([`TriangleMesh::assert_indices_in_range`]).
    pub fn build(mesh: &TriangleMesh, options: &BuildOptions) -> Self {
        Self::build_leaving_out(mesh, options, true)
    }

    /// [`WideBvh::build`] with every triangle in the leaves, those no ray
    /// can hit too: for the walk to every crossing
    /// ([`WideBvh::crossings`]), whose exact test of the crossings near an
    /// edge works on the corners, not on the stored edges.
    pub(crate) fn build_keeping_all(mesh: &TriangleMesh, options: &BuildOptions) -> Self {
        Self::build_leaving_out(mesh, options, false)
    }

    fn build_leaving_out(mesh: &TriangleMesh, options: &BuildOptions, leave_out: bool) -> Self {
        mesh.assert_indices_in_range();
        let wide = build_wide::<N, T>(mesh, options, leave_out);
        // The traversal writes its stack unchecked (see `traverse_with`).
        assert!(
            wide.stack < N::STACK,
            "tree too deep for the traversal stack"
        );
        WideBvh {
            nodes: wide.nodes,
            root_box: wide.root_box,
            root: wide.root,
            leaves: wide.leaves,
            stats: wide.stats,
            small_stack: wide.stack <= SMALL_STACK,
            path: BoxPath::detect(),
            built_sah: None,
        }
    }

    /// Use the box kernel `path` instead of the detected one (for tests).
    #[cfg(test)]
    pub(crate) fn with_path(mut self, path: BoxPath) -> Self {
        assert!(BoxPath::available().contains(&path));
        self.path = path;
        self
    }

    #[inline(always)]
    fn traverse<const ANY: bool>(&self, ray: &Ray) -> (Option<Hit>, bool) {
        if self.stats.triangle_refs == 0 {
            return (None, false);
        }
        let (mut tfar, mut best) = (ray.traversal_tfar(), None);
        let any = self.subtree::<ANY>(self.root, ray, &mut tfar, &mut best);
        (best, any)
    }

    /// The single-ray traversal of the subtree `start`, from the ray's
    /// current `tfar` and nearest hit `best` (both updated): from the root
    /// for [`Accel::intersect`] and [`Accel::occluded`], from a packet's
    /// node for the hand-over of the packet path (Benthin et al.
    /// 2012). Returns true for an any-hit query's hit (`ANY`).
    #[inline(always)]
    fn subtree<const ANY: bool>(
        &self,
        start: Child4,
        ray: &Ray,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        let reach = Reach::new(*tfar, *best);
        let reach = match self.path {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `path` is Avx2 only where `BoxPath::detect` found AVX2
            // and FMA on this CPU (`with_path` checks the same).
            BoxPath::Avx2 => unsafe { self.traverse_avx2::<ANY>(start, ray, reach) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `path` is Avx512 only where `BoxPath::detect` found
            // every feature `traverse_avx512` is compiled for.
            BoxPath::Avx512 => unsafe { self.traverse_avx512::<ANY>(start, ray, reach) },
            path => self.traverse_portable::<ANY>(start, ray, path, reach),
        };
        *tfar = reach.t;
        if ANY {
            return reach.prim != Reach::NONE;
        }
        *best = reach.hit();
        false
    }

    /// The traversal for CPUs without AVX2 (and the scalar kernel in
    /// tests), kept out of line: inlined, it sat in the packet kernel's
    /// hand-over and made the kernel's code worse (1M terrain primaries
    /// took 5% fewer instructions with it out of line; BENCHMARKS.md).
    #[inline(never)]
    fn traverse_portable<const ANY: bool>(
        &self,
        start: Child4,
        ray: &Ray,
        path: BoxPath,
        reach: Reach,
    ) -> Reach {
        self.traverse_from::<ANY>(start, ray, path, reach)
    }

    /// The traversal compiled for AVX-512 (F, VL, BW, DQ) besides AVX2 and
    /// FMA: the code and arithmetic of [`WideBvh::traverse_avx2`], with 32
    /// vector registers and mask compares.
    ///
    /// # Safety
    /// The CPU must support every feature named (`BoxPath::Avx512`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,avx512f,avx512vl,avx512bw,avx512dq,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn traverse_avx512<const ANY: bool>(
        &self,
        start: Child4,
        ray: &Ray,
        reach: Reach,
    ) -> Reach {
        self.traverse_from::<ANY>(start, ray, BoxPath::Avx512, reach)
    }

    /// The traversal compiled for AVX2 and FMA, so that the AVX box kernel
    /// and everything around it inline into one loop.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn traverse_avx2<const ANY: bool>(
        &self,
        start: Child4,
        ray: &Ray,
        reach: Reach,
    ) -> Reach {
        self.traverse_from::<ANY>(start, ray, BoxPath::Avx2, reach)
    }

    /// The nearest hit of `ray` from the root, compiled for AVX2 and FMA.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn intersect_avx2(&self, ray: &Ray) -> Option<Hit> {
        self.root_walk::<false>(ray, BoxPath::Avx2).0
    }

    /// Whether `ray` hits anything, compiled for AVX2 and FMA.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn occluded_avx2(&self, ray: &Ray) -> bool {
        self.root_walk::<true>(ray, BoxPath::Avx2).1
    }

    /// The nearest hit of `ray` from the root, compiled as
    /// [`WideBvh::traverse_avx512`] is.
    ///
    /// # Safety
    /// The CPU must support every feature named (`BoxPath::Avx512`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,avx512f,avx512vl,avx512bw,avx512dq,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn intersect_avx512(&self, ray: &Ray) -> Option<Hit> {
        self.root_walk::<false>(ray, BoxPath::Avx512).0
    }

    /// Whether `ray` hits anything, compiled as
    /// [`WideBvh::traverse_avx512`] is.
    ///
    /// # Safety
    /// The CPU must support every feature named (`BoxPath::Avx512`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,avx512f,avx512vl,avx512bw,avx512dq,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn occluded_avx512(&self, ray: &Ray) -> bool {
        self.root_walk::<true>(ray, BoxPath::Avx512).1
    }

    /// [`WideBvh::traverse_on`] from the root with the ray's own reach,
    /// inlined into the entry point of its box kernel `path`.
    #[inline(always)]
    fn root_walk<const ANY: bool>(&self, ray: &Ray, path: BoxPath) -> (Option<Hit>, bool) {
        if self.stats.triangle_refs == 0 {
            return (None, false);
        }
        let (mut tfar, mut best) = (ray.traversal_tfar(), None);
        let any = self.traverse_on::<ANY>(self.root, ray, path, &mut tfar, &mut best);
        (best, any)
    }

    /// [`WideBvh::traverse_on`] from `reach` and back to it (an any-hit
    /// query's hit as a `prim` other than [`Reach::NONE`]).
    #[inline(always)]
    fn traverse_from<const ANY: bool>(
        &self,
        start: Child4,
        ray: &Ray,
        path: BoxPath,
        reach: Reach,
    ) -> Reach {
        let (mut tfar, mut best) = (reach.t, reach.hit());
        let any = self.traverse_on::<ANY>(start, ray, path, &mut tfar, &mut best);
        let mut out = Reach::new(tfar, if ANY { None } else { best });
        if any {
            out.prim = 0;
        }
        out
    }

    #[inline(always)]
    fn traverse_on<const ANY: bool>(
        &self,
        start: Child4,
        ray: &Ray,
        path: BoxPath,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        match &self.leaves {
            Leaves::Packed(packs) => {
                let leaf = PackedLeaf {
                    packs,
                    ray,
                    r4: Ray4::new(ray),
                };
                self.walk::<ANY>(start, ray, path, leaf, tfar, best)
            }
            Leaves::Single(tris) => {
                let leaf = SingleLeaf {
                    tris,
                    ray,
                    rd: T::prepare(ray),
                };
                self.walk::<ANY>(start, ray, path, leaf, tfar, best)
            }
        }
    }

    #[inline(always)]
    fn walk<const ANY: bool>(
        &self,
        start: Child4,
        ray: &Ray,
        path: BoxPath,
        leaf: impl LeafTest,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        if self.small_stack {
            self.traverse_with::<ANY, SMALL_STACK>(start, ray, path, leaf, tfar, best)
        } else {
            self.traverse_with::<ANY, LARGE_STACK>(start, ray, path, leaf, tfar, best)
        }
    }

    /// Traversal of the subtree `start` with an `S`-entry stack, enough for
    /// this tree (a subtree needs no more than the whole tree). `tfar` and
    /// `best` are read at the start and written back at the end; the loop
    /// works on local copies.
    #[inline(always)]
    fn traverse_with<const ANY: bool, const S: usize>(
        &self,
        start: Child4,
        ray: &Ray,
        path: BoxPath,
        leaf: impl LeafTest,
        tfar_io: &mut f32,
        best_io: &mut Option<Hit>,
    ) -> bool {
        let mut tfar = *tfar_io;
        let mut best: Option<Hit> = *best_io;
        // No separate test of the root's box: the root node's test of its
        // children's boxes culls the same rays (they lie inside it), and a
        // root leaf's triangle test is exact. It cost 4% of a ray's
        // instructions (callgrind).
        let rb = RayBox::new(ray);
        let mut stack = Stack::<S>::new();
        let st = stack.ptr();
        let mut sp = 0usize;
        let mut cur = start;
        loop {
            if cur.count > 0 {
                let (first, count) = (cur.index as usize, cur.count as usize);
                if leaf.test::<ANY>(first, count, &mut tfar, &mut best) {
                    *tfar_io = tfar;
                    return true;
                }
            } else {
                debug_assert!((cur.index as usize) < self.nodes.len());
                // SAFETY: inner references are made by the builds from the
                // index of a node they pushed, so they are in bounds.
                let node = unsafe { self.nodes.get_unchecked(cur.index as usize) };
                // SAFETY: `path` is a kernel this CPU runs (see `subtree`).
                let h = unsafe { node.entries(path, &rb, ray.tnear, tfar) };
                // SAFETY: the stack bound of `build` (the stack has its slack
                // beyond); AVX-512 where `path` says so (see `subtree`).
                let next = unsafe {
                    enter::<ANY, _>(
                        &self.nodes,
                        node.children(),
                        h.t(),
                        h.mask(),
                        st,
                        &mut sp,
                        &leaf,
                        path == BoxPath::Avx512,
                    )
                };
                if let Some(next) = next {
                    cur = next;
                    continue;
                }
            }
            // Pop, skipping entries beyond the nearest hit found since they
            // were pushed.
            loop {
                if sp == 0 {
                    *tfar_io = tfar;
                    *best_io = best;
                    return false;
                }
                sp -= 1;
                // SAFETY: entry `sp` is below the stack pointer, written by
                // a push.
                let (c, t) = unsafe { st.read(sp) };
                if t <= tfar {
                    cur = c;
                    break;
                }
            }
        }
    }
}

impl<N: NodeWidth, T: TriangleTest> Accel for WideBvh<N, T> {
    /// One ray from the root, through an entry point compiled for this
    /// CPU's box kernel that gives the answer back as it is; the packet
    /// path's hand-over goes through [`Reach`] instead.
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        match self.path {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `path` is Avx2 only where `BoxPath::detect` found AVX2
            // and FMA on this CPU (`with_path` checks the same).
            BoxPath::Avx2 => unsafe { self.intersect_avx2(ray) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `path` is Avx512 only where `BoxPath::detect` found
            // every feature `intersect_avx512` is compiled for.
            BoxPath::Avx512 => unsafe { self.intersect_avx512(ray) },
            _ => self.traverse::<false>(ray).0,
        }
    }

    /// As [`WideBvh::intersect`], for any hit.
    fn occluded(&self, ray: &Ray) -> bool {
        match self.path {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as in `intersect`.
            BoxPath::Avx2 => unsafe { self.occluded_avx2(ray) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as in `intersect`.
            BoxPath::Avx512 => unsafe { self.occluded_avx512(ray) },
            _ => self.traverse::<true>(ray).1,
        }
    }

    /// Depth first, slot 0 first; a child's box is read from its parent
    /// node, the root's from `root_box`. The triangles that packed leaves
    /// leave out ([`super::tri4::Unhittable`]) come last, as one more leaf
    /// below the root with their own bounds, which the root's region
    /// includes.
    fn visit_regions(&self, enter: &mut dyn FnMut(&Aabb) -> bool, leaf: &mut dyn FnMut(&[u32])) {
        let unhittable = match &self.leaves {
            Leaves::Packed(p) if !p.unhittable.prims.is_empty() => Some(&p.unhittable),
            _ => None,
        };
        let tree = self.stats.triangle_refs > 0;
        let mut root = if tree {
            Aabb::new(self.root_box.min.into(), self.root_box.max.into())
        } else {
            Aabb::EMPTY
        };
        if let Some(u) = unhittable {
            root = root.union(u.bounds);
        }
        if !(tree || unhittable.is_some()) || !enter(&root) {
            return;
        }
        if tree {
            self.visit_tree_regions(enter, leaf);
        }
        if let Some(u) = unhittable {
            if enter(&u.bounds) {
                leaf(&u.prims);
            }
        }
    }

    fn stats(&self) -> AccelStats {
        self.stats.clone()
    }

    /// [`WideBvh::save`], recording `scale`.
    fn save_at_scale(
        &self,
        path: &std::path::Path,
        mesh: &TriangleMesh,
        scale: crate::UnitScale,
    ) -> Result<(), crate::accel::PersistError> {
        WideBvh::save_scaled(self, path, mesh, scale)
    }

    /// [`WideBvh::refit`].
    fn refit(
        &mut self,
        mesh: &TriangleMesh,
    ) -> Result<crate::accel::RefitReport, crate::accel::RefitError> {
        WideBvh::refit(self, mesh)
    }

    /// Coherent packets over Möller, sixteen rays with AVX-512, else eight
    /// (Wald et al. 2001, with Benthin et al. 2012's hand-over to single
    /// rays; see `bvh/packet/`), single rays otherwise.
    fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        super::packet::intersect_batch(self, rays, hits);
    }

    /// As [`Accel::intersect_batch`], for occlusion.
    fn occluded_batch(&self, rays: &[Ray], occluded: &mut [bool]) {
        super::packet::occluded_batch(self, rays, occluded);
    }
}

/// The coherent packet path (Wald et al. 2001, Benthin et al. 2012):
/// `bvh/packet/`, one kernel for both widths, handing over to this tree's
/// own single-ray traversal.
impl<N: NodeWidth, T: TriangleTest> PacketTree for WideBvh<N, T> {
    type Node = N;

    fn packet_view(&self) -> Option<View<'_, N>> {
        match &self.leaves {
            Leaves::Packed(packs) if self.stats.triangle_refs > 0 => Some(View {
                nodes: &self.nodes,
                root: self.root,
                leaves: packs,
                extent: (0..3)
                    .map(|a| self.root_box.max[a] - self.root_box.min[a])
                    .fold(0.0, f32::max),
            }),
            _ => None,
        }
    }

    #[inline(always)]
    fn single_subtree<const ANY: bool>(
        &self,
        _view: &View<'_, N>,
        start: Child4,
        ray: &Ray,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        self.subtree::<ANY>(start, ray, tfar, best)
    }

    /// Nearest hits and occlusion on wide nodes that interleave
    /// ([`NodeWidth::INTERLEAVE`]): twelve rays stepped in turn (`WALKS` in
    /// `wide_bvh/walk.rs`), so that one ray's node loads overlap the
    /// others' work. These are the rays that formed no packet; on
    /// incoherent rays, occlusion ran 1.6–2.0× faster this way than one
    /// ray after the other (BENCHMARKS.md). Otherwise one ray after the
    /// other.
    #[inline(always)]
    fn singles<const ANY: bool>(
        &self,
        rays: &[Ray],
        mut done: impl FnMut(usize, bool, Option<Hit>),
    ) {
        if N::INTERLEAVE {
            self.interleaved::<ANY>(rays, done);
        } else if ANY {
            for (i, ray) in rays.iter().enumerate() {
                done(i, self.occluded(ray), None);
            }
        } else {
            for (i, ray) in rays.iter().enumerate() {
                done(i, false, self.intersect(ray));
            }
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn traverse_packet<
        const ANY: bool,
        const L: usize,
        W: super::packet::kernel::Width<L>,
    >(
        &self,
        view: &View<'_, N>,
        rays: &[Ray],
        p: &super::packet::kernel::Packet<L>,
        switch: u32,
        out: &mut super::packet::kernel::PacketHits<L>,
    ) {
        // SAFETY: the caller guarantees the width's features. `build`
        // checked that the tree's deepest stack is below `N::STACK`
        // (at most `LARGE_STACK`), and `small_stack` says whether it fits
        // `SMALL_STACK`. The small stack where it fits: the kernel's frame
        // with the large one is 48 KB, whose pages were probed on every
        // packet (44 instructions per packet; BENCHMARKS.md).
        unsafe {
            if self.small_stack {
                W::traverse::<ANY, Self, SMALL_STACK>(self, view, rays, p, switch, out)
            } else {
                W::traverse::<ANY, Self, LARGE_STACK>(self, view, rays, p, switch, out)
            }
        }
    }
}

/// Both widths through their parts, for the refit (`refit.rs`) and the
/// saved files (`persist.rs`).
impl<N: NodeWidth, T: TriangleTest> WideParts for WideBvh<N, T> {
    type Node = N;
    type Test = T;
    const KIND: AccelKind = N::KIND;
    const STACK: usize = N::STACK;
    fn parts(&self) -> PartsRef<'_, N, T> {
        PartsRef {
            nodes: &self.nodes,
            root_box: &self.root_box,
            root: self.root,
            leaves: &self.leaves,
            stats: &self.stats,
            built_sah: self.built_sah,
        }
    }
    fn parts_mut(&mut self) -> PartsMut<'_, N, T> {
        PartsMut {
            nodes: &mut self.nodes,
            root_box: &mut self.root_box,
            root: self.root,
            leaves: &mut self.leaves,
            stats: &mut self.stats,
            built_sah: &mut self.built_sah,
        }
    }
    fn from_parts(p: PartsOwned<N, T>) -> Self {
        assert!(p.stack < N::STACK, "tree too deep for the traversal stack");
        WideBvh {
            nodes: p.nodes,
            root_box: p.root_box,
            root: p.root,
            leaves: p.leaves,
            stats: p.stats,
            small_stack: p.stack <= SMALL_STACK,
            path: BoxPath::detect(),
            built_sah: p.built_sah,
        }
    }
}

impl<N: NodeWidth, T: TriangleTest> WideBvh<N, T> {
    /// [`Accel::visit_regions`] over the tree, its root's region accepted.
    fn visit_tree_regions(
        &self,
        enter: &mut dyn FnMut(&Aabb) -> bool,
        leaf: &mut dyn FnMut(&[u32]),
    ) {
        let mut stack = vec![self.root];
        let mut accepted = Vec::with_capacity(<N as WideSlots>::WIDTH);
        let mut prims = Vec::new();
        while let Some(cur) = stack.pop() {
            if cur.count > 0 {
                let (first, count) = (cur.index as usize, cur.count as usize);
                match &self.leaves {
                    Leaves::Single(tris) => leaf(tris.prims(first, count)),
                    Leaves::Packed(packs) => {
                        prims.clear();
                        packs.prims(cur, &mut prims);
                        leaf(&prims);
                    }
                }
                continue;
            }
            let node = &self.nodes[cur.index as usize];
            accepted.clear();
            for (slot, &child) in node.children().iter().enumerate() {
                if child != Child4::EMPTY && enter(&node.slot_box(slot)) {
                    accepted.push(child);
                }
            }
            // Push in reverse so that slot 0 is visited first.
            stack.extend(accepted.iter().rev());
        }
    }
}
