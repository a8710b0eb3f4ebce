//! [`PointTree`]: the 8-wide BVH behind a [`super::SurfaceBvh`]'s point
//! queries (closest point, distance, winding number), made on the first
//! point query.
//!
//! It is made by the same binned-SAH build as [`crate::accel::Bvh8`]
//! (module `accel::bvh::build`), collapsed into nodes of up to eight
//! children the same way (the largest-area inner child's children pulled
//! up first), with the children's boxes in structure-of-arrays layout so
//! that one query point is tested against all eight at once (the loops
//! over the eight lanes compile to SIMD). Unlike the ray-casting tree's
//! leaves (packs of precomputed Möller data), its leaves keep the
//! triangles' corners, which the closest-point and solid-angle kernels
//! need, and every child slot keeps the range of triangles below it, from
//! which the winding-number moments are made ([`super::winding`]). The
//! closest-point search reads the leaves' corners from their copy in
//! structure of arrays ([`CornerGroups`]).

use super::corner_groups::CornerGroups;
use super::moments::Moments;
use super::surface_node::{SurfaceNode, EMPTY, WIDTH};
use crate::aabb::Aabb;
use crate::accel::bvh::{build, BoxPath, BuildNode, BuildOptions};
use crate::mesh::TriangleMesh;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::OnceLock;

/// The point queries' tree of a surface, at the surface's scale. The root
/// is node 0 (a mesh of one leaf gets a root node with that leaf as its
/// only child); an empty mesh has no nodes.
pub(crate) struct PointTree {
    pub(crate) nodes: Vec<SurfaceNode>,
    /// Corners of the triangles in leaf order.
    pub(crate) tris: Vec<[Vec3; 3]>,
    /// Mesh triangle index of each triangle in leaf order.
    pub(crate) prims: Vec<u32>,
    /// The leaves' corners in groups for the closest-point kernel; a leaf
    /// slot's `child` is its first group.
    pub(crate) groups: CornerGroups,
    /// The instruction set the closest-point search is compiled for,
    /// detected once at build.
    pub(crate) path: BoxPath,
    /// Most traversal stack entries a query can need (each inner node
    /// visited pushes at most eight and pops one).
    pub(crate) stack_need: usize,
    /// Winding-number moments, made on first use.
    pub(crate) moments: OnceLock<Moments>,
}

impl PointTree {
    /// Build over all triangles of `mesh` (already at the surface's scale):
    /// the binned SAH or linear BVH that `options.quality` names, leaves of
    /// up to `options.max_leaf_size`.
    pub(crate) fn build(mesh: &TriangleMesh, options: &BuildOptions) -> Self {
        let tree = build::build(mesh, options);
        let tris: Vec<[Vec3; 3]> = tree
            .order
            .par_iter()
            .map(|&t| mesh.triangle(t as usize))
            .collect();
        let mut points = PointTree {
            nodes: Vec::new(),
            tris,
            prims: tree.order,
            groups: CornerGroups::default(),
            path: BoxPath::detect(),
            stack_need: 1,
            moments: OnceLock::new(),
        };
        if !points.prims.is_empty() {
            points.nodes.push(SurfaceNode::default());
            let depth = fill(&mut points.nodes, 0, &root_slots(&tree.root), PAR_LEVELS);
            points.stack_need = stack_need(depth);
            points.groups = CornerGroups::build(&mut points.nodes, &points.tris);
        }
        points
    }

    /// The winding-number moments of every node; made on first use.
    pub(crate) fn moments(&self) -> &Moments {
        self.moments
            .get_or_init(|| Moments::build(&self.nodes, &self.tris))
    }

    /// Bytes held: nodes, corners (and their groups), triangle indices and
    /// the moments where they have been made.
    pub(crate) fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<SurfaceNode>()
            + self.tris.len() * (std::mem::size_of::<[Vec3; 3]>() + std::mem::size_of::<u32>())
            + self.groups.bytes()
            + self.moments.get().map_or(0, Moments::bytes)
    }
}

/// The levels of wide nodes below the root whose subtrees are made in
/// parallel: each inner child's subtree on its own, appended in slot order.
const PAR_LEVELS: u32 = 2;

/// Fill node `at` of `nodes` with `slots` as children, making their inner
/// nodes after it (each node's inner children after it, so moments can be
/// made children first by walking the nodes backwards); returns the number
/// of inner levels from `at` down (1 for a node of leaves). For `par`
/// levels, each inner child's subtree is made on its own in parallel and
/// appended in slot order, its references moved by its place; the tree
/// does not depend on the number of threads.
fn fill(nodes: &mut Vec<SurfaceNode>, at: usize, slots: &[&BuildNode], par: u32) -> usize {
    let mut node = SurfaceNode::default();
    let mut inner = Vec::new();
    for (k, s) in slots.iter().enumerate() {
        set_slot_box(&mut node.min, &mut node.max, k, &s.bounds());
        let (first, total) = s.triangle_range();
        node.first[k] = first;
        node.total[k] = total;
        match s {
            BuildNode::Leaf { first, count, .. } => {
                node.child[k] = *first;
                node.count[k] = (*count).max(1);
                if *count == 0 {
                    node.child[k] = EMPTY;
                    node.count[k] = 0;
                }
            }
            BuildNode::Inner { .. } if par == 0 => {
                node.child[k] = nodes.len() as u32;
                nodes.push(SurfaceNode::default());
                inner.push((nodes.len() - 1, *s));
            }
            BuildNode::Inner { .. } => inner.push((k, *s)),
        }
    }
    let mut depth = 1;
    if par == 0 {
        nodes[at] = node;
        for (idx, s) in inner {
            depth = depth.max(1 + fill(nodes, idx, &widen(s), 0));
        }
        return depth;
    }
    let subtrees: Vec<(Vec<SurfaceNode>, usize)> = inner
        .par_iter()
        .map(|(_, s)| {
            let mut sub = vec![SurfaceNode::default()];
            let d = fill(&mut sub, 0, &widen(s), par - 1);
            (sub, d)
        })
        .collect();
    for ((k, _), (mut sub, d)) in inner.iter().zip(subtrees) {
        let offset = nodes.len() as u32;
        for n in &mut sub {
            for c in 0..WIDTH {
                if n.count[c] == 0 && n.child[c] != EMPTY {
                    n.child[c] += offset;
                }
            }
        }
        node.child[*k] = offset;
        nodes.append(&mut sub);
        depth = depth.max(1 + d);
    }
    nodes[at] = node;
    depth
}

