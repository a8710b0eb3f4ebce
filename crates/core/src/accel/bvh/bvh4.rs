//! 4-wide BVH with SIMD box tests and ordered stack traversal.

use super::box4::RayBox4;
use super::build::BuildOptions;
use super::enter::enter;
use super::node4::Node4;
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

/// Traversal stack entries for any tree: each wide node visited pushes at
/// most three.
pub(super) const STACK: usize = 3 * MAX_DEPTH + 1;

/// The stack of trees that need no more (most do; a smaller stack is cheaper
/// to set up per ray).
pub(super) const SMALL_STACK: usize = 64;

/// 4-wide BVH in the style of Embree's (Wald et al. 2014), made by collapsing
/// the binned-SAH binary tree of [`super::build`]: each wide node takes up to
/// four children, pulling up the grandchildren of its largest-area inner child
/// first, and the leaves are the binary tree's (same triangle ranges).
///
/// A node holds its children's boxes in structure-of-arrays layout, padded
/// exactly as [`super::Bvh2`]'s so that box culling never disagrees with the
/// triangle test, and one ray is tested against all four at once with SSE
/// (scalar elsewhere). Traversal visits the entered children near to far:
/// the nearest next, the others pushed with their entry distances on a
/// fixed-size stack (farthest deepest) and skipped on pop when a nearer hit
/// has been found since. Occlusion queries do not sort and stop at the first
/// hit.
///
/// Over [`Moller`] the leaves are packs of four triangles tested at once
/// with SSE, as Embree's `triangle4` (Wald et al. 2014; see
/// [`super::tri4`]), with the scalar test's answers bit for bit; the other
/// tests keep one triangle at a time.
pub struct Bvh4<T: TriangleTest> {
    pub(super) nodes: Vec<Node4>,
    pub(super) root_box: NodeBox,
    pub(super) root: Child4,
    pub(super) leaves: Leaves<T>,
    pub(super) stats: AccelStats,
    /// Whether traversal fits in [`SMALL_STACK`] entries.
    pub(super) small_stack: bool,
    /// The SAH measure of the tree as built or loaded (see
    /// `refit::stored_sah`), taken at the first refit or save.
    pub(super) built_sah: Option<f64>,
}

impl<T: TriangleTest> Bvh4<T> {
    /// Build over all triangles of `mesh`.
    pub fn build(mesh: &TriangleMesh, options: &BuildOptions) -> Self {
        let wide = build_wide::<Node4, T>(mesh, options);
        // The traversal writes its stack unchecked (see `traverse_with`).
        assert!(wide.stack < STACK, "tree too deep for the traversal stack");
        Bvh4 {
            nodes: wide.nodes,
            root_box: wide.root_box,
            root: wide.root,
            leaves: wide.leaves,
            stats: wide.stats,
            small_stack: wide.stack <= SMALL_STACK,
            built_sah: None,
        }
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
        match &self.leaves {
            Leaves::Packed(packs) => {
                let leaf = PackedLeaf {
                    packs,
                    ray,
                    r4: Ray4::new(ray),
                };
                self.walk::<ANY>(start, ray, leaf, tfar, best)
            }
            Leaves::Single(tris) => {
                let leaf = SingleLeaf {
                    tris,
                    ray,
                    rd: T::prepare(ray),
                };
                self.walk::<ANY>(start, ray, leaf, tfar, best)
            }
        }
    }

    #[inline(always)]
    fn walk<const ANY: bool>(
        &self,
        start: Child4,
        ray: &Ray,
        leaf: impl LeafTest,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        if self.small_stack {
            self.traverse_with::<ANY, SMALL_STACK>(start, ray, leaf, tfar, best)
        } else {
            self.traverse_with::<ANY, STACK>(start, ray, leaf, tfar, best)
        }
    }

