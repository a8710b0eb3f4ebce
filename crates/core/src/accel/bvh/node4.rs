//! The 4-wide node of [`super::Bvh4`] and its construction by collapsing a
//! binary build tree (issue 8; the collapse is the usual way to get an
//! Embree-style wide BVH out of a binned-SAH binary build, paper 001 for
//! BVHs in general).

use super::box4::Box4;
use super::build::BuildNode;
use super::node_box::NodeBox;

/// A reference to a child: an inner node (`count == 0`, `index` into the
/// node array), a leaf (`count > 0` triangles from `index` in leaf order), or
/// an unused slot ([`Child4::EMPTY`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub(crate) struct Child4 {
    pub index: u32,
    pub count: u32,
}

impl Child4 {
    /// An unused slot; its box in [`Box4`] is inverted so no ray enters it.
    pub const EMPTY: Child4 = Child4 {
        index: u32::MAX,
        count: 0,
    };
}

/// A 128-byte inner node (two cache lines): the padded boxes of up to four
/// children in structure-of-arrays layout, and the child references.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub(crate) struct Node4 {
    pub boxes: Box4,
    pub child: [Child4; 4],
}

/// The inner nodes of a collapsed tree and its shape figures, defined as for
/// the binary tree (see [`crate::accel::AccelStats`]).
pub(crate) struct Collapsed {
    pub nodes: Vec<Node4>,
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

/// Collapse the binary tree below `root` into 4-wide nodes: each wide node
/// starts from the two children of a binary node and, while it has fewer
/// than four, replaces its largest-area inner child by that child's two
/// children. Leaves are the binary tree's leaves, triangle ranges unchanged.
pub(crate) fn collapse(root: &BuildNode, traversal_cost: f64) -> Collapsed {
    let mut c = Collapsed {
        nodes: Vec::new(),
        root: Child4::EMPTY,
        inner: 0,
        leaves: 0,
        depth: 0,
        sah_cost: 0.0,
        stack: 0,
    };
    let root_area = (root.bounds().surface_area() as f64).max(f64::MIN_POSITIVE);
    c.root = emit(root, 0, 0, root_area, traversal_cost, &mut c);
    c
}

/// Up to `W` binary-tree nodes that become the children of the wide node
/// made from the inner node `node` (shared by the 4- and 8-wide trees): the
/// two children of `node`, then, while there are fewer than `W`, the
/// largest-area inner one replaced by its two children.
pub(super) fn wide_children<const W: usize>(node: &BuildNode) -> ([&BuildNode; W], usize) {
    let BuildNode::Inner { children, .. } = node else {
        unreachable!("only inner nodes have children")
    };
    let mut kids = [&children[0]; W];
    kids[1] = &children[1];
    let mut n = 2;
    while n < W {
        let largest = (0..n)
            .filter(|&i| matches!(kids[i], BuildNode::Inner { .. }))
            .max_by(|&a, &b| {
                let (sa, sb) = (
                    kids[a].bounds().surface_area(),
                    kids[b].bounds().surface_area(),
                );
                sa.total_cmp(&sb)
            });
        let Some(i) = largest else { break };
        let BuildNode::Inner { children, .. } = kids[i] else {
            unreachable!()
        };
        kids[i] = &children[0];
        kids[n] = &children[1];
        n += 1;
    }
    (kids, n)
}

fn emit(
    node: &BuildNode,
    depth: u32,
    pending: usize,
    root_area: f64,
    c_trav: f64,
    c: &mut Collapsed,
) -> Child4 {
    c.depth = c.depth.max(depth);
    let rel = node.bounds().surface_area() as f64 / root_area;
    match node {
        BuildNode::Leaf { first, count, .. } => {
            c.leaves += 1;
            c.sah_cost += rel * *count as f64;
            Child4 {
                index: *first,
                count: *count,
            }
        }
        BuildNode::Inner { .. } => {
            c.inner += 1;
            c.sah_cost += rel * c_trav;
            let index = c.nodes.len();
            c.nodes.push(Node4::default());
            let mut n = Node4 {
                boxes: Box4::EMPTY,
                child: [Child4::EMPTY; 4],
            };
            let (kids, k) = wide_children::<4>(node);
            let pending = pending + k - 1;
            c.stack = c.stack.max(pending);
            for (slot, kid) in kids[..k].iter().enumerate() {
                let b: NodeBox = kid.bounds().into();
                n.boxes.set(slot, &b);
                n.child[slot] = emit(kid, depth + 1, pending, root_area, c_trav, c);
            }
            c.nodes[index] = n;
            Child4 {
                index: index as u32,
                count: 0,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::build::{build, BuildOptions};
    use crate::mesh::TriangleMesh;
    use crate::rng::Pcg32;
    use glam::Vec3;

    fn soup(n: usize, seed: u64) -> TriangleMesh {
        let mut rng = Pcg32::new(seed);
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for i in 0..n {
            let c = rng.in_box(Vec3::ZERO, Vec3::ONE);
            for _ in 0..3 {
                positions.push(c + rng.unit_vector() * 0.02);
            }
            let i = 3 * i as u32;
            indices.push([i, i + 1, i + 2]);
        }
        TriangleMesh::new(positions, indices)
    }

    #[test]
    fn collapse_keeps_every_triangle_exactly_once() {
        for (n, leaf) in [(1, 4), (2, 1), (5, 1), (1000, 4), (20_000, 1), (20_000, 8)] {
            let mesh = soup(n, n as u64);
            let opts = BuildOptions {
                max_leaf_size: leaf,
                ..Default::default()
            };
            let tree = build(&mesh, &opts);
            let (bin_nodes, bin_leaves, bin_depth, _) =
                crate::accel::bvh::build::tree_shape(&tree.root, 1.0);
            let c = collapse(&tree.root, 1.0);
            assert_eq!(c.leaves, bin_leaves, "same leaves as the binary tree");
            assert!(c.inner + c.leaves <= bin_nodes);
            assert!(c.depth <= bin_depth);
            assert!(c.stack <= 3 * c.depth as usize);
            assert_eq!(c.inner, c.nodes.len());
            // Walk the wide tree; every triangle position is covered once.
            let mut seen = vec![0u32; tree.order.len()];
            let mut stack = vec![c.root];
            let mut inner_seen = 0;
            while let Some(r) = stack.pop() {
                if r.count > 0 {
                    for s in &mut seen[r.index as usize..(r.index + r.count) as usize] {
                        *s += 1;
                    }
                    continue;
                }
                inner_seen += 1;
                let node = &c.nodes[r.index as usize];
                let used = node.child.iter().filter(|&&k| k != Child4::EMPTY).count();
                assert!(used >= 2, "every wide node has at least two children");
                for (s, &k) in node.child.iter().enumerate() {
                    if s < used {
                        assert_ne!(k, Child4::EMPTY);
                        stack.push(k);
                    } else {
                        assert_eq!(k, Child4::EMPTY, "unused slots come last");
                        assert_eq!(node.boxes.get(s).min, Vec3::INFINITY);
                    }
                }
            }
            assert_eq!(inner_seen, c.inner);
            assert!(seen.iter().all(|&s| s == 1), "n = {n}");
            let mut prims = tree.order.clone();
            prims.sort_unstable();
            assert!(prims.iter().copied().eq(0..n as u32));
        }
    }
}
