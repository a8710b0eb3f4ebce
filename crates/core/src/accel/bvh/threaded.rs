//! The stackless threaded BVH (Smits 1998): nodes in pre-order, each with an
//! escape index.

use super::build::{build, BuildNode, BuildOptions, BuildTree};
use crate::aabb::Aabb;
use crate::accel::leaf::LeafTriangles;
use crate::accel::node_box::NodeBox;
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
/// complete tree with one triangle per leaf: [`ThreadedBvh::complete`]
/// builds that tree. [`ThreadedBvh::build`] flattens the same binned-SAH tree
/// as [`super::Bvh2`] instead (leaf size from [`BuildOptions::max_leaf_size`],
/// 1 gives one-triangle leaves), so the two layouts differ only in traversal.
pub struct ThreadedBvh<T: TriangleTest> {
    nodes: Vec<Node>,
    tris: LeafTriangles<T>,
    stats: AccelStats,
}

impl<T: TriangleTest> ThreadedBvh<T> {
    /// Build over all triangles of `mesh`.
    ///
    /// # Panics
    /// When a triangle refers to a vertex the mesh does not have
    /// ([`TriangleMesh::assert_indices_in_range`]).
    pub fn build(mesh: &TriangleMesh, options: &BuildOptions) -> Self {
        mesh.assert_indices_in_range();
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

    /// The threaded BVH of Kim et al.'s GPU stream ray tracer (after Purcell
    /// et al. 2002): a complete binary tree built bottom-up over the
    /// triangles in mesh index order, one triangle per leaf. The leaves are
    /// paired in order, then the pairs, and so on (an odd node at the end of
    /// a level moves up unpaired), so the pre-order visits the leaves in
    /// index order and the depth is ⌈log2 n⌉. No sorting and no cost model:
    /// the boxes are as tight as the mesh's triangle order is coherent.
    pub fn complete(mesh: &TriangleMesh) -> Self {
        let n = mesh.num_triangles();
        assert!(
            n <= FIRST_MASK as usize + 1,
            "threaded BVH holds at most 2^27 triangles"
        );
        let tree = BuildTree {
            root: complete_tree(mesh),
            order: (0..n as u32).collect(),
        };
        let mut nodes = Vec::with_capacity(tree.root.count_nodes());
        preorder(&tree.root, &mut nodes);
        let options = BuildOptions {
            max_leaf_size: 1,
            ..BuildOptions::default()
        };
        let (tris, stats) = tree.into_leaves(mesh, std::mem::size_of_val(&nodes[..]), &options);
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

/// The complete binary tree over the triangles of `mesh` in index order,
/// built level by level from one-triangle leaves (see
/// [`ThreadedBvh::complete`]); an empty mesh gives one empty leaf.
fn complete_tree(mesh: &TriangleMesh) -> BuildNode {
    let mut level: Vec<BuildNode> = (0..mesh.num_triangles())
        .map(|i| BuildNode::Leaf {
            bounds: mesh.triangle_bounds(i),
            first: i as u32,
            count: 1,
        })
        .collect();
    while level.len() > 1 {
        let mut next = Vec::with_capacity(level.len().div_ceil(2));
        let mut nodes = level.into_iter();
        while let Some(a) = nodes.next() {
            match nodes.next() {
                Some(b) => {
                    let bounds = a.bounds().union(b.bounds());
                    next.push(BuildNode::Inner {
                        bounds,
                        children: Box::new([a, b]),
                        leaf_ok: false,
                    });
                }
                None => next.push(a),
            }
        }
        level = next;
    }
    level.pop().unwrap_or(BuildNode::Leaf {
        bounds: Aabb::EMPTY,
        first: 0,
        count: 0,
    })
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