/// The children of a wide root: the tree's one leaf, or the root widened.
pub(crate) fn root_slots(root: &BuildNode) -> Vec<&BuildNode> {
    match root {
        BuildNode::Leaf { .. } => vec![root],
        BuildNode::Inner { .. } => widen(root),
    }
}

/// The most traversal stack entries a walk of a wide tree `depth` inner
/// levels deep can need: each inner node visited pushes at most eight and
/// pops one.
pub(crate) fn stack_need(depth: usize) -> usize {
    (WIDTH - 1) * depth + WIDTH + 1
}

/// Store box `b` as slot `k` of a wide node's boxes in structure of
/// arrays.
pub(crate) fn set_slot_box(
    min: &mut [[f32; WIDTH]; 3],
    max: &mut [[f32; WIDTH]; 3],
    k: usize,
    b: &Aabb,
) {
    for a in 0..3 {
        min[a][k] = b.min[a];
        max[a][k] = b.max[a];
    }
}

/// The up to eight nodes that replace the inner node `node`: its two
/// children, then repeatedly the inner one of largest surface area replaced
/// by its own two children, as the wide collapse of the ray-casting BVHs.
pub(crate) fn widen(node: &BuildNode) -> Vec<&BuildNode> {
    let BuildNode::Inner { children, .. } = node else {
        return vec![node];
    };
    let mut slots: Vec<&BuildNode> = vec![&children[0], &children[1]];
    while slots.len() < WIDTH {
        let pick = slots
            .iter()
            .enumerate()
            .filter(|(_, s)| matches!(s, BuildNode::Inner { .. }))
            .max_by(|a, b| {
                a.1.bounds()
                    .surface_area()
                    .total_cmp(&b.1.bounds().surface_area())
            })
            .map(|(i, _)| i);
        let Some(i) = pick else { break };
        let BuildNode::Inner { children, .. } = slots[i] else {
            break;
        };
        slots[i] = &children[0];
        slots.push(&children[1]);
    }
    slots
}

#[cfg(test)]
mod tests {
    use super::super::corner_groups::LANES;
    use super::*;
    use crate::rng::Pcg32;

    #[test]
    fn every_triangle_sits_in_exactly_one_leaf_inside_its_boxes() {
        let mut rng = Pcg32::new(3);
        let mut pos = Vec::new();
        let mut idx = Vec::new();
        for i in 0..3000u32 {
            let c = rng.in_box(Vec3::ZERO, Vec3::ONE);
            for _ in 0..3 {
                pos.push(c + rng.unit_vector() * 0.01);
            }
            idx.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        let mesh = TriangleMesh::new(pos, idx);
        let bvh = PointTree::build(&mesh, &BuildOptions::default());
        let mut seen = vec![0u32; mesh.num_triangles()];
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &bvh.nodes[n];
            for k in 0..WIDTH {
                if node.child[k] == EMPTY {
                    continue;
                }
                let lo = Vec3::new(node.min[0][k], node.min[1][k], node.min[2][k]);
                let hi = Vec3::new(node.max[0][k], node.max[1][k], node.max[2][k]);
                let r = node.first[k] as usize..(node.first[k] + node.total[k]) as usize;
                for t in r.clone() {
                    for v in bvh.tris[t] {
                        assert!(v.cmpge(lo).all() && v.cmple(hi).all());
                    }
                }
                if node.count[k] > 0 {
                    assert_eq!(node.count[k] as usize, r.len());
                    let g = node.child[k] as usize;
                    for (i, t) in r.clone().enumerate() {
                        let (group, lane) = (g + i / LANES, i % LANES);
                        assert_eq!(bvh.groups.first[group] as usize, t - i % LANES);
                        let c = &bvh.groups.corners[group];
                        for (j, v) in bvh.tris[t].iter().enumerate() {
                            assert_eq!(*v, Vec3::new(c[j][0][lane], c[j][1][lane], c[j][2][lane]));
                        }
                    }
                    for t in r {
                        seen[bvh.prims[t] as usize] += 1;
                        assert_eq!(bvh.tris[t], mesh.triangle(bvh.prims[t] as usize));
                    }
                } else {
                    stack.push(node.child[k] as usize);
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
    }
}
