//! Stackless kd-tree traversal with ropes and leaf boxes (Popov, Günther,
//! Seidel & Slusallek 2007), the stackless alternative to the per-ray stack.

use super::base::KdTree;
use super::layout::KdNode;
use super::KdOptions;
use crate::aabb::Aabb;
use crate::accel::{Accel, AccelStats, FlatKdRopes};
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::TriangleTest;

/// No neighbour: the face lies on the scene boundary.
const NONE: u32 = FlatKdRopes::NO_ROPE;

/// What the rope traversal keeps per leaf: its cell, its six ropes (the
/// node on the other side of each face, indexed `2 · axis + (1 if max
/// face)`) and its entries in the triangle-index list.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
struct LeafRecord {
    cell: Aabb,
    ropes: [u32; 6],
    first: u32,
    count: u32,
}

/// Stackless kd-tree traversal with ropes (Popov et al. 2007): each leaf
/// stores its box and, per face, a link to the smallest node that covers
/// the neighbourhood across that face ("optimised" ropes pushed down as far
/// as they stay unambiguous). The ray enters the leaf holding its entry
/// point, then moves from leaf to leaf through the exit face's rope,
/// descending from the rope's node to the leaf that holds the exit point.
/// No stack and no restarts, but 56 bytes per leaf on top of the nodes.
pub struct KdRopes<T: TriangleTest> {
    tree: KdTree<T>,
    /// The tree's nodes with each leaf's word pointing at its record.
    nodes: Vec<KdNode>,
    leaves: Vec<LeafRecord>,
}

impl<T: TriangleTest> KdRopes<T> {
    /// Build over all triangles of `mesh`.
    pub fn build(mesh: &TriangleMesh, opts: &KdOptions) -> Self {
        Self::from_tree(KdTree::build(mesh, opts))
    }

    /// Traverse an already built tree.
    pub fn from_tree(mut tree: KdTree<T>) -> Self {
        let (cells, _) = tree.cells_and_parents();
        let (nodes, leaves) = rope_leaves(&tree.nodes, &cells);
        // The traversal reads only the rope copy of the nodes.
        tree.nodes = Vec::new();
        KdRopes {
            tree,
            nodes,
            leaves,
        }
    }

    /// The nodes, leaf records, triangle-index list and triangles as flat
    /// arrays for devices with kernels of their own (layout in
    /// [`FlatKdRopes`]).
    pub fn flat(&self) -> FlatKdRopes {
        let leaves = self
            .leaves
            .iter()
            .flat_map(|r| {
                let c = r.cell.min.to_array().into_iter();
                let c = c.chain(r.cell.max.to_array()).map(f32::to_bits);
                c.chain(r.ropes).chain([r.first, r.count])
            })
            .collect();
        FlatKdRopes {
            nodes: self.nodes.iter().flat_map(|n| n.words()).collect(),
            leaves,
            indices: self.tree.indices.clone(),
            root_min: self.tree.root_cell.min.to_array(),
            root_max: self.tree.root_cell.max.to_array(),
            tris: self.tree.tris.flat(),
        }
    }

    /// Descend from `node` to the leaf whose cell holds `p`, with points on a
    /// plane sent to the side the ray moves into.
    #[inline(always)]
    fn locate(&self, mut node: u32, p: [f32; 3], d: [f32; 3]) -> &LeafRecord {
        loop {
            let n = self.nodes[node as usize];
            if n.is_leaf() {
                return &self.leaves[n.first()];
            }
            let a = n.axis();
            let s = n.split();
            let above = p[a] > s || (p[a] == s && d[a] > 0.0);
            node = n.first_child() + above as u32;
        }
    }

    fn visit(&self, enter: &mut dyn FnMut(&Aabb) -> bool, leaf: &mut dyn FnMut(&[u32])) {
        let range = |n: KdNode| {
            let r = &self.leaves[n.first()];
            (r.first as usize, r.count as usize)
        };
        self.tree.visit_nodes(&self.nodes, &range, enter, leaf)
    }

