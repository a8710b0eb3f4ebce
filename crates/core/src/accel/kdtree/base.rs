//! What every kd-tree traversal shares: the compact nodes, the
//! triangle-index list, the precomputed triangles and the root cell.

use super::layout::{layout, KdNode};
use super::tree::{split_cell, KdBuildNode, TreeShape};
use super::{game, median, sah, KdOptions, KdSplit, TriangleSet};
use crate::aabb::Aabb;
use crate::accel::leaf::LeafTriangles;
use crate::accel::node_box::NodeBox;
use crate::accel::AccelStats;
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::TriangleTest;
use serde::Serialize;
use std::time::Instant;

/// How a kd-tree was built.
#[derive(Clone, Debug, Serialize)]
pub struct KdBuildInfo {
    /// Split rule (`sah`, `median`, `game:H`).
    pub split: String,
    /// Wall-clock build time of the tree (seconds), without the triangle
    /// precomputation and the layout.
    pub build_seconds: f64,
    /// Triangles cut by at least one split plane (the game build's "split
    /// polygons"; for the others, triangles referenced by several leaves).
    pub split_triangles: usize,
    /// Empty leaves.
    pub empty_leaves: usize,
}

/// A kd-tree in the compact GPU layout: 8-byte nodes breadth-first, leaves
/// pointing into one triangle-index list, triangles precomputed once each
/// for the test `T`. The traversals ([`super::KdStack`], [`super::KdRopes`],
/// [`super::KdRestart`], [`super::KdBacktrack`]) wrap it.
pub struct KdTree<T: TriangleTest> {
    pub(crate) nodes: Vec<KdNode>,
    pub(crate) indices: Vec<u32>,
    pub(crate) root_cell: Aabb,
    pub(crate) tris: LeafTriangles<T>,
    pub(crate) shape: TreeShape,
    pub(crate) info: KdBuildInfo,
}

/// Build the pointer tree with the rule in `opts`; returns it with its root
/// cell.
pub fn build_tree(mesh: &TriangleMesh, opts: &KdOptions) -> (KdBuildNode, Aabb) {
    let set = TriangleSet::new(mesh);
    let cell = set.root_cell();
    let root = if set.ids.is_empty() {
        KdBuildNode::Leaf(Vec::new())
    } else {
        match opts.split {
            KdSplit::Sah => sah::build(&set, &cell, opts),
            KdSplit::Median => median::build(&set, &cell, opts),
            KdSplit::Game(h) => game::build(&set, &cell, h, opts).0,
        }
    };
    (root, cell)
}

impl<T: TriangleTest> KdTree<T> {
    /// Build over all triangles of `mesh`.
    pub fn build(mesh: &TriangleMesh, opts: &KdOptions) -> Self {
        let start = Instant::now();
        let (root, cell) = build_tree(mesh, opts);
        Self::from_build(mesh, &root, &cell, opts, start.elapsed().as_secs_f64())
    }

    /// Lay out a pointer tree built over `mesh` (see [`build_tree`]), so that
    /// several traversals can share one build.
    ///
    /// The triangles are precomputed in the order the leaves first list them
    /// (depth first), so that a leaf's triangles and its neighbours' lie
    /// close together in memory.
    pub fn from_build(
        mesh: &TriangleMesh,
        root: &KdBuildNode,
        cell: &Aabb,
        opts: &KdOptions,
        build_seconds: f64,
    ) -> Self {
        let shape = root.shape(cell, opts.traversal_cost as f64);
        let split_triangles = count_split(root, mesh.num_triangles());
        let lay = layout(root, cell, opts.subtree_levels);
        let (order, position) = first_use_order(root, mesh.num_triangles());
        let indices = lay.indices.iter().map(|&t| position[t as usize]).collect();
        let tris = LeafTriangles::new(mesh, order);
        let info = KdBuildInfo {
            split: opts.split.name(),
            build_seconds,
            split_triangles,
            empty_leaves: shape.empty_leaves,
        };
        KdTree {
            nodes: lay.nodes,
            indices,
            root_cell: *cell,
            tris,
            shape,
            info,
        }
    }

    /// Per node its cell and its parent (`u32::MAX` for the root), from the
    /// split planes; in breadth-first order a parent precedes its children.
    pub(crate) fn cells_and_parents(&self) -> (Vec<Aabb>, Vec<u32>) {
        let n = self.nodes.len();
        let mut cells = vec![self.root_cell; n];
        let mut parents = vec![u32::MAX; n];
        for i in 0..n {
            let node = self.nodes[i];
            if !node.is_leaf() {
                let c = node.first_child() as usize;
                let halves = split_cell(&cells[i], node.axis(), node.split());
                cells[c] = halves[0];
                cells[c + 1] = halves[1];
                parents[c] = i as u32;
                parents[c + 1] = i as u32;
            }
        }
        (cells, parents)
    }

    /// The tree as flat arrays for devices with kernels of their own.
    pub fn flat(&self) -> crate::accel::FlatKdTree {
        crate::accel::FlatKdTree {
            nodes: self.nodes.iter().flat_map(|n| n.words()).collect(),
            indices: self.indices.clone(),
            root_min: self.root_cell.min.to_array(),
            root_max: self.root_cell.max.to_array(),
            depth: self.shape.depth,
            tris: self.tris.flat(),
        }
    }

