//! The direct wide build: the binned-SAH build making the wide
//! nodes of [`super::Bvh4`] and [`super::Bvh8`] as it goes, with no binary
//! tree in between, as Embree's wide builders do (Wald et al. 2014, "Embree:
//! a kernel framework for efficient CPU ray tracing").
//!
//! A wide node starts from the two halves of its own split and, while it has
//! free slots, splits the child of largest area that the binary build would
//! split; a split is planned ([`plan`], [`sweep_plan`]) when its node becomes a
//! child and carried out when the node is opened, so each binary split is
//! binned and partitioned once, as in [`super::build`]. The rules are
//! [`super::collapse`]'s, child order, node numbering and ties included, so the
//! result is, node for node and triangle for triangle, the binary build
//! collapsed; what goes is the binary tree's allocation, walk and release
//! (about 40 of the 1M-triangle terrain's 370 ms on one thread; with the
//! build's loops prefetching, the direct build is 3-4% faster than the binary
//! one collapsed). The splits of the largest nodes are carried out ahead, in
//! parallel ([`Build::open_early`]), with the same result.

use super::binning::{Bins, PrimRef, RangeInfo};
use super::build::sweep::sweep_plan;
use super::build::{order_of, plan, prim_refs, split_refs, BuildOptions, Plan};
use super::collapse::{to_open, Collapsed, PAR_DEPTH};
use super::wide_node::Child4;
use super::wide_node::WideSlots;
use rayon::prelude::*;

/// A child-to-be of a wide node: a range of the references, its bounds,
/// its depth in the binary tree and what the binary build does with it.
#[derive(Clone, Copy, Debug)]
struct Kid {
    /// First reference, in the whole build's order.
    first: usize,
    len: usize,
    info: RangeInfo,
    depth: usize,
    step: Step,
}

/// What the binary build does with a node.
#[derive(Clone, Copy, Debug)]
enum Step {
    /// Split (or not) as the SAH plans.
    Sah(Plan),
    /// Split as the SAH will plan when the node is opened: a node above the
    /// leaf bound, which [`plan`] never makes a leaf (nor `leaf_ok`). Its
    /// references are binned just before they are partitioned, while they
    /// are in the cache, as in the binary build.
    Later,
    /// Below a node marked `leaf_ok`: split by the sweep after `at`
    /// references (already sorted), or a leaf (`None`).
    Swept(Option<(usize, bool)>),
}

impl Kid {
    /// A leaf of the binary tree.
    fn is_leaf(&self) -> bool {
        matches!(self.step, Step::Sah(Plan::Leaf) | Step::Swept(None))
    }

    /// An inner node the SAH would rather keep as one leaf: opened while a
    /// wide node has free slots, else one leaf of its whole range.
    fn leaf_ok(&self) -> bool {
        matches!(
            self.step,
            Step::Sah(Plan::Binned { leaf_ok: true, .. }) | Step::Swept(Some((_, true)))
        )
    }

    /// The collapse's choice key: the area of an inner node, -1 for a leaf
    /// (never opened).
    fn area(&self) -> f32 {
        if self.is_leaf() {
            -1.0
        } else {
            self.info.bounds.aabb().surface_area()
        }
    }
}

/// The constants of one build.
struct Build<'o> {
    opts: &'o BuildOptions,
    root_area: f64,
    /// The halves of the kids opened ahead of the wide nodes
    /// ([`Build::open_early`]), by first reference and length.
    early: Vec<((usize, usize), [Kid; 2])>,
}

/// Kids of more references than this are opened ahead of the wide nodes,
/// the two halves of each in parallel (see [`Build::open_early`]).
const EARLY: usize = 64 * 1024;

