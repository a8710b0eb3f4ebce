//! 8-wide BVH with AVX box tests and ordered stack traversal.

use super::box8::{BoxPath, RayBox8};
use super::build::BuildOptions;
use super::enter::enter;
use super::node8::Node8;
use super::stack::Stack;
use super::tri4::Ray4;
use super::wide_leaf::{LeafTest, Leaves, PackedLeaf, SingleLeaf};
use super::wide_node::Child4;
use super::wide_tree::build_wide;
use super::MAX_DEPTH;
use crate::aabb::Aabb;
use crate::accel::node_box::NodeBox;
use crate::accel::{Accel, AccelStats};
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::TriangleTest;

/// Traversal stack entries for any tree: each 8-wide node visited pushes at
/// most seven.
pub(super) const STACK: usize = 7 * MAX_DEPTH + 1;

mod walk;

/// The stack of trees that need no more (most do).
pub(super) const SMALL_STACK: usize = 64;

/// 8-wide BVH as Embree uses on AVX machines for single rays (Wald et al. 2014,
/// "Embree: a kernel framework for efficient CPU ray tracing"), made by
/// collapsing the binned-SAH binary tree of [`super::build`] into nodes of up
/// to eight children (the largest-area inner child's children pulled up first),
/// the leaves being the binary tree's.
///
/// A node holds its children's boxes in structure-of-arrays layout, padded
/// exactly as [`super::Bvh2`]'s, and one ray is tested against all eight at
/// once: with AVX where the CPU has AVX2 and FMA (detected once, at build;
/// the whole traversal is then compiled for them), else with two SSE halves
/// or a scalar loop ([`super::box8`]). Traversal is [`super::Bvh4`]'s:
/// entered children near to far, the nearest next, the others pushed with
/// their entry distances and skipped on pop when a nearer hit has been
/// found; occlusion queries stop at the first hit without sorting. Over
/// [`Moller`] the leaves are packs of four triangles tested with SSE
/// ([`super::tri4`], Embree's `triangle4`).
pub struct Bvh8<T: TriangleTest> {
    pub(super) nodes: Vec<Node8>,
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

impl<T: TriangleTest> Bvh8<T> {
    /// Build over all triangles of `mesh`.
    pub fn build(mesh: &TriangleMesh, options: &BuildOptions) -> Self {
        let wide = build_wide::<Node8, T>(mesh, options);
        // The traversal writes its stack unchecked (see `traverse_with`).
        assert!(wide.stack < STACK, "tree too deep for the traversal stack");
        Bvh8 {
            nodes: wide.nodes,
            root_box: wide.root_box,
            root: wide.root,
            leaves: wide.leaves,
            stats: wide.stats,
            small_stack: wide.stack <= SMALL_STACK,
            built_sah: None,
            path: BoxPath::detect(),
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
        match self.path {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `path` is Avx2 only where `BoxPath::detect` found AVX2
            // and FMA on this CPU (`with_path` checks the same).
            BoxPath::Avx2 => unsafe { self.traverse_avx2::<ANY>(start, ray, tfar, best) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `path` is Avx512 only where `BoxPath::detect` found
            // every feature `traverse_avx512` is compiled for.
            BoxPath::Avx512 => unsafe { self.traverse_avx512::<ANY>(start, ray, tfar, best) },
            path => self.traverse_portable::<ANY>(start, ray, path, tfar, best),
        }
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
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        self.traverse_on::<ANY>(start, ray, path, tfar, best)
    }

    /// The traversal compiled for AVX-512 (F, VL, BW, DQ) besides AVX2 and
    /// FMA: the code and arithmetic of [`Bvh8::traverse_avx2`], with 32
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
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        self.traverse_on::<ANY>(start, ray, BoxPath::Avx512, tfar, best)
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
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        self.traverse_on::<ANY>(start, ray, BoxPath::Avx2, tfar, best)
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
            self.traverse_with::<ANY, STACK>(start, ray, path, leaf, tfar, best)
        }
    }

