//! The boxes a wide BVH ([`super::Bvh4`], [`super::Bvh8`]) stores: each the
//! union of the tolerance bands of the triangles below it
//! ([`TriangleTest::reach`]), fitted bottom-up over the finished tree,
//! after a build and after a refit.
//!
//! The triangle tests report hits up to a small fraction of a triangle
//! beyond its edges (`tri::MAX_EDGE_TOLERANCE`), so a box must hold that
//! band of each of its triangles for box culling never to lose a hit.
//! Padding each box by that fraction of its own extent, as the binary BVH
//! does, holds it too, but grows with the box: high in the tree a node's
//! box gains a margin many times its triangles' bands, and rays enter
//! boxes they cannot hit anything in. The union of the triangles' own
//! bands is the tightest box that holds them all, as Embree's boxes hold
//! exactly their primitives (Wald et al. 2014).

use super::wide_node::{Child4, WideSlots};
use crate::aabb::Aabb;
use crate::accel::node_box::NodeBox;
use crate::mesh::TriangleMesh;
use crate::tri::TriangleTest;
use rayon::prelude::*;

/// The reach of a tree's leaf units, in leaf order: one box per pack of
/// four (`per_unit` 4) or per triangle (`per_unit` 1).
pub(crate) struct UnitReach {
    pub bounds: Vec<Aabb>,
    pub per_unit: usize,
}

/// The reach of triangle `prim` of `mesh` under the test `T`.
#[inline]
fn triangle_reach<T: TriangleTest>(mesh: &TriangleMesh, prim: u32) -> Aabb {
    let [a, b, c] = mesh.triangle(prim as usize);
    T::reach(a, b, c)
}

/// The reach of each triangle of `prims` (one-triangle leaves, in leaf
/// order) over `mesh`, in parallel; packed leaves take their packs' reach
/// while packing (`Tri4Leaves::from_refs`, the refit).
pub(crate) fn triangle_units<T: TriangleTest>(prims: &[u32], mesh: &TriangleMesh) -> UnitReach {
    let mut bounds = Vec::new();
    prims
        .par_iter()
        .with_min_len(4096)
        .map(|&prim| triangle_reach::<T>(mesh, prim))
        .collect_into_vec(&mut bounds);
    UnitReach {
        bounds,
        per_unit: 1,
    }
}

/// Store in every slot of `nodes` and in `root_box` the union of the reach
/// of the units below it, from the last node to the first: nodes are in
/// pre-order (a child after its parent; built trees are, loaded ones are
/// checked), so every child's box is known when its parent's slots are
/// written. Returns the SAH cost of the new boxes relative to the root's
/// (traversal and triangle tests cost 1).
pub(crate) fn fit_boxes<N: WideSlots>(
    nodes: &mut [N],
    root: Child4,
    root_box: &mut NodeBox,
    units: &UnitReach,
) -> f64 {
    let leaf_bounds = |c: Child4| {
        let first = c.index as usize;
        let count = (c.count as usize).div_ceil(units.per_unit);
        units.bounds[first..first + count]
            .iter()
            .fold(Aabb::EMPTY, |a, &b| a.union(b))
    };
    let area = |b: &Aabb| b.surface_area() as f64;
    let mut bounds = vec![Aabb::EMPTY; nodes.len()];
    let mut sah = 0.0;
    for i in (0..nodes.len()).rev() {
        let node = &mut nodes[i];
        let mut nb = Aabb::EMPTY;
        for slot in 0..N::WIDTH {
            let c = node.children_mut()[slot];
            if c == Child4::EMPTY {
                continue;
            }
            let cb = if c.count > 0 {
                let b = leaf_bounds(c);
                sah += area(&b) * c.count as f64;
                b
            } else {
                debug_assert!(c.index as usize > i, "nodes in pre-order");
                bounds[c.index as usize]
            };
            node.set_slot(slot, &NodeBox::exact(cb), c);
            nb = nb.union(cb);
        }
        sah += area(&nb);
        bounds[i] = nb;
    }
    let rb = if root.count > 0 {
        let b = leaf_bounds(root);
        sah += area(&b) * root.count as f64;
        b
    } else if root == Child4::EMPTY || nodes.is_empty() {
        Aabb::EMPTY
    } else {
        bounds[root.index as usize]
    };
    *root_box = NodeBox::exact(rb);
    sah / area(&rb).max(f64::MIN_POSITIVE)
}
