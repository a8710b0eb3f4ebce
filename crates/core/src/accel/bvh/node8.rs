//! The 8-wide node of [`super::Bvh8`] and its construction by collapsing a
//! binary build tree (issue 8): Embree's BVH8 layout on AVX machines (Wald
//! et al. 2014), made the way [`super::node4`] makes the 4-wide tree.

use super::box8::Box8;
use super::build::BuildNode;
use super::node4::{wide_children, Child4};
use super::node_box::NodeBox;

/// A 256-byte inner node (four cache lines): the padded boxes of up to
/// eight children in structure-of-arrays layout, and the child references
/// (as in [`super::Bvh4`]: an inner node, a leaf or an unused slot).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub(crate) struct Node8 {
    pub boxes: Box8,
    pub child: [Child4; 8],
}

/// The inner nodes of a tree collapsed to 8-wide nodes and its shape
/// figures, defined as for the binary tree (see
/// [`crate::accel::AccelStats`]).
pub(crate) struct Collapsed8 {
    pub nodes: Vec<Node8>,
    pub root: Child4,
    pub inner: usize,
    pub leaves: usize,
    pub depth: u32,
    pub sah_cost: f64,
    /// Most traversal stack entries a ray can need: the largest sum, over a
    /// root-to-leaf path, of each inner node's children less one.
    pub stack: usize,
}

/// Collapse the binary tree below `root` into 8-wide nodes: each wide node
/// starts from the two children of a binary node and, while it has fewer
/// than eight, replaces its largest-area inner child by that child's two
/// children. Leaves are the binary tree's leaves, triangle ranges unchanged.
pub(crate) fn collapse8(root: &BuildNode, traversal_cost: f64) -> Collapsed8 {
    let mut c = Collapsed8 {
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

fn emit(
    node: &BuildNode,
    depth: u32,
    pending: usize,
    root_area: f64,
    c_trav: f64,
    c: &mut Collapsed8,
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
            c.nodes.push(Node8::default());
            let mut n = Node8 {
                boxes: Box8::EMPTY,
                child: [Child4::EMPTY; 8],
            };
            let (kids, k) = wide_children::<8>(node);
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

    /// Walking the collapsed tree covers every triangle position of the
    /// binary tree exactly once, each child's box contains its subtree's
    /// boxes, and unused slots come last with inverted boxes.
    #[test]
    fn collapse8_keeps_every_triangle_exactly_once() {
        for (n, leaf) in [(1, 4), (2, 1), (9, 1), (1000, 4), (20_000, 1), (20_000, 8)] {
            let mesh = soup(n, n as u64);
            let opts = BuildOptions {
                max_leaf_size: leaf,
                ..Default::default()
            };
            let tree = build(&mesh, &opts);
            let (bin_nodes, bin_leaves, bin_depth, _) =
                crate::accel::bvh::build::tree_shape(&tree.root, 1.0);
            let c = collapse8(&tree.root, 1.0);
            assert_eq!(c.leaves, bin_leaves, "same leaves as the binary tree");
            assert!(c.inner + c.leaves <= bin_nodes);
            assert!(c.depth <= bin_depth);
            assert!(c.stack <= 7 * c.depth as usize);
            assert_eq!(c.inner, c.nodes.len());
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
                        if k.count == 0 {
                            let outer = node.boxes.get(s);
                            let inner = &c.nodes[k.index as usize];
                            for t in 0..8 {
                                if inner.child[t] != Child4::EMPTY {
                                    let b = inner.boxes.get(t);
                                    assert!(outer.min.cmple(b.min).all());
                                    assert!(outer.max.cmpge(b.max).all());
                                }
                            }
                        }
                        stack.push(k);
                    } else {
                        assert_eq!(k, Child4::EMPTY, "unused slots come last");
                        assert_eq!(node.boxes.get(s).min, Vec3::INFINITY);
                    }
                }
            }
            assert_eq!(inner_seen, c.inner);
            assert!(seen.iter().all(|&s| s == 1), "n = {n}");
        }
    }
}
