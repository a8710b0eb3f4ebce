//! The collapse of a binary build tree into the wide nodes of
//! [`super::Bvh4`] and [`super::Bvh8`]: the usual way to get an
//! Embree-style wide BVH out of a binary build (Wald et al. 2014), written
//! once for both widths. The linear BVH ([`super::build::lbvh`]) goes through it;
//! the SAH builds make the same wide nodes directly
//! ([`super::wide_build`], which follows these rules step for step and is
//! tested against this walk).
//!
//! Each wide node starts from the two children of a binary node and, while
//! it has fewer than its width, replaces its largest-area inner child by
//! that child's two children. Leaves are the binary tree's leaves, triangle
//! ranges unchanged, and the inner nodes marked `leaf_ok` that a node has
//! not opened (a tree built with [`super::BuildOptions::fill_wide_nodes`]:
//! such a node is opened like any inner child while slots are free, which
//! is Embree's rule, and otherwise becomes one leaf of its whole range).
//! Nodes are numbered in depth-first pre-order, the root first.
//!
//! The top [`PAR_DEPTH`] levels collapse their children's subtrees in
//! parallel, each into its own node array, concatenated afterwards in child
//! order with their inner references shifted: the same array, node for node,
//! as the serial walk (the full dragon's collapse took 16 ms on one thread,
//! 8% of a 2-thread build).

use super::build::BuildNode;
use super::wide_node::{Child4, WideSlots};
use rayon::prelude::*;

/// Levels of wide nodes whose subtrees are collapsed in parallel (up to
/// `WIDTH^PAR_DEPTH` tasks).
pub(crate) const PAR_DEPTH: u32 = 2;

/// The inner nodes of a collapsed tree and its shape figures, defined as for
/// the binary tree (see [`crate::accel::AccelStats`]).
pub(crate) struct Collapsed<N> {
    pub nodes: Vec<N>,
    pub root: Child4,
    pub inner: usize,
    pub leaves: usize,
    pub depth: u32,
    pub sah_cost: f64,
    /// Most traversal stack entries a ray can need: the largest sum, over a
    /// root-to-leaf path, of each inner node's children less one (at a node,
    /// the stack holds at most the unvisited siblings of its ancestors).
    pub stack: usize,
}

impl<N> Collapsed<N> {
    pub(crate) fn empty() -> Self {
        Collapsed {
            nodes: Vec::new(),
            root: Child4::EMPTY,
            inner: 0,
            leaves: 0,
            depth: 0,
            sah_cost: 0.0,
            stack: 0,
        }
    }

    /// Append `sub`, collapsed on its own, and return its root `r` with the
    /// shifted index: its inner references move up by the nodes already
    /// here.
    pub(crate) fn append(&mut self, r: Child4, mut sub: Collapsed<N>) -> Child4
    where
        N: WideSlots,
    {
        let offset = self.nodes.len() as u32;
        sub.nodes.par_iter_mut().with_min_len(4096).for_each(|n| {
            for c in n.children_mut() {
                if c.count == 0 && *c != Child4::EMPTY {
                    c.index += offset;
                }
            }
        });
        self.nodes.append(&mut sub.nodes);
        self.inner += sub.inner;
        self.leaves += sub.leaves;
        self.depth = self.depth.max(sub.depth);
        self.sah_cost += sub.sah_cost;
        self.stack = self.stack.max(sub.stack);
        match r.count {
            0 => Child4 {
                index: r.index + offset,
                count: 0,
            },
            _ => r,
        }
    }
}

/// Collapse the binary tree below `root` into nodes of `N::WIDTH` children
/// (see the module docs).
pub(crate) fn collapse<N: WideSlots>(root: &BuildNode, traversal_cost: f64) -> Collapsed<N> {
    collapse_with(root, traversal_cost, PAR_DEPTH)
}

/// [`collapse`] with the top `par_depth` levels in parallel (0: serial).
fn collapse_with<N: WideSlots>(root: &BuildNode, c_trav: f64, par_depth: u32) -> Collapsed<N> {
    let mut c = Collapsed::empty();
    let root_area = (root.bounds().surface_area() as f64).max(f64::MIN_POSITIVE);
    let walk = Walk {
        root_area,
        c_trav,
        par_depth,
    };
    c.root = walk.emit(root, 0, 0, &mut c);
    c
}

