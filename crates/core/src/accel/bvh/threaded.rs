//! The stackless threaded BVH (Smits 1998): nodes in pre-order, each with an
//! escape index.

use super::build::{build, BuildNode, BuildOptions};
use super::node_box::NodeBox;
use crate::aabb::Aabb;
use crate::accel::leaf::LeafTriangles;
use crate::accel::{Accel, AccelStats};
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::TriangleTest;

/// Leaf triangle counts are packed into the top bits of `prims`.
const COUNT_BITS: u32 = 5;
const FIRST_MASK: u32 = (1 << (32 - COUNT_BITS)) - 1;

/// A 32-byte node: box, escape index, and packed triangle range
/// (count in the top 5 bits, 0 for inner nodes; first triangle below).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C)]
struct Node {
    bounds: NodeBox,
    /// Where to go when the ray misses this box (or after a leaf): the next
    /// node in pre-order after this node's subtree; `nodes.len()` ends.
    escape: u32,
    prims: u32,
}

/// The threaded BVH (Smits 1998, "Efficiency issues for ray tracing"): the tree
/// is stored in pre-order, so a node's first child is the next node in the
/// array, and each node carries an escape index — where traversal continues
/// when the ray misses its box. Traversal is a single loop over the array with
/// no stack: hit → next node, miss → escape. The price is a fixed visiting
/// order (left child first), with no nearest-child-first ordering and no
/// pruning of subtrees queued before a nearer hit was found.
///
/// GPU stream ray tracers after Purcell et al. (2002) build it bottom-up as a
/// complete tree with one triangle per leaf; here it is flattened from the same
/// binned-SAH tree as [`super::Bvh2`] (leaf size from
/// [`BuildOptions::max_leaf_size`], 1 reproduces their one-triangle leaves), so
/// the two layouts differ only in traversal.
pub struct ThreadedBvh<T: TriangleTest> {
    nodes: Vec<Node>,
    tris: LeafTriangles<T>,
    stats: AccelStats,
}

impl<T: TriangleTest> ThreadedBvh<T> {
    /// Build over all triangles of `mesh`.
    pub fn build(mesh: &TriangleMesh, options: &BuildOptions) -> Self {
        let tree = build(mesh, options);
        assert!(
            tree.order.len() <= FIRST_MASK as usize + 1,
            "threaded BVH holds at most 2^27 triangles"
        );
        let mut nodes = Vec::with_capacity(tree.root.count_nodes());
        preorder(&tree.root, &mut nodes);
        let (tris, stats) = tree.into_leaves(mesh, std::mem::size_of_val(&nodes[..]), options);
        ThreadedBvh { nodes, tris, stats }
    }

    /// The nodes and triangles as flat arrays for devices with kernels of
    /// their own.
    pub fn flat(&self) -> crate::accel::FlatThreadedBvh {
        let mut nodes = Vec::with_capacity(self.nodes.len() * 8);
        for n in &self.nodes {
            nodes.extend(n.bounds.min.map(f32::to_bits));
            nodes.extend(n.bounds.max.map(f32::to_bits));
            nodes.extend([n.escape, n.prims]);
        }
        crate::accel::FlatThreadedBvh {
            nodes,
            tris: self.tris.flat(),
        }
    }

    #[inline(always)]
    fn traverse<const ANY: bool>(&self, ray: &Ray) -> (Option<Hit>, bool) {
        let rd = T::prepare(ray);
        let mut tfar = ray.tfar;
        let mut best: Option<Hit> = None;
        let end = self.nodes.len();
        let mut idx = 0usize;
        while idx < end {
            let node = &self.nodes[idx];
            if node.bounds.entry(ray, ray.tnear, tfar) == f32::INFINITY {
                idx = node.escape as usize;
                continue;
            }
            let count = (node.prims >> (32 - COUNT_BITS)) as usize;
            if count > 0 {
                let first = (node.prims & FIRST_MASK) as usize;
                if self
                    .tris
                    .test::<ANY>(first, count, ray, &rd, &mut tfar, &mut best)
                {
                    return (None, true);
                }
                idx = node.escape as usize;
            } else {
                idx += 1;
            }
        }
        (best, false)
    }
}

/// Append `node`'s subtree in pre-order and fill in escape indices.
fn preorder(node: &BuildNode, nodes: &mut Vec<Node>) {
    let index = nodes.len();
    nodes.push(Node {
        bounds: node.bounds().into(),
        ..Node::default()
    });
    match node {
        BuildNode::Leaf { first, count, .. } => {
            nodes[index].prims = first | (count << (32 - COUNT_BITS));
        }
        BuildNode::Inner { children, .. } => {
            preorder(&children[0], nodes);
            preorder(&children[1], nodes);
        }
    }
    nodes[index].escape = nodes.len() as u32;
}

impl<T: TriangleTest> Accel for ThreadedBvh<T> {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.traverse::<false>(ray).0
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.traverse::<true>(ray).1
    }

    /// The escape-index walk of the ray traversal with the box test
    /// replaced by `enter`: accepted → next node, pruned or leaf → escape.
    fn visit_regions(&self, enter: &mut dyn FnMut(&Aabb) -> bool, leaf: &mut dyn FnMut(&[u32])) {
        let end = if self.tris.len() == 0 {
            0
        } else {
            self.nodes.len()
        };
        let mut idx = 0usize;
        while idx < end {
            let node = &self.nodes[idx];
            let region = Aabb::new(node.bounds.min.into(), node.bounds.max.into());
            if !enter(&region) {
                idx = node.escape as usize;
                continue;
            }
            let count = (node.prims >> (32 - COUNT_BITS)) as usize;
            if count > 0 {
                let first = (node.prims & FIRST_MASK) as usize;
                leaf(self.tris.prims(first, count));
                idx = node.escape as usize;
            } else {
                idx += 1;
            }
        }
    }

    fn stats(&self) -> AccelStats {
        self.stats.clone()
    }
}