impl Build<'_> {
    /// The kid over `refs` (at `first`), binned as the SAH build does.
    fn sah_kid(
        &self,
        refs: &[PrimRef],
        first: usize,
        info: RangeInfo,
        depth: usize,
        bins: &mut Bins,
    ) -> Kid {
        let step = if refs.len() > self.opts.max_leaf_size {
            Step::Later
        } else {
            Step::Sah(plan(refs, &info, depth, self.opts, bins))
        };
        Kid {
            first,
            len: refs.len(),
            info,
            depth,
            step,
        }
    }

    /// The kid over `refs` (at `first`) below a `leaf_ok` node: swept (its
    /// references sorted now, as [`super::build::sweep::sweep_node`] does on entry).
    fn swept_kid(&self, refs: &mut [PrimRef], first: usize, depth: usize) -> Kid {
        let info = RangeInfo::of(refs).clean();
        Kid {
            first,
            len: refs.len(),
            info,
            depth,
            step: Step::Swept(sweep_plan(refs, &info, self.opts)),
        }
    }

    /// Split `kids[i]` (not a leaf), whose references are `refs`: it is
    /// replaced by its left half and its right half is pushed, each
    /// planned. (Kids are written in place rather than returned: a kid is
    /// 232 bytes.)
    fn open(&self, refs: &mut [PrimRef], kids: &mut Vec<Kid>, i: usize, bins: &mut Bins) {
        if kids[i].len > EARLY {
            let key = (kids[i].first, kids[i].len);
            if let Some((_, [left, right])) = self.early.iter().find(|e| e.0 == key) {
                kids[i] = *left;
                kids.push(*right);
                return;
            }
        }
        let Kid {
            first,
            len: _,
            info,
            depth,
            step,
        } = kids[i];
        let d = depth + 1;
        let step = match step {
            Step::Later => Step::Sah(plan(refs, &info, depth, self.opts, bins)),
            s => s,
        };
        match step {
            Step::Sah(p) => {
                let (_, mid, linfo, rinfo) = split_refs(refs, &p);
                let (left, right) = refs.split_at_mut(mid);
                if matches!(p, Plan::Binned { leaf_ok: true, .. }) {
                    kids[i] = self.swept_kid(left, first, d);
                    kids.push(self.swept_kid(right, first + mid, d));
                } else {
                    kids[i] = self.sah_kid(left, first, linfo, d, bins);
                    kids.push(self.sah_kid(right, first + mid, rinfo, d, bins));
                }
            }
            Step::Swept(Some((at, _))) => {
                let (left, right) = refs.split_at_mut(at);
                kids[i] = self.swept_kid(left, first, d);
                kids.push(self.swept_kid(right, first + at, d));
            }
            Step::Swept(None) | Step::Later => unreachable!("a leaf is not opened"),
        }
    }

    /// Open `kid` (over `refs`) and, recursively, its halves while they
    /// hold more than [`EARLY`] references, the two halves of each in
    /// parallel; the halves of every kid opened go to `out`. An opening
    /// depends only on the kid's own references, and the wide nodes open
    /// every such kid first thing (none is a leaf), so taking the halves
    /// from `out` later ([`Build::open`]) makes the same tree. What changes
    /// is when: the root's wide node opens its children one after the
    /// other, about three binary levels whose partitions ran on one core
    /// (their binning was already parallel); opened ahead, every level
    /// below the root's own split runs on all cores. Two threads, builds
    /// alternated in one process: the 1M-triangle terrain 1.04× faster,
    /// the full dragon 1.03×, the 500k scatter 2% slower in one round and
    /// 2.5% faster in another; one thread alike within 2.6%.
    fn open_early(
        &self,
        refs: &mut [PrimRef],
        kid: Kid,
        bins: &mut Bins,
        out: &mut Vec<((usize, usize), [Kid; 2])>,
    ) {
        if kid.len <= EARLY || kid.is_leaf() {
            return;
        }
        let mut kids = vec![kid];
        self.open(refs, &mut kids, 0, bins);
        let halves = [kids[0], kids[1]];
        out.push(((kid.first, kid.len), halves));
        let (left, right) = refs.split_at_mut(halves[0].len);
        let mut more = Vec::new();
        rayon::join(
            || self.open_early(left, halves[0], bins, out),
            || {
                let mut own = Bins::new(self.opts.bins);
                self.open_early(right, halves[1], &mut own, &mut more)
            },
        );
        out.append(&mut more);
    }

    /// Order the references of a `leaf_ok` kid that stays one leaf (its
    /// `step`) as the binary build does: it builds the subtree below, which
    /// the collapse then ignores, and that reorders the leaf's triangles.
    /// The same splits and sorts, without the subtree's nodes.
    fn settle(&self, refs: &mut [PrimRef], step: Step) {
        let at = match step {
            Step::Sah(p) => split_refs(refs, &p).1,
            Step::Swept(Some((at, _))) => at,
            Step::Swept(None) | Step::Later => return,
        };
        let (left, right) = refs.split_at_mut(at);
        for half in [left, right] {
            let k = self.swept_kid(half, 0, 0);
            self.settle(half, k.step);
        }
    }

    /// Emit `kid`, whose references are `refs` (at wide depth `depth`,
    /// below ancestors leaving `pending` siblings on the stack), into `c`;
    /// returns its reference. [`super::collapse`]'s `emit`, step for step.
    fn emit<N: WideSlots>(
        &self,
        refs: &mut [PrimRef],
        kid: &Kid,
        depth: u32,
        pending: usize,
        c: &mut Collapsed<N>,
        bins: &mut Bins,
    ) -> Child4 {
        c.depth = c.depth.max(depth);
        let rel = kid.info.bounds.aabb().surface_area() as f64 / self.root_area;
        if kid.is_leaf() || kid.leaf_ok() {
            if kid.leaf_ok() {
                self.settle(refs, kid.step);
            }
            c.leaves += 1;
            c.sah_cost += rel * kid.len as f64;
            return Child4 {
                index: kid.first as u32,
                count: kid.len as u32,
            };
        }
        c.inner += 1;
        c.sah_cost += rel * self.opts.traversal_cost as f64;
        let index = c.nodes.len();
        c.nodes.push(N::EMPTY);
        let kids = self.wide_children(refs, kid, N::WIDTH, bins);
        let kids = &kids[..];
        let pending = pending + kids.len() - 1;
        c.stack = c.stack.max(pending);
        let out: Vec<Child4> = if depth < PAR_DEPTH {
            // Each child's subtree on its own, then appended in order.
            let parts = disjoint(refs, kid.first, kids);
            let subs: Vec<(Child4, Collapsed<N>)> = parts
                .into_par_iter()
                .zip(kids.par_iter())
                .map(|(part, k)| {
                    let mut sub = Collapsed::empty();
                    // Room for more than the usual node count (an inner
                    // node per 20-25 triangles on the terrain and the
                    // dragon), so that the array is rarely copied as it
                    // grows.
                    sub.nodes.reserve(k.len / 16 + 1);
                    let mut own = Bins::new(self.opts.bins);
                    let r = self.emit(part, k, depth + 1, pending, &mut sub, &mut own);
                    (r, sub)
                })
                .collect();
            c.nodes
                .reserve(subs.iter().map(|(_, s)| s.nodes.len()).sum());
            super::huge_pages::advise(&mut c.nodes);
            subs.into_iter().map(|(r, sub)| c.append(r, sub)).collect()
        } else {
            kids.iter()
                .map(|k| {
                    let start = k.first - kid.first;
                    let part = &mut refs[start..start + k.len];
                    self.emit(part, k, depth + 1, pending, c, bins)
                })
                .collect()
        };
        let mut node = N::EMPTY;
        for (slot, (k, r)) in kids.iter().zip(out).enumerate() {
            node.set_slot(slot, &k.info.bounds.aabb().into(), r);
        }
        c.nodes[index] = node;
        Child4 {
            index: index as u32,
            count: 0,
        }
    }

    /// The children of the wide node made from `kid`: its two halves, then,
    /// while there are fewer than `width`, the largest-area inner one
    /// opened into its two halves (ties to the later one).
    fn wide_children(
        &self,
        refs: &mut [PrimRef],
        kid: &Kid,
        width: usize,
        bins: &mut Bins,
    ) -> Vec<Kid> {
        let mut kids = Vec::with_capacity(8);
        kids.push(*kid);
        self.open(refs, &mut kids, 0, bins);
        let mut areas = [-1.0f32; 8];
        areas[0] = kids[0].area();
        areas[1] = kids[1].area();
        while kids.len() < width.min(8) {
            let n = kids.len();
            let Some(i) = to_open(&areas[..n]) else {
                break;
            };
            let start = kids[i].first - kid.first;
            let len = kids[i].len;
            self.open(&mut refs[start..start + len], &mut kids, i, bins);
            areas[i] = kids[i].area();
            areas[n] = kids[n].area();
        }
        kids
    }
}