    /// Traversal of the subtree `start` with an `N`-entry stack, enough for
    /// this tree (a subtree needs no more than the whole tree). `tfar` and
    /// `best` are read at the start and written back at the end; the loop
    /// works on local copies.
    #[inline(always)]
    fn traverse_with<const ANY: bool, const N: usize>(
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
        let rb = RayBox8::new(ray);
        let mut stack = Stack::<N>::new();
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
                // SAFETY: inner references are made by `collapse` from the
                // index of a node it pushed, so they are in bounds.
                let node = unsafe { self.nodes.get_unchecked(cur.index as usize) };
                // SAFETY: `path` is a kernel this CPU runs (see `traverse`).
                let h = unsafe { node.boxes.entries(path, &rb, ray.tnear, tfar) };
                // SAFETY: the stack bound of `build` (the stack has its slack
                // beyond); AVX-512 where `path` says so (see `traverse`).
                let next = unsafe {
                    enter::<ANY, _>(
                        &self.nodes,
                        &node.child,
                        &h.t,
                        h.mask,
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

impl<T: TriangleTest> Accel for Bvh8<T> {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.traverse::<false>(ray).0
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.traverse::<true>(ray).1
    }

    /// Depth first, slot 0 first; a child's box is read from its parent
    /// node, the root's from `root_box`.
    fn visit_regions(&self, enter: &mut dyn FnMut(&Aabb) -> bool, leaf: &mut dyn FnMut(&[u32])) {
        let root = Aabb::new(self.root_box.min.into(), self.root_box.max.into());
        if self.stats.triangle_refs == 0 || !enter(&root) {
            return;
        }
        let mut stack = vec![self.root];
        let mut accepted = Vec::with_capacity(8);
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
            for (slot, &child) in node.child.iter().enumerate() {
                if child != Child4::EMPTY && enter(&node.boxes.get(slot)) {
                    accepted.push(child);
                }
            }
            stack.extend(accepted.iter().rev());
        }
    }

    fn stats(&self) -> AccelStats {
        self.stats.clone()
    }

    /// [`Bvh8::save`].
    fn save(
        &self,
        path: &std::path::Path,
        mesh: &TriangleMesh,
    ) -> Result<(), crate::accel::PersistError> {
        Bvh8::save(self, path, mesh)
    }

    /// [`Bvh8::refit`].
    fn refit(
        &mut self,
        mesh: &TriangleMesh,
    ) -> Result<crate::accel::RefitReport, crate::accel::RefitError> {
        Bvh8::refit(self, mesh)
    }

    /// Coherent packets over Möller, sixteen rays with AVX-512, else eight
    /// (Wald et al. 2001, with Benthin et al. 2012's hand-over to single rays; see
    /// `bvh/packet/`), single rays otherwise.
    fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        super::packet::intersect_batch(self, rays, hits);
    }

    /// As [`Accel::intersect_batch`], for occlusion.
    fn occluded_batch(&self, rays: &[Ray], occluded: &mut [bool]) {
        super::packet::occluded_batch(self, rays, occluded);
    }
}

/// The coherent packet path over 8-wide nodes (Wald et al. 2001, Benthin et al.
/// 2012): `bvh/packet/`, the same kernel as [`super::Bvh4`]'s, handing over
/// to this tree's own single-ray traversal.
impl<T: TriangleTest> super::packet::PacketTree for Bvh8<T> {
    type Node = Node8;

    fn packet_view(&self) -> Option<super::packet::View<'_, Node8>> {
        match &self.leaves {
            Leaves::Packed(packs) if self.stats.triangle_refs > 0 => Some(super::packet::View {
                nodes: &self.nodes,
                root: self.root,
                leaves: packs,
            }),
            _ => None,
        }
    }

    #[inline(always)]
    fn single_subtree<const ANY: bool>(
        &self,
        _view: &super::packet::View<'_, Node8>,
        start: Child4,
        ray: &Ray,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        self.subtree::<ANY>(start, ray, tfar, best)
    }

