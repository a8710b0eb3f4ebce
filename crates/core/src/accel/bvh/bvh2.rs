//! Binary BVH with a per-ray stack, nearest child first.

use super::build::{build, BuildNode, BuildOptions};
use super::node_box::NodeBox;
use super::MAX_DEPTH;
use crate::accel::leaf::LeafTriangles;
use crate::accel::{Accel, AccelStats};
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::TriangleTest;

/// A 32-byte flattened node: box, then either the index of the first of two
/// adjacent children (`count == 0`) or a leaf's triangle range.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C)]
struct Node {
    bounds: NodeBox,
    /// Inner: index of the left child (the right one follows it).
    /// Leaf: index of the first triangle.
    first: u32,
    /// Number of triangles; 0 for inner nodes.
    count: u32,
}

/// Binary BVH over precomputed triangles, built with the binned SAH
/// ([`super::build`]). Sibling nodes are stored side by side, so an inner node
/// needs a single child index; traversal tests both children's boxes, visits
/// the nearer first and pushes the other on a fixed-size stack.
pub struct Bvh2<T: TriangleTest> {
    nodes: Vec<Node>,
    tris: LeafTriangles<T>,
    stats: AccelStats,
}

impl<T: TriangleTest> Bvh2<T> {
    /// Build over all triangles of `mesh`.
    pub fn build(mesh: &TriangleMesh, options: &BuildOptions) -> Self {
        let tree = build(mesh, options);
        let mut nodes = Vec::with_capacity(tree.root.count_nodes());
        nodes.push(Node::default());
        flatten(&tree.root, 0, &mut nodes);
        let (tris, stats) = tree.into_leaves(mesh, std::mem::size_of_val(&nodes[..]), options);
        Bvh2 { nodes, tris, stats }
    }

    #[inline(always)]
    fn traverse<const ANY: bool>(&self, ray: &Ray) -> (Option<Hit>, bool) {
        let rd = T::prepare(ray);
        let mut tfar = ray.tfar;
        let mut best: Option<Hit> = None;
        if self.tris.len() == 0 || self.nodes[0].bounds.entry(ray, ray.tnear, tfar) == f32::INFINITY
        {
            return (None, false);
        }
        let mut stack = [0u32; MAX_DEPTH];
        let mut sp = 0usize;
        let mut idx = 0usize;
        loop {
            let node = &self.nodes[idx];
            if node.count > 0 {
                let first = node.first as usize;
                if self
                    .tris
                    .test::<ANY>(first, node.count as usize, ray, &rd, &mut tfar, &mut best)
                {
                    return (None, true);
                }
            } else {
                let l = node.first as usize;
                let tl = self.nodes[l].bounds.entry(ray, ray.tnear, tfar);
                let tr = self.nodes[l + 1].bounds.entry(ray, ray.tnear, tfar);
                let (near, far, tn, tf) = if tl <= tr {
                    (l, l + 1, tl, tr)
                } else {
                    (l + 1, l, tr, tl)
                };
                if tn != f32::INFINITY {
                    if tf != f32::INFINITY {
                        stack[sp] = far as u32;
                        sp += 1;
                    }
                    idx = near;
                    continue;
                }
            }
            // Pop, skipping nodes that lie beyond the nearest hit found since
            // they were pushed.
            loop {
                if sp == 0 {
                    return (best, false);
                }
                sp -= 1;
                let n = stack[sp] as usize;
                if ANY || self.nodes[n].bounds.entry(ray, ray.tnear, tfar) != f32::INFINITY {
                    idx = n;
                    break;
                }
            }
        }
    }
}

/// Write `node` at `index`; its children go to a freshly appended pair.
fn flatten(node: &BuildNode, index: usize, nodes: &mut Vec<Node>) {
    match node {
        BuildNode::Leaf {
            bounds,
            first,
            count,
        } => {
            nodes[index] = Node {
                bounds: (*bounds).into(),
                first: *first,
                count: *count,
            };
        }
        BuildNode::Inner {
            bounds, children, ..
        } => {
            let left = nodes.len();
            nodes.push(Node::default());
            nodes.push(Node::default());
            nodes[index] = Node {
                bounds: (*bounds).into(),
                first: left as u32,
                count: 0,
            };
            flatten(&children[0], left, nodes);
            flatten(&children[1], left + 1, nodes);
        }
    }
}

impl<T: TriangleTest> Accel for Bvh2<T> {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.traverse::<false>(ray).0
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.traverse::<true>(ray).1
    }

    fn stats(&self) -> AccelStats {
        self.stats.clone()
    }
}