    /// How the tree was built.
    pub fn info(&self) -> &KdBuildInfo {
        &self.info
    }

    /// Stats with `extra_bytes` of traversal-specific data added.
    pub(crate) fn stats_with(&self, extra_bytes: usize) -> AccelStats {
        let node_bytes = std::mem::size_of_val(&self.nodes[..]);
        // (`nodes` is empty when a traversal keeps its own copy and counts it
        // in `extra_bytes`.)
        AccelStats {
            nodes: self.shape.nodes,
            leaves: self.shape.leaves,
            bytes: node_bytes + self.indices.len() * 4 + self.tris.bytes() + extra_bytes,
            node_bytes: node_bytes + extra_bytes,
            depth: self.shape.depth,
            sah_cost: self.shape.sah_cost,
            triangle_refs: self.indices.len(),
        }
    }

    /// The ray's interval inside the root cell, within `[tnear, tfar]`.
    #[inline(always)]
    pub(crate) fn clip_root(&self, ray: &Ray) -> Option<(f32, f32)> {
        if self.indices.is_empty() {
            return None;
        }
        slab(&self.root_cell, ray, ray.tnear, ray.tfar)
    }

    /// Test the triangles of `leaf`.
    #[inline(always)]
    pub(crate) fn test_leaf<const ANY: bool>(
        &self,
        leaf: KdNode,
        ray: &Ray,
        rd: &T::RayData,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        let list = &self.indices[leaf.first()..leaf.first() + leaf.count()];
        self.tris.test_indexed::<ANY>(list, ray, rd, tfar, best)
    }

    /// Visit cells and leaves for [`crate::accel::Accel::visit_regions`],
    /// with the cells recomputed from the split planes.
    pub(crate) fn visit(&self, enter: &mut dyn FnMut(&Aabb) -> bool, leaf: &mut dyn FnMut(&[u32])) {
        let range = |n: KdNode| (n.first(), n.count());
        self.visit_nodes(&self.nodes, &range, enter, leaf)
    }

    /// [`KdTree::visit`] over a copy of the nodes whose leaves `range` maps
    /// to their entries in the triangle-index list.
    pub(crate) fn visit_nodes(
        &self,
        nodes: &[KdNode],
        range: &dyn Fn(KdNode) -> (usize, usize),
        enter: &mut dyn FnMut(&Aabb) -> bool,
        leaf: &mut dyn FnMut(&[u32]),
    ) {
        if self.indices.is_empty() {
            return;
        }
        let mut stack = vec![(0u32, self.root_cell)];
        let mut prims = Vec::new();
        while let Some((i, cell)) = stack.pop() {
            if !enter(&cell) {
                continue;
            }
            let n = nodes[i as usize];
            if n.is_leaf() {
                let (first, count) = range(n);
                prims.clear();
                prims.extend(
                    self.indices[first..first + count]
                        .iter()
                        .map(|&i| self.tris.prim(i as usize)),
                );
                leaf(&prims);
            } else {
                let [l, r] = split_cell(&cell, n.axis(), n.split());
                stack.push((n.first_child() + 1, r));
                stack.push((n.first_child(), l));
            }
        }
    }
}

/// Ray interval inside `cell` within `[tnear, tfar]`: the slab test with
/// the exit widened past its rounding as in [`NodeBox::entry`], and NaNs
/// from `0 · inf` (origin on a slab plane of an axis-parallel ray) ignored.
#[inline(always)]
pub(crate) fn slab(cell: &Aabb, ray: &Ray, tnear: f32, tfar: f32) -> Option<(f32, f32)> {
    let mut enter = tnear;
    let mut exit = f32::INFINITY;
    for a in 0..3 {
        let t0 = (cell.min[a] - ray.origin[a]) * ray.inv_dir[a];
        let t1 = (cell.max[a] - ray.origin[a]) * ray.inv_dir[a];
        enter = enter.max(t0.min(t1));
        exit = exit.min(t0.max(t1));
    }
    let exit = (exit * NodeBox::ROBUST_EXIT).min(tfar);
    (enter <= exit).then_some((enter, exit))
}

/// Triangles listed by more than one leaf.
fn count_split(root: &KdBuildNode, n: usize) -> usize {
    let mut seen = vec![0u8; n];
    let mut stack = vec![root];
    while let Some(node) = stack.pop() {
        match node {
            KdBuildNode::Leaf(tris) => {
                for &t in tris {
                    seen[t as usize] = seen[t as usize].saturating_add(1);
                }
            }
            KdBuildNode::Inner { children, .. } => stack.extend(children.iter()),
        }
    }
    seen.iter().filter(|&&c| c > 1).count()
}

/// Triangles in the order the leaves first list them, depth first, and
/// each triangle's position in that order.
fn first_use_order(root: &KdBuildNode, n: usize) -> (Vec<u32>, Vec<u32>) {
    let mut position = vec![u32::MAX; n];
    let mut order = Vec::new();
    let mut stack = vec![root];
    while let Some(node) = stack.pop() {
        match node {
            KdBuildNode::Leaf(tris) => {
                for &t in tris {
                    if position[t as usize] == u32::MAX {
                        position[t as usize] = order.len() as u32;
                        order.push(t);
                    }
                }
            }
            KdBuildNode::Inner { children, .. } => {
                stack.push(&children[1]);
                stack.push(&children[0]);
            }
        }
    }
    (order, position)
}