    /// Nearest hits: twelve rays stepped in turn (`WALKS` in `bvh8/walk.rs`).
    /// Occlusion: one ray after the other, the plain loop, which was 1.25–1.6× faster
    /// than two walks on shadow rays (full dragon and scatter, 1 thread),
    /// where interleaving made incoherent nearest-hit rays 1.2× faster.
    #[inline(always)]
    fn singles<const ANY: bool>(
        &self,
        rays: &[Ray],
        mut done: impl FnMut(usize, bool, Option<Hit>),
    ) {
        if ANY {
            for (i, ray) in rays.iter().enumerate() {
                done(i, self.occluded(ray), None);
            }
        } else {
            self.interleaved::<ANY>(rays, done);
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
        view: &super::packet::View<'_, Node8>,
        rays: &[Ray],
        p: &super::packet::kernel::Packet<L>,
        switch: u32,
        out: &mut super::packet::kernel::PacketHits<L>,
    ) {
        // SAFETY: the caller guarantees the width's features. `build`
        // checked that the tree's deepest stack is below `STACK`, and
        // `small_stack` says whether it fits `SMALL_STACK`. The small stack
        // where it fits: the kernel's frame with the large one is 48 KB,
        // whose pages were probed on every packet (44 instructions per
        // packet; BENCHMARKS.md).
        unsafe {
            if self.small_stack {
                W::traverse::<ANY, Self, SMALL_STACK>(self, view, rays, p, switch, out)
            } else {
                W::traverse::<ANY, Self, STACK>(self, view, rays, p, switch, out)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::BruteForce;
    use crate::rng::Pcg32;
    use crate::tri::{Moller, Plucker};
    use glam::Vec3;

    fn agree(a: Option<Hit>, b: Option<Hit>) -> bool {
        match (a, b) {
            (Some(x), Some(y)) => (x.t - y.t).abs() <= 1e-5 * x.t.abs().max(y.t.abs()).max(1e-6),
            (x, y) => x.is_some() == y.is_some(),
        }
    }

    /// Triangles shrinking geometrically towards the origin: a deep chain
    /// whose traversal needs the large stack; every box kernel gives the
    /// same answers, equal to brute force up to ties.
    #[test]
    fn deep_chain_every_kernel_agrees_with_brute_force() {
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for i in 0..200u32 {
            let s = 0.8f32.powi(i as i32);
            positions.extend([
                Vec3::new(s, 0.0, 0.0),
                Vec3::new(s * 1.1, s, 0.0),
                Vec3::new(s, 0.0, s),
            ]);
            indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        let mesh = TriangleMesh::new(positions, indices);
        let opts = BuildOptions {
            max_leaf_size: 1,
            packed_leaf_size: 1,
            ..Default::default()
        };
        let brute = BruteForce::<Moller>::new(&mesh);
        let paths = BoxPath::available();
        let trees: Vec<Bvh8<Moller>> = paths
            .iter()
            .map(|&p| Bvh8::<Moller>::build(&mesh, &opts).with_path(p))
            .collect();
        assert!(
            !trees[0].small_stack,
            "the chain should need the large stack"
        );
        let mut rng = Pcg32::new(8);
        let mut hits = 0;
        for _ in 0..5000 {
            let target =
                rng.in_box(Vec3::ZERO, Vec3::splat(0.3)) * 0.8f32.powi(rng.below(60) as i32);
            let origin = target + rng.unit_vector() * 2.0;
            let ray = Ray::new(origin, target - origin);
            let want = brute.intersect(&ray);
            let first = trees[0].intersect(&ray);
            assert!(agree(first, want), "{ray:?} {first:?} {want:?}");
            for t in &trees {
                let got = t.intersect(&ray);
                assert_eq!(
                    got.map(|h| (h.t.to_bits(), h.prim)),
                    first.map(|h| (h.t.to_bits(), h.prim)),
                    "{:?} {ray:?}",
                    t.path
                );
                assert_eq!(t.occluded(&ray), want.is_some(), "{ray:?}");
            }
            hits += want.is_some() as usize;
        }
        assert!(hits > 100, "{hits}");
    }

    /// A random soup, packed (Möller) and single-triangle (Plücker) leaves,
    /// every kernel: the same answers as brute force up to ties, and the
    /// kernels bit-identical to each other.
    #[test]
    fn random_soup_every_kernel_and_leaf_kind_agrees_with_brute_force() {
        let mut rng = Pcg32::new(81);
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for i in 0..3000u32 {
            let c = rng.in_box(Vec3::ZERO, Vec3::ONE);
            let size = 0.002 + 0.08 * rng.next_f32().powi(3);
            for _ in 0..3 {
                positions.push(c + rng.unit_vector() * size);
            }
            indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        let mesh = TriangleMesh::new(positions, indices);
        let opts = BuildOptions::default();
        let brute = BruteForce::<Moller>::new(&mesh);
        let brute_p = BruteForce::<Plucker>::new(&mesh);
        let paths = BoxPath::available();
        let moller: Vec<Bvh8<Moller>> = paths
            .iter()
            .map(|&p| Bvh8::<Moller>::build(&mesh, &opts).with_path(p))
            .collect();
        let plucker: Vec<Bvh8<Plucker>> = paths
            .iter()
            .map(|&p| Bvh8::<Plucker>::build(&mesh, &opts).with_path(p))
            .collect();
        let mut hits = 0;
        for i in 0..20_000 {
            let target = rng.in_box(Vec3::ZERO, Vec3::ONE);
            let origin = if i % 3 == 0 {
                rng.in_box(Vec3::ZERO, Vec3::ONE)
            } else {
                Vec3::splat(0.5) + rng.unit_vector() * 2.0
            };
            let ray = if i % 5 == 0 {
                Ray::segment(origin, target - origin, 0.1 * rng.next_f32(), 0.5)
            } else {
                Ray::new(origin, target - origin)
            };
            let want = brute.intersect(&ray);
            let want_p = brute_p.intersect(&ray);
            hits += want.is_some() as usize;
            let m0 = moller[0].intersect(&ray);
            let p0 = plucker[0].intersect(&ray);
            assert!(agree(m0, want), "{ray:?} {m0:?} {want:?}");
            assert!(agree(p0, want_p), "{ray:?} {p0:?} {want_p:?}");
            for (m, p) in moller.iter().zip(&plucker) {
                assert_eq!(
                    m.intersect(&ray).map(|h| h.t.to_bits()),
                    m0.map(|h| h.t.to_bits())
                );
                assert_eq!(
                    p.intersect(&ray).map(|h| h.t.to_bits()),
                    p0.map(|h| h.t.to_bits())
                );
                assert_eq!(m.occluded(&ray), want.is_some(), "{ray:?}");
                assert_eq!(p.occluded(&ray), want_p.is_some(), "{ray:?}");
            }
        }
        assert!(hits > 2000, "{hits}");
    }
}
