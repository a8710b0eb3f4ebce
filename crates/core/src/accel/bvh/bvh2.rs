//! Binary BVH with a per-ray stack, nearest child first.

use super::build::{build, BuildNode, BuildOptions};
use super::MAX_DEPTH;
use crate::aabb::Aabb;
use crate::accel::leaf::LeafTriangles;
use crate::accel::node_box::NodeBox;
use crate::accel::{Accel, AccelStats};
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::TriangleTest;
use glam::Vec3;

/// A reference to a child: an inner node (`count == 0`, `index` into the
/// node array) or a leaf (`count` triangles from `index` in leaf order).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C)]
struct Child {
    index: u32,
    count: u32,
}

/// A 64-byte inner node (one cache line) holding the boxes of both
/// children, so that one memory access serves both slab tests; leaves have
/// no node of their own. The boxes are stored per axis, `lo[axis][child]`.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
struct Node {
    lo: [[f32; 2]; 3],
    hi: [[f32; 2]; 3],
    child: [Child; 2],
}

impl Node {
    /// The (padded) box of child `c`.
    fn child_box(&self, c: usize) -> Aabb {
        Aabb::new(
            Vec3::new(self.lo[0][c], self.lo[1][c], self.lo[2][c]),
            Vec3::new(self.hi[0][c], self.hi[1][c], self.hi[2][c]),
        )
    }

    /// Entry distances of the ray into both child boxes within `[tnear, tfar]`,
    /// `f32::INFINITY` for a miss (see [`NodeBox::entry`] for the rounding).
    #[inline(always)]
    fn entries(&self, ray: &Ray, tnear: f32, tfar: f32) -> [f32; 2] {
        let o = ray.origin.to_array();
        let id = ray.inv_dir.to_array();
        let mut out = [0.0; 2];
        for (c, slot) in out.iter_mut().enumerate() {
            let mut enter = tnear;
            let mut exit = f32::INFINITY;
            for a in 0..3 {
                let t0 = (self.lo[a][c] - o[a]) * id[a];
                let t1 = (self.hi[a][c] - o[a]) * id[a];
                enter = enter.max(t0.min(t1));
                exit = exit.min(t0.max(t1));
            }
            let exit = (exit * NodeBox::ROBUST_EXIT).min(tfar);
            *slot = if enter <= exit { enter } else { f32::INFINITY };
        }
        out
    }
}

/// Binary BVH over precomputed triangles, built with the binned SAH
/// (module `bvh::build`). Each inner node stores both children's boxes in one
/// cache line; traversal tests both, visits the nearer first and pushes the
/// other, with its entry distance, on a fixed-size stack, skipping it on pop
/// when a nearer hit has been found since. Occlusion queries stop at the
/// first hit.
pub struct Bvh2<T: TriangleTest> {
    nodes: Vec<Node>,
    root_box: NodeBox,
    root: Child,
    tris: LeafTriangles<T>,
    stats: AccelStats,
}

impl<T: TriangleTest> Bvh2<T> {
    /// Build over all triangles of `mesh`.
    ///
    /// # Panics
    /// When a triangle refers to a vertex the mesh does not have
    /// ([`TriangleMesh::assert_indices_in_range`]).
    pub fn build(mesh: &TriangleMesh, options: &BuildOptions) -> Self {
        mesh.assert_indices_in_range();
        let tree = build(mesh, options);
        let mut nodes = Vec::with_capacity(tree.root.count_nodes() / 2 + 1);
        let root = flatten(&tree.root, &mut nodes);
        let root_box = tree.root.bounds().into();
        let (tris, stats) = tree.into_leaves(mesh, std::mem::size_of_val(&nodes[..]), options);
        Bvh2 {
            nodes,
            root_box,
            root,
            tris,
            stats,
        }
    }

    #[inline(always)]
    fn traverse<const ANY: bool>(&self, ray: &Ray) -> (Option<Hit>, bool) {
        let rd = T::prepare(ray);
        let mut tfar = ray.tfar;
        let mut best: Option<Hit> = None;
        if self.tris.len() == 0 || self.root_box.entry(ray, ray.tnear, tfar) == f32::INFINITY {
            return (None, false);
        }
        let mut stack = [(Child::default(), 0f32); MAX_DEPTH];
        let mut sp = 0usize;
        let mut cur = self.root;
        loop {
            if cur.count > 0 {
                let (first, count) = (cur.index as usize, cur.count as usize);
                if self
                    .tris
                    .test::<ANY>(first, count, ray, &rd, &mut tfar, &mut best)
                {
                    return (None, true);
                }
            } else {
                let node = &self.nodes[cur.index as usize];
                let [tl, tr] = node.entries(ray, ray.tnear, tfar);
                let (near, far, tn, tf) = if tl <= tr {
                    (node.child[0], node.child[1], tl, tr)
                } else {
                    (node.child[1], node.child[0], tr, tl)
                };
                if tn != f32::INFINITY {
                    if tf != f32::INFINITY {
                        stack[sp] = (far, tf);
                        sp += 1;
                    }
                    cur = near;
                    continue;
                }
            }
            // Pop, skipping entries that lie beyond the nearest hit found
            // since they were pushed.
            loop {
                if sp == 0 {
                    return (best, false);
                }
                sp -= 1;
                let (c, t) = stack[sp];
                if t <= tfar {
                    cur = c;
                    break;
                }
            }
        }
    }
}

/// Append the inner nodes of `node`'s subtree (depth first) and return the
/// reference to `node`.
fn flatten(node: &BuildNode, nodes: &mut Vec<Node>) -> Child {
    match node {
        BuildNode::Leaf { first, count, .. } => Child {
            index: *first,
            count: *count,
        },
        BuildNode::Inner { children, .. } => {
            let index = nodes.len();
            nodes.push(Node::default());
            let mut n = Node::default();
            for (c, child) in children.iter().enumerate() {
                let b: NodeBox = child.bounds().into();
                for a in 0..3 {
                    n.lo[a][c] = b.min[a];
                    n.hi[a][c] = b.max[a];
                }
                n.child[c] = flatten(child, nodes);
            }
            nodes[index] = n;
            Child {
                index: index as u32,
                count: 0,
            }
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

    /// Depth first, child 0 first; a child's box is read from its parent
    /// node, the root's from `root_box`.
    fn visit_regions(&self, enter: &mut dyn FnMut(&Aabb) -> bool, leaf: &mut dyn FnMut(&[u32])) {
        let root = Aabb::new(self.root_box.min.into(), self.root_box.max.into());
        if self.tris.len() == 0 || !enter(&root) {
            return;
        }
        let mut stack = vec![self.root];
        while let Some(cur) = stack.pop() {
            if cur.count > 0 {
                leaf(self.tris.prims(cur.index as usize, cur.count as usize));
                continue;
            }
            let node = &self.nodes[cur.index as usize];
            // Push child 1 first so that child 0 is visited first.
            for c in [1, 0] {
                if enter(&node.child_box(c)) {
                    stack.push(node.child[c]);
                }
            }
        }
    }

    fn stats(&self) -> AccelStats {
        self.stats.clone()
    }
}