    #[inline(always)]
    fn traverse<const ANY: bool>(&self, ray: &Ray) -> (Option<Hit>, bool) {
        let t = &self.tree;
        let Some((tmin, scene_exit)) = t.clip_root(ray) else {
            return (None, false);
        };
        let rd = T::prepare(ray);
        let mut tfar = ray.tfar;
        let mut best = None;
        let o = ray.origin.to_array();
        let d = ray.dir.to_array();
        let inv = ray.inv_dir.to_array();
        let mut leaf = self.locate(0, ray.at(tmin).to_array(), d);
        // Each step crosses a face in the ray's direction, so no leaf is
        // visited twice; the bound only guards against a broken tree.
        for _ in 0..self.leaves.len() {
            let node = KdNode::leaf(leaf.first, leaf.count);
            if t.test_leaf::<ANY>(node, ray, &rd, &mut tfar, &mut best) {
                return (None, true);
            }
            let mut exit = f32::INFINITY;
            let mut face = 0;
            for a in 0..3 {
                if d[a] != 0.0 {
                    let up = d[a] > 0.0;
                    let plane = if up {
                        leaf.cell.max[a]
                    } else {
                        leaf.cell.min[a]
                    };
                    let te = (plane - o[a]) * inv[a];
                    if te < exit {
                        exit = te;
                        face = 2 * a + up as usize;
                    }
                }
            }
            if tfar <= exit || exit >= scene_exit {
                return (best, false);
            }
            let next = leaf.ropes[face];
            if next == NONE {
                return (best, false);
            }
            let mut p = ray.at(exit).to_array();
            let a = face / 2;
            p[a] = if face & 1 == 1 {
                leaf.cell.max[a]
            } else {
                leaf.cell.min[a]
            };
            leaf = self.locate(next, p, d);
        }
        (best, false)
    }
}

/// Rope records for every leaf: ropes pass from parent to children (the
/// sibling becomes the rope across the split face), then each is pushed
/// down while the neighbour's split either runs parallel to the face (take
/// the child touching it) or leaves the whole face on one side.
fn rope_leaves(nodes: &[KdNode], cells: &[Aabb]) -> (Vec<KdNode>, Vec<LeafRecord>) {
    let mut out = nodes.to_vec();
    let mut leaves = Vec::new();
    let mut stack = vec![(0u32, [NONE; 6])];
    while let Some((i, ropes)) = stack.pop() {
        let n = nodes[i as usize];
        if n.is_leaf() {
            let cell = cells[i as usize];
            let ropes = std::array::from_fn(|f| push_down(nodes, ropes[f], f, &cell));
            out[i as usize] = KdNode::leaf(leaves.len() as u32, n.count() as u32);
            leaves.push(LeafRecord {
                cell,
                ropes,
                first: n.first() as u32,
                count: n.count() as u32,
            });
        } else {
            let (a, c) = (n.axis(), n.first_child());
            let mut below = ropes;
            below[2 * a + 1] = c + 1;
            let mut above = ropes;
            above[2 * a] = c;
            stack.push((c, below));
            stack.push((c + 1, above));
        }
    }
    (out, leaves)
}

/// Popov et al.'s rope optimisation for face `face` of a leaf with `cell`.
fn push_down(nodes: &[KdNode], mut rope: u32, face: usize, cell: &Aabb) -> u32 {
    let (fa, up) = (face / 2, face & 1 == 1);
    while rope != NONE {
        let n = nodes[rope as usize];
        if n.is_leaf() {
            break;
        }
        let (a, s, c) = (n.axis(), n.split(), n.first_child());
        rope = if a == fa {
            // Parallel to the face: the child next to it.
            if up {
                c
            } else {
                c + 1
            }
        } else if cell.max[a] <= s {
            c
        } else if cell.min[a] >= s {
            c + 1
        } else {
            break;
        };
    }
    rope
}

kd_accel!(KdRopes, self => std::mem::size_of_val(&self.nodes[..]) + std::mem::size_of_val(&self.leaves[..]));