/// Up to `width` (at most 8) binary-tree nodes that become the children of
/// the wide node made from the inner node `node`, in the first slots of the
/// array: the two children of `node`, then, while there are fewer than
/// `width`, the largest-area inner one replaced by its two children.
fn wide_children(node: &BuildNode, width: usize) -> ([&BuildNode; 8], usize) {
    let BuildNode::Inner { children, .. } = node else {
        unreachable!("only inner nodes have children")
    };
    // Each kid's area, or -1 for a leaf (never opened): computed once.
    let area = |k: &BuildNode| match k {
        BuildNode::Inner { bounds, .. } => bounds.surface_area(),
        BuildNode::Leaf { .. } => -1.0,
    };
    let mut kids = [&children[0]; 8];
    let mut areas = [-1.0f32; 8];
    kids[1] = &children[1];
    areas[0] = area(kids[0]);
    areas[1] = area(kids[1]);
    let mut n = 2;
    while n < width.min(8) {
        let Some(i) = to_open(&areas[..n]) else {
            break;
        };
        let BuildNode::Inner { children, .. } = kids[i] else {
            unreachable!("only inner kids have a non-negative area")
        };
        kids[i] = &children[0];
        kids[n] = &children[1];
        areas[i] = area(kids[i]);
        areas[n] = area(kids[n]);
        n += 1;
    }
    (kids, n)
}

/// Which of a wide node's children to open next, given their areas (-1
/// for a leaf): the largest, the later one at equal areas; `None` when
/// every child is a leaf. The rule the collapse and the direct wide build
/// ([`super::wide_build`]) share.
pub(crate) fn to_open(areas: &[f32]) -> Option<usize> {
    let mut i = 0;
    for j in 1..areas.len() {
        if areas[j] >= areas[i] {
            i = j;
        }
    }
    (areas[i] >= 0.0).then_some(i)
}

/// The constants of one collapse.
struct Walk {
    root_area: f64,
    c_trav: f64,
    par_depth: u32,
}