/// The references of each of `kids` (ranges that tile `refs`, which starts
/// at `base`) as separate slices, in the order of `kids`.
fn disjoint<'r>(refs: &'r mut [PrimRef], base: usize, kids: &[Kid]) -> Vec<&'r mut [PrimRef]> {
    let mut by_first: Vec<usize> = (0..kids.len()).collect();
    by_first.sort_unstable_by_key(|&i| kids[i].first);
    let mut parts: Vec<Option<&'r mut [PrimRef]>> = (0..kids.len()).map(|_| None).collect();
    let mut rest = refs;
    let mut at = base;
    for i in by_first {
        debug_assert_eq!(kids[i].first, at, "the children's ranges tile the node's");
        let (part, tail) = rest.split_at_mut(kids[i].len);
        parts[i] = Some(part);
        rest = tail;
        at += kids[i].len;
    }
    parts
        .into_iter()
        .map(|p| p.expect("every child has its range"))
        .collect()
}

/// Build the wide tree of `N` nodes over the triangles of `mesh` with the
/// binned SAH (options already clamped, quality [`super::BuildQuality::Sah`]
/// or `High`): the collapsed tree, its root box and the triangle order its
/// leaves refer to.
pub(crate) fn build_direct<N: WideSlots>(
    mesh: &crate::mesh::TriangleMesh,
    opts: &BuildOptions,
) -> (Collapsed<N>, crate::aabb::Aabb, Vec<u32>) {
    let (mut refs, info) = prim_refs(mesh);
    let root_box = info.bounds.aabb();
    let mut build = Build {
        opts,
        root_area: (root_box.surface_area() as f64).max(f64::MIN_POSITIVE),
        early: Vec::new(),
    };
    let mut bins = Bins::new(opts.bins);
    let root = build.sah_kid(&refs, 0, info, 0, &mut bins);
    let mut early = Vec::new();
    build.open_early(&mut refs, root, &mut bins, &mut early);
    build.early = early;
    let mut c = Collapsed::empty();
    c.root = build.emit(&mut refs, &root, 0, 0, &mut c, &mut bins);
    (c, root_box, order_of(&refs))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::build::{build, clamped};
    use crate::accel::bvh::collapse::{collapse, tests::soup};
    use crate::accel::bvh::node4::Node4;
    use crate::accel::bvh::node8::Node8;
    use crate::mesh::TriangleMesh;
    use glam::Vec3;

    /// The direct build equals the binary build collapsed: the same node
    /// array, node for node (boxes and references), the same root, shape
    /// figures and triangle order (the SAH cost summed in the same order,
    /// so equal exactly).
    fn same_as_collapsed<N: WideSlots>(
        mesh: &TriangleMesh,
        opts: &BuildOptions,
        same: impl Fn(&N, &N) -> bool,
    ) {
        let opts = clamped(opts);
        let tree = build(mesh, &opts);
        let want = collapse::<N>(&tree.root, opts.traversal_cost as f64);
        let (got, root_box, order) = build_direct::<N>(mesh, &opts);
        let what = format!("{} triangles, {opts:?}", mesh.num_triangles());
        assert_eq!(order, tree.order, "{what}");
        assert_eq!(root_box, tree.root.bounds(), "{what}");
        assert_eq!(got.root, want.root, "{what}");
        assert_eq!(got.nodes.len(), want.nodes.len(), "{what}");
        let differ = got
            .nodes
            .iter()
            .zip(&want.nodes)
            .position(|(a, b)| !same(a, b));
        assert_eq!(differ, None, "first differing node, {what}");
        assert_eq!(
            (got.inner, got.leaves, got.depth, got.stack),
            (want.inner, want.leaves, want.depth, want.stack),
            "{what}"
        );
        assert_eq!(got.sah_cost, want.sah_cost, "{what}");
    }

    /// Meshes for the comparison: random soups from one triangle to enough
    /// for the parallel binning (over 64k references) and parallel
    /// subtrees, and a stack of coincident triangles (no SAH split: the
    /// median split).
    fn meshes() -> Vec<TriangleMesh> {
        let mut out: Vec<TriangleMesh> = [1, 2, 7, 300, 5_000, 70_000]
            .into_iter()
            .map(|n| soup(n, 11 + n as u64))
            .collect();
        let (mut positions, mut indices) = (Vec::new(), Vec::new());
        for i in 0..600u32 {
            positions.extend([Vec3::ZERO, Vec3::X, Vec3::Y]);
            indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        out.push(TriangleMesh::new(positions, indices));
        out
    }

    /// With subtrees large enough for two levels of early opening (and the
    /// halves of a kid split unevenly), the direct build still equals the
    /// binary build collapsed.
    #[test]
    fn early_opening_keeps_the_binary_build_collapsed() {
        let mesh = soup(4 * EARLY + 1000, 5);
        let opts = BuildOptions::default();
        same_as_collapsed::<Node8>(&mesh, &opts, |a, b| {
            a.boxes == b.boxes && a.child == b.child
        });
    }

    #[test]
    fn direct_build_equals_the_binary_build_collapsed() {
        for mesh in meshes() {
            for (leaf, block, fill) in [
                (4, 1, false),
                (1, 1, false),
                (16, 4, false),
                (16, 4, true),
                (8, 4, true),
            ] {
                let opts = BuildOptions {
                    max_leaf_size: leaf,
                    leaf_block: block,
                    fill_wide_nodes: fill,
                    ..BuildOptions::default()
                };
                same_as_collapsed::<Node4>(&mesh, &opts, |a, b| {
                    a.boxes == b.boxes && a.child == b.child
                });
                same_as_collapsed::<Node8>(&mesh, &opts, |a, b| {
                    a.boxes == b.boxes && a.child == b.child
                });
            }
        }
    }
}
