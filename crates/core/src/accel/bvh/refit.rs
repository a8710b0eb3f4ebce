//! Refit of a wide BVH ([`super::Bvh4`], [`super::Bvh8`]) to moved vertices:
//! the topology (nodes, leaves, triangle order) is kept and every box is
//! recomputed bottom-up in one pass over the tree, O(n), as Embree's refit
//! of a BVH over deforming geometry (`RTC_BUILD_QUALITY_REFIT`; Wald,
//! Boulos and Shirley 2007, "Ray tracing deformable scenes using dynamic
//! bounding volume hierarchies", for the refit and its degradation).
//!
//! A refit tree answers every query exactly (its boxes contain its
//! triangles as a fresh build's do), but its boxes may overlap more than a
//! fresh build's, so rays visit more nodes. The quality measure is the
//! surface area heuristic cost of the stored (padded) boxes, relative to
//! the root box, with traversal and triangle costs 1 ([`stored_sah`]);
//! [`RefitReport::degradation`] is its ratio to the cost of the tree as
//! built, and [`WideBvh::refit_or_rebuild`] rebuilds once it passes a limit
//! ([`super::DEFAULT_MAX_DEGRADATION`]).

use super::fit::{fit_boxes, triangle_units, UnitReach};
use super::node_width::NodeWidth;
use super::refit_report::{RefitError, RefitReport};
use super::tri4::Unhittable;
use super::wide_bvh::WideBvh;
use super::wide_leaf::Leaves;
use super::wide_node::Child4;
use super::wide_parts::{PartsMut, PartsRef, WideNode, WideParts};
use super::BuildOptions;
use crate::aabb::Aabb;
use crate::mesh::TriangleMesh;
use crate::tri::TriangleTest;
use rayon::prelude::*;

/// The SAH cost of a wide tree from its stored (padded) boxes, relative to
/// the root box: `sum_inner SA(n)/SA(root) + sum_leaf SA(n)/SA(root) *
/// n_tris`. Used for the tree as built and the refit tree alike.
pub(crate) fn stored_sah<N: WideNode, T: TriangleTest>(p: &PartsRef<'_, N, T>) -> f64 {
    let area = |b: Aabb| b.surface_area() as f64;
    let root = area(Aabb::new(p.root_box.min.into(), p.root_box.max.into()));
    let mut sum = if p.root.count > 0 {
        root * p.root.count as f64
    } else {
        root
    };
    for node in p.nodes {
        for (slot, c) in node.children().iter().enumerate() {
            if *c == Child4::EMPTY {
                continue;
            }
            let cost = if c.count > 0 { c.count as f64 } else { 1.0 };
            sum += area(node.slot_box(slot)) * cost;
        }
    }
    sum / root.max(f64::MIN_POSITIVE)
}

/// Refit `bvh` to `mesh` (see the module docs).
pub(crate) fn refit<B: WideParts>(
    bvh: &mut B,
    mesh: &TriangleMesh,
) -> Result<RefitReport, RefitError> {
    let tree = bvh.parts().stats.triangle_refs + left_out(bvh.parts().leaves);
    check_mesh(mesh, tree)?;
    let built_sah = match bvh.parts().built_sah {
        Some(s) => s,
        None => stored_sah(&bvh.parts()),
    };
    let p = bvh.parts_mut();
    *p.built_sah = Some(built_sah);
    refit_parts(p, mesh);
    let sah = stored_sah(&bvh.parts());
    Ok(RefitReport {
        built_sah,
        sah,
        refit_sah: sah,
        rebuilt: false,
    })
}

/// Triangles of the mesh that `leaves` leave out ([`Unhittable`]).
pub(super) fn left_out<T: TriangleTest>(leaves: &Leaves<T>) -> usize {
    match leaves {
        Leaves::Packed(p) => p.unhittable.prims.len(),
        Leaves::Single(_) => 0,
    }
}