impl Walk {
    /// Emit `node` (at `depth`, below ancestors leaving `pending` siblings
    /// on the stack) into `c`; returns its reference.
    fn emit<N: WideSlots>(
        &self,
        node: &BuildNode,
        depth: u32,
        pending: usize,
        c: &mut Collapsed<N>,
    ) -> Child4 {
        c.depth = c.depth.max(depth);
        let rel = node.bounds().surface_area() as f64 / self.root_area;
        if let BuildNode::Leaf { .. } | BuildNode::Inner { leaf_ok: true, .. } = node {
            let (first, count) = node.triangle_range();
            c.leaves += 1;
            c.sah_cost += rel * count as f64;
            return Child4 {
                index: first,
                count,
            };
        }
        c.inner += 1;
        c.sah_cost += rel * self.c_trav;
        let index = c.nodes.len();
        c.nodes.push(N::EMPTY);
        let mut n = N::EMPTY;
        let (kids, k) = wide_children(node, N::WIDTH);
        let kids = &kids[..k];
        let pending = pending + kids.len() - 1;
        c.stack = c.stack.max(pending);
        let refs: Vec<Child4> = if depth < self.par_depth {
            // Each child's subtree on its own, then appended in order.
            let subs: Vec<(Child4, Collapsed<N>)> = kids
                .par_iter()
                .map(|kid| {
                    let mut sub = Collapsed::empty();
                    let r = self.emit(kid, depth + 1, pending, &mut sub);
                    (r, sub)
                })
                .collect();
            subs.into_iter().map(|(r, sub)| c.append(r, sub)).collect()
        } else {
            kids.iter()
                .map(|kid| self.emit(kid, depth + 1, pending, c))
                .collect()
        };
        for (slot, (kid, r)) in kids.iter().zip(refs).enumerate() {
            n.set_slot(slot, &kid.bounds().into(), r);
        }
        c.nodes[index] = n;
        Child4 {
            index: index as u32,
            count: 0,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::accel::bvh::build::{build, BuildOptions};
    use crate::accel::bvh::node4::Node4;
    use crate::accel::bvh::node8::Node8;
    use crate::mesh::TriangleMesh;
    use glam::Vec3;

    /// `n` small random triangles in the unit cube.
    pub(crate) fn soup(n: usize, seed: u64) -> TriangleMesh {
        crate::test_soup::soup(n, seed, 0.02, 0.0, 1)
    }

    /// Walking the collapsed tree covers every triangle position of the
    /// binary tree exactly once, with the binary tree's leaves; every node
    /// has at least two children, unused slots last with inverted boxes;
    /// each child's box contains its own children's boxes; the shape figures
    /// agree with the walk (inner nodes) and bound the stack.
    ///
    /// With [`BuildOptions::fill_wide_nodes`] (leaf blocks of four, as the
    /// packed leaves build) the leaves are the marked subtrees instead, no
    /// larger than the leaf bound, and a node keeps a free slot only when
    /// every child is a leaf of one block, which cannot be split further.
    fn keeps_every_triangle_exactly_once<N: WideSlots>() {
        for (n, leaf, fill) in [
            (1, 4, false),
            (2, 1, false),
            (5, 1, false),
            (9, 1, false),
            (1000, 4, false),
            (20_000, 1, false),
            (20_000, 8, false),
            (1, 16, true),
            (7, 16, true),
            (1000, 16, true),
            (20_000, 16, true),
            (20_000, 8, true),
        ] {
            let mesh = soup(n, n as u64);
            let opts = BuildOptions {
                max_leaf_size: leaf,
                leaf_block: if fill { 4 } else { 1 },
                fill_wide_nodes: fill,
                ..Default::default()
            };
            let tree = build(&mesh, &opts);
            let (bin_nodes, bin_leaves, bin_depth, _) =
                crate::accel::bvh::build::tree_shape(&tree.root, 1.0);
            let c = collapse::<N>(&tree.root, 1.0);
            if fill {
                assert!(c.leaves <= bin_leaves, "marked subtrees are leaves");
            } else {
                assert_eq!(c.leaves, bin_leaves, "same leaves as the binary tree");
            }
            assert!(c.inner + c.leaves <= bin_nodes);
            assert!(c.depth <= bin_depth);
            assert!(c.stack <= (N::WIDTH - 1) * c.depth as usize);
            assert_eq!(c.inner, c.nodes.len());
            let mut seen = vec![0u32; tree.order.len()];
            let mut stack = vec![c.root];
            let mut inner_seen = 0;
            while let Some(r) = stack.pop() {
                if r.count > 0 {
                    assert!(r.count as usize <= leaf, "leaf within the bound");
                    for s in &mut seen[r.index as usize..(r.index + r.count) as usize] {
                        *s += 1;
                    }
                    continue;
                }
                inner_seen += 1;
                let node = &c.nodes[r.index as usize];
                let used = (0..N::WIDTH)
                    .filter(|&s| node.slot(s).1 != Child4::EMPTY)
                    .count();
                assert!(used >= 2, "every wide node has at least two children");
                if fill && used < N::WIDTH {
                    assert!(
                        (0..used).all(|s| (1..=4).contains(&node.slot(s).1.count)),
                        "a free slot only beside leaves of one block (n = {n})"
                    );
                }
                for s in 0..N::WIDTH {
                    let (outer, k) = node.slot(s);
                    if s >= used {
                        assert_eq!(k, Child4::EMPTY, "unused slots come last");
                        assert_eq!(outer.min, Vec3::INFINITY);
                        continue;
                    }
                    assert_ne!(k, Child4::EMPTY);
                    if k.count == 0 {
                        let inner = &c.nodes[k.index as usize];
                        for t in 0..N::WIDTH {
                            let (b, kk) = inner.slot(t);
                            if kk != Child4::EMPTY {
                                assert!(outer.min.cmple(b.min).all());
                                assert!(outer.max.cmpge(b.max).all());
                            }
                        }
                    }
                    stack.push(k);
                }
            }
            assert_eq!(inner_seen, c.inner);
            assert!(seen.iter().all(|&s| s == 1), "n = {n}");
            let mut prims = tree.order.clone();
            prims.sort_unstable();
            assert!(prims.iter().copied().eq(0..n as u32));
        }
    }

    #[test]
    fn collapse4_keeps_every_triangle_exactly_once() {
        keeps_every_triangle_exactly_once::<Node4>();
    }

    #[test]
    fn collapse8_keeps_every_triangle_exactly_once() {
        keeps_every_triangle_exactly_once::<Node8>();
    }

    /// The parallel collapse gives the serial walk's node array, node for
    /// node (boxes and references), and the same shape figures (the SAH
    /// cost summed in another order, so equal up to rounding), for both
    /// widths, trees from one leaf to many levels of parallel subtrees, and
    /// with filled nodes or not.
    #[test]
    fn parallel_collapse_equals_serial_walk() {
        fn check<N: WideSlots>(tree: &BuildNode, same: impl Fn(&N, &N) -> bool) {
            let serial = collapse_with::<N>(tree, 1.0, 0);
            for par in [1, 2, 3] {
                let p = collapse_with::<N>(tree, 1.0, par);
                assert_eq!(p.nodes.len(), serial.nodes.len());
                assert!(p.nodes.iter().zip(&serial.nodes).all(|(a, b)| same(a, b)));
                assert_eq!(p.root, serial.root);
                assert_eq!(
                    (p.inner, p.leaves, p.depth, p.stack),
                    (serial.inner, serial.leaves, serial.depth, serial.stack)
                );
                let tol = 1e-9 * serial.sah_cost.max(1.0);
                assert!((p.sah_cost - serial.sah_cost).abs() <= tol);
            }
        }
        for n in [1, 2, 7, 300, 20_000] {
            let mesh = soup(n, 5 + n as u64);
            for fill in [false, true] {
                let opts = BuildOptions {
                    fill_wide_nodes: fill,
                    leaf_block: if fill { 4 } else { 1 },
                    max_leaf_size: if fill { 16 } else { 4 },
                    ..BuildOptions::default()
                };
                let tree = build(&mesh, &opts);
                check::<Node4>(&tree.root, |a, b| a.boxes == b.boxes && a.child == b.child);
                check::<Node8>(&tree.root, |a, b| a.boxes == b.boxes && a.child == b.child);
            }
        }
    }
}
