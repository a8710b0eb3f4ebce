//! The build shared by the wide BVHs ([`super::Bvh4`],
//! [`super::Bvh8`]): the binned SAH making wide nodes directly
//! ([`super::wide_build`]), or the linear BVH's binary tree
//! ([`super::build::lbvh`]) collapsed into wide nodes ([`super::collapse`]); the
//! leaves packed four triangles at a time over Möller (Embree's
//! `triangle4`, Wald et al. 2014) or kept one triangle after the other for
//! the other tests; the boxes fitted to their triangles' reach
//! ([`super::fit`]); and the shape figures of the wide tree.

use super::build::{build, clamped, BuildNode, BuildOptions, BuildQuality, BuildTree};
use super::collapse::collapse;
use super::fit::{fit_boxes, triangle_units, UnitReach};
use super::tri4::{Tri4Leaves, Unhittable};
use super::wide_build::build_direct;
use super::wide_leaf::{wide_build_options, Leaves};
use super::wide_node::Child4;
use super::wide_node::WideSlots;
use crate::accel::leaf::LeafTriangles;
use crate::accel::node_box::NodeBox;
use crate::accel::AccelStats;
use crate::mesh::TriangleMesh;
use crate::tri::TriangleTest;
use rayon::prelude::*;

/// A wide tree ready for traversal.
pub(crate) struct WideTree<N, T: TriangleTest> {
    pub nodes: Vec<N>,
    pub root_box: NodeBox,
    pub root: Child4,
    pub leaves: Leaves<T>,
    /// Shape figures of the wide tree (nodes, leaves, depth and SAH cost as
    /// collapsed; bytes of nodes and leaves).
    pub stats: AccelStats,
    /// Most traversal stack entries a ray can need.
    pub stack: usize,
}

/// Build the wide tree of `N` nodes over the triangles of `mesh`: with
/// packed leaves and `leave_out`, those a ray can hit (see
/// [`Unhittable`]), else all.
pub(crate) fn build_wide<N: WideSlots, T: TriangleTest>(
    mesh: &TriangleMesh,
    options: &BuildOptions,
    leave_out: bool,
) -> WideTree<N, T> {
    let packed = T::PACKS_OF_FOUR;
    let options = &wide_build_options(options, packed);
    // Packs leave out the triangles no ray can hit: the tree is built over
    // the others (sharing the vertices), its order then naming the mesh's
    // triangles again.
    let unhittable = if packed && leave_out {
        Unhittable::of_mesh(mesh)
    } else {
        Unhittable::none()
    };
    let kept = (!unhittable.prims.is_empty()).then(|| unhittable.kept(mesh.num_triangles()));
    let hittable = kept.as_ref().map(|kept| {
        TriangleMesh::new(
            mesh.positions.clone(),
            kept.iter().map(|&i| mesh.indices[i as usize]).collect(),
        )
    });
    let tree_mesh = hittable.as_ref().unwrap_or(mesh);
    // The SAH builds make the wide nodes directly; the linear BVH is
    // collapsed from its binary tree, which is freed while the leaves are
    // made (on one thread it took 6-7 ms of the 1M-triangle terrain's
    // build).
    // Their boxes, padded by each box's own extent, are replaced by the
    // tighter unions of the triangles' reach once the leaves are made.
    let (mut wide, mut order, binary) = match options.quality {
        BuildQuality::Sah | BuildQuality::High => {
            let (wide, _, order) = build_direct::<N>(tree_mesh, &clamped(options));
            (wide, order, None)
        }
        BuildQuality::Fast => {
            let BuildTree { root, order } = build(tree_mesh, options);
            let wide = collapse::<N>(&root, options.traversal_cost as f64);
            (wide, order, Some(root))
        }
    };
    drop(hittable);
    if let Some(kept) = &kept {
        order.par_iter_mut().for_each(|p| *p = kept[*p as usize]);
    }
    let mut root_box = NodeBox::default();
    let node_bytes = std::mem::size_of_val(&wide.nodes[..]);
    let triangle_refs = order.len();
    let (_, (leaves, units)) = rayon::join(
        || binary.map(|root| free(root, 0)),
        || {
            if packed {
                let refs = std::iter::once(&mut wide.root).chain(
                    wide.nodes
                        .iter_mut()
                        .flat_map(|n| n.children_mut().iter_mut()),
                );
                let (mut packs, bounds) = Tri4Leaves::from_refs(mesh, &order, refs);
                packs.unhittable = unhittable;
                let units = UnitReach {
                    bounds,
                    per_unit: 4,
                };
                (Leaves::Packed(packs), units)
            } else {
                let tris = LeafTriangles::new(mesh, order);
                let units = triangle_units::<T>(tris.prims(0, tris.len()), mesh);
                (Leaves::Single(tris), units)
            }
        },
    );
    fit_boxes(&mut wide.nodes, wide.root, &mut root_box, &units);
    let leaf_bytes = match &leaves {
        Leaves::Packed(p) => p.bytes(),
        Leaves::Single(t) => t.bytes(),
    };
    let stats = AccelStats {
        nodes: wide.inner + wide.leaves,
        leaves: wide.leaves,
        bytes: node_bytes + leaf_bytes,
        node_bytes,
        depth: wide.depth,
        sah_cost: wide.sah_cost,
        triangle_refs,
    };
    WideTree {
        nodes: wide.nodes,
        root_box,
        root: wide.root,
        leaves,
        stats,
        stack: wide.stack,
    }
}

/// Free the binary tree below `node`, its top levels in parallel.
fn free(node: BuildNode, depth: u32) {
    if let BuildNode::Inner { children, .. } = node {
        let [a, b] = *children;
        if depth < 8 {
            rayon::join(|| free(a, depth + 1), || free(b, depth + 1));
        } else {
            drop((a, b));
        }
    }
}