/// The mesh has the tree's triangle count and every index is in range.
pub(super) fn check_mesh(mesh: &TriangleMesh, tree: usize) -> Result<(), RefitError> {
    if mesh.num_triangles() != tree {
        return Err(RefitError::TriangleCount {
            tree,
            mesh: mesh.num_triangles(),
        });
    }
    let vertices = mesh.positions.len();
    // The largest index, a reduction the compiler vectorises; the bad
    // triangle is looked for only when there is one.
    let largest = mesh
        .indices
        .par_chunks(1 << 14)
        .map(|c| c.iter().fold(0u32, |m, t| m.max(t[0]).max(t[1]).max(t[2])))
        .max();
    if largest.is_none_or(|m| (m as usize) < vertices) {
        return Ok(());
    }
    let (triangle, t) = mesh
        .indices
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&i| i as usize >= vertices))
        .expect("a triangle holds the largest index");
    Err(RefitError::VertexIndex {
        triangle,
        index: *t
            .iter()
            .find(|&&i| i as usize >= vertices)
            .expect("a bad index"),
        vertices,
    })
}

/// The leaves' triangles recomputed from `mesh` (in parallel, with each
/// pack's reach), then every box fitted to them ([`fit_boxes`]).
fn refit_parts<N: WideNode, T: TriangleTest>(p: PartsMut<'_, N, T>, mesh: &TriangleMesh) {
    let units = match &mut *p.leaves {
        Leaves::Packed(packs) => {
            let mut bounds = Vec::new();
            packs
                .packs_mut()
                .par_iter_mut()
                .with_min_len(1024)
                .map(|pack| pack.reload(mesh))
                .collect_into_vec(&mut bounds);
            let prims = std::mem::take(&mut packs.unhittable.prims);
            packs.unhittable = Unhittable::with_prims(prims, mesh);
            UnitReach {
                bounds,
                per_unit: 4,
            }
        }
        Leaves::Single(leaf_tris) => {
            leaf_tris.recompute(mesh);
            triangle_units::<T>(leaf_tris.prims(0, leaf_tris.len()), mesh)
        }
    };
    p.stats.sah_cost = fit_boxes(p.nodes, p.root, p.root_box, &units);
}

impl<N: NodeWidth, T: TriangleTest> WideBvh<N, T> {
    /// Refit the tree to `mesh`: the mesh it was built over (same
    /// triangles, same vertex indices) with moved vertices. Every
    /// box is recomputed bottom-up in O(n) and the topology kept
    /// (Embree's refit); the answers are exact as after a build,
    /// the speed may degrade ([`RefitReport::degradation`]).
    ///
    /// The triangles that packed leaves leave out because no ray can hit
    /// them ([`super::tri4::Unhittable`]) stay out while they have no
    /// area; when one has gained area, the tree is built again with the
    /// default options instead (`rebuilt` in the report).
    pub fn refit(&mut self, mesh: &TriangleMesh) -> Result<RefitReport, RefitError> {
        self.refit_or_rebuild(mesh, &BuildOptions::default(), f64::INFINITY)
    }

    /// Refit the tree to `mesh` as [`Self::refit`], and rebuild it
    /// with `options` when the refit tree's SAH cost is more than
    /// `max_degradation` times the built tree's (see
    /// [`super::DEFAULT_MAX_DEGRADATION`]) or when a triangle the packed
    /// leaves left out has gained area; the rebuilt tree is the new
    /// reference for later refits.
    pub fn refit_or_rebuild(
        &mut self,
        mesh: &TriangleMesh,
        options: &BuildOptions,
        max_degradation: f64,
    ) -> Result<RefitReport, RefitError> {
        let mut report = refit(self, mesh)?;
        let hittable_again = match &self.leaves {
            Leaves::Packed(p) => !p.unhittable.still_unhittable(mesh),
            Leaves::Single(_) => false,
        };
        if hittable_again || report.degradation() > max_degradation {
            *self = Self::build(mesh, options);
            let sah = stored_sah(&self.parts());
            self.built_sah = Some(sah);
            report.sah = sah;
            report.rebuilt = true;
        }
        Ok(report)
    }

    /// The SAH cost (`stored_sah`) of the tree as it is now, and of
    /// the tree as built (or loaded), whose ratio is the refit's
    /// degradation.
    pub fn sah_costs(&self) -> (f64, f64) {
        let now = stored_sah(&self.parts());
        (now, self.built_sah.unwrap_or(now))
    }
}