    /// Traversal of the subtree `start` with an `N`-entry stack, enough for
    /// this tree (a subtree needs no more than the whole tree); `leaf` tests
    /// a leaf's triangles (`first`, `count`, the current `tfar` and nearest
    /// hit) and returns true for an any-hit query's hit. `tfar` and `best`
    /// are read at the start and written back at the end; the loop works on
    /// local copies.
    #[inline(always)]
    fn traverse_with<const ANY: bool, const N: usize>(
        &self,
        start: Child4,
        ray: &Ray,
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
        let rb = RayBox4::new(ray);
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
                let h = node.boxes.entries(&rb, ray.tnear, tfar);
                // SAFETY: the stack bound of `build`, as for `st` above.
                let next = unsafe {
                    enter::<ANY, _>(
                        &self.nodes,
                        &node.child,
                        &h.t,
                        h.mask,
                        st,
                        &mut sp,
                        &leaf,
                        false,
                    )
                };
                if let Some(next) = next {
                    cur = next;
                    continue;
                }
            }
            // Pop, skipping entries that lie beyond the nearest hit found
            // since they were pushed.
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

impl<T: TriangleTest> Accel for Bvh4<T> {
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
        let mut accepted = Vec::with_capacity(4);
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
            // Push in reverse so that slot 0 is visited first.
            stack.extend(accepted.iter().rev());
        }
    }

    fn stats(&self) -> AccelStats {
        self.stats.clone()
    }

    /// [`Bvh4::save`].
    fn save(
        &self,
        path: &std::path::Path,
        mesh: &TriangleMesh,
    ) -> Result<(), crate::accel::PersistError> {
        Bvh4::save(self, path, mesh)
    }

    /// [`Bvh4::refit`].
    fn refit(
        &mut self,
        mesh: &TriangleMesh,
    ) -> Result<crate::accel::RefitReport, crate::accel::RefitError> {
        Bvh4::refit(self, mesh)
    }

    /// Coherent packets over Möller, sixteen rays with AVX-512, else eight
    /// (see `bvh/packet/`), single rays otherwise.
    fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        super::packet::intersect_batch(self, rays, hits);
    }

    /// As [`Accel::intersect_batch`], for occlusion.
    fn occluded_batch(&self, rays: &[Ray], occluded: &mut [bool]) {
        super::packet::occluded_batch(self, rays, occluded);
    }
}

/// The coherent packet path (Wald et al. 2001, Benthin et al. 2012):
/// `bvh/packet/`, handing over to its 4-wide single-ray subtree traversal.
impl<T: TriangleTest> super::packet::PacketTree for Bvh4<T> {
    type Node = Node4;

    fn packet_view(&self) -> Option<super::packet::View<'_, Node4>> {
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
        _view: &super::packet::View<'_, Node4>,
        start: Child4,
        ray: &Ray,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        self.subtree::<ANY>(start, ray, tfar, best)
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn traverse_packet<
        const ANY: bool,
        const L: usize,
        W: super::packet::kernel::Width<L>,
    >(
        &self,
        view: &super::packet::View<'_, Node4>,
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
    use crate::tri::Moller;
    use glam::Vec3;

    /// Triangles shrinking geometrically towards the origin: the SAH peels
    /// them off one at a time, so the tree is a deep chain whose traversal
    /// needs more than the small stack.
    #[test]
    fn deep_chain_uses_the_large_stack_and_agrees_with_brute_force() {
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for i in 0..100u32 {
            let s = 0.7f32.powi(i as i32);
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
        let wide = Bvh4::<Moller>::build(&mesh, &opts);
        let brute = BruteForce::<Moller>::new(&mesh);
        assert!(!wide.small_stack, "the chain should need the large stack");
        let mut rng = Pcg32::new(4);
        let mut hits = 0;
        for _ in 0..5000 {
            let target =
                rng.in_box(Vec3::ZERO, Vec3::splat(0.3)) * 0.7f32.powi(rng.below(40) as i32);
            let origin = target + rng.unit_vector() * 2.0;
            let ray = Ray::new(origin, target - origin);
            let (a, b) = (wide.intersect(&ray), brute.intersect(&ray));
            // Equal up to ties, as in tests/accel_agreement.rs.
            match (a, b) {
                (Some(x), Some(y)) => {
                    let tol = 1e-5 * x.t.abs().max(y.t.abs()).max(1e-6);
                    assert!((x.t - y.t).abs() <= tol, "{ray:?} {x:?} {y:?}");
                }
                (x, y) => assert_eq!(x.is_some(), y.is_some(), "{ray:?}"),
            }
            assert_eq!(wide.occluded(&ray), b.is_some(), "{ray:?}");
            hits += a.is_some() as usize;
        }
        assert!(hits > 100, "{hits}");
    }
}
