//! Acceleration structures behind one [`Accel`] trait, each generic over the
//! ray/triangle test.
//!
//! - [`BruteForce`]: every ray against every triangle, the reference.
//! - [`Bvh2`]: binary BVH, binned-SAH build, stack traversal nearest child first.
//! - [`Bvh4`] and [`Bvh8`]: the one [`WideBvh`] at widths four and eight,
//!   built as wide nodes directly from the binned SAH, box tests of all
//!   children at once (SSE, AVX2, AVX-512), ordered stack traversal, and
//!   for Möller–Trumbore leaves of four-triangle packs with a packet path.
//! - [`ThreadedBvh`]: BVH in pre-order with escape indices (Smits 1998),
//!   traversed without a stack; [`ThreadedBvh::complete`] builds it as the
//!   complete tree over the triangles in mesh order.
//! - [`LinearBoxes`]: one level of boxes over runs of eight triangles in
//!   mesh order, scanned in order.
//! - The kd-trees ([`KdStack`], [`KdRopes`], [`KdRestart`], [`KdBacktrack`]):
//!   one tree, four traversals (a stack; ropes, Popov et al. 2007; restart
//!   and backtrack, Foley & Sugerman 2005).
//!
//! [`build_accel`] builds any of them by [`AccelKind`] and
//! [`TestKind`](crate::tri::TestKind) at run time.

use crate::aabb::Aabb;
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use rayon::prelude::*;
use serde::Serialize;

mod brute;
pub mod bvh;
mod far_rays;
pub mod flat;
pub mod kdtree;
mod kind;
mod leaf;
mod linear_boxes;
pub(crate) mod node_box;
mod registry;
mod unit_scaled;

pub use brute::BruteForce;
pub use bvh::{
    BuildOptions, BuildQuality, Bvh2, Bvh4, Bvh8, Node4, Node8, PersistError, RefitError,
    RefitReport, ThreadedBvh, WideBvh,
};
pub use far_rays::{approach_start, FarRays, FAR_RADII};
pub use flat::{
    FlatBvh8, FlatChild, FlatKdRopes, FlatKdTree, FlatNode8, FlatThreadedBvh, FlatTriangles,
};
pub use kdtree::{KdBacktrack, KdOptions, KdRestart, KdRopes, KdSplit, KdStack};
pub use kind::AccelKind;
pub use linear_boxes::{LinearBoxes, LINEAR_BOX_SIZE};
pub use registry::{build_accel, kd_accel_from_tree, load_accel, refit_keeps_precision};
pub use unit_scaled::UnitScaled;

/// Rays per rayon task in the batch queries: large enough to amortise task
/// overhead, small enough to balance two cores on uneven work.
pub const BATCH_GRAIN: usize = 256;

/// Size and quality figures of a built structure.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct AccelStats {
    /// Nodes (inner + leaves); 0 for brute force.
    pub nodes: usize,
    /// Leaf nodes.
    pub leaves: usize,
    /// Bytes held by the structure (nodes, index lists, precomputed triangles).
    pub bytes: usize,
    /// Bytes of the nodes alone.
    pub node_bytes: usize,
    /// Longest root-to-leaf path (root has depth 0).
    pub depth: u32,
    /// Surface area heuristic cost (traversal cost 1, triangle cost 1,
    /// relative to the root box): `sum_inner SA(n)/SA(root) * c_trav +
    /// sum_leaf SA(n)/SA(root) * n_tris * c_isect`.
    pub sah_cost: f64,
    /// Triangles referenced by the leaves: more than the mesh has when
    /// triangles are split, fewer when the packed leaves leave out those
    /// no ray can hit (`bvh4`, `bvh8` over Möller).
    pub triangle_refs: usize,
}

/// A structure that answers ray queries on a triangle mesh.
///
/// Every implementation gives the same answers as [`BruteForce`] up to ties
/// (two triangles at the same distance, e.g. on a shared edge), which is what
/// the test suite checks.
pub trait Accel: Send + Sync {
    /// Nearest hit with `t` in `[ray.tnear, ray.tfar]`.
    fn intersect(&self, ray: &Ray) -> Option<Hit>;

    /// True if any triangle is hit with `t` in `[ray.tnear, ray.tfar]`; stops
    /// at the first one found.
    fn occluded(&self, ray: &Ray) -> bool;

    /// Size and quality figures.
    fn stats(&self) -> AccelStats;

    /// Walk the structure's regions for spatial queries: `enter` is called
    /// with a node's region (conservative: contains every triangle point and
    /// the triangles' tolerance bands stored below it) and returns false to
    /// prune it; `leaf` is called with the mesh triangle indices stored in a
    /// reached leaf (a triangle may be reported by several leaves).
    ///
    /// A child's region is entered only after its parent's was accepted, and
    /// a leaf's own region is entered just before its triangles are reported.
    /// Space-partitioning trees whose leaves hold triangles clipped to their
    /// cells (kd-trees) may pass the cells instead: it suffices that the
    /// regions of the leaves storing a triangle together cover it, and that a
    /// parent's region contains its children's. The frustum, box and sphere
    /// queries of [`crate::query`] (the game queries of Kim 2013) are built on it.
    fn visit_regions(&self, enter: &mut dyn FnMut(&Aabb) -> bool, leaf: &mut dyn FnMut(&[u32]));

    /// Save the built structure to `path`, `mesh` being the mesh it was
    /// built over or last refit to, in the versioned, checksummed format
    /// of `bvh/persist.rs`, loaded again by [`load_accel`] (or by the
    /// structure's own `load` when it was built over the mesh as given, not
    /// scaled or moved as [`build_accel`] does tiny and far meshes). The
    /// wide BVHs ([`Bvh4`], [`Bvh8`]) have a saved form; the other
    /// structures refuse with [`PersistError::Unsupported`].
    fn save(&self, path: &std::path::Path, mesh: &TriangleMesh) -> Result<(), PersistError> {
        self.save_at_scale(path, mesh, crate::UnitScale::ONE)
    }

    /// [`Accel::save`] of a structure built over the model at `scale`
    /// (`mesh` being the scaled model, as [`UnitScaled`] holds it): the
    /// file records the scale, so that [`load_accel`] loads it again over
    /// the model as given, whatever its vertices then.
    fn save_at_scale(
        &self,
        path: &std::path::Path,
        mesh: &TriangleMesh,
        scale: crate::UnitScale,
    ) -> Result<(), PersistError> {
        let _ = (mesh, scale);
        Err(PersistError::Unsupported {
            path: path.to_path_buf(),
        })
    }

    /// Refit the structure to `mesh`, the mesh it was built over with
    /// moved vertices: boxes recomputed bottom-up in O(n), topology kept
    /// (see `bvh/refit.rs`; built again instead when a triangle that
    /// packed leaves left out for having no area has gained one). The wide
    /// BVHs ([`Bvh4`], [`Bvh8`]) refit; the
    /// other structures refuse with [`RefitError::Unsupported`] (build
    /// them again). The scaling and placement [`build_accel`] chose stay:
    /// [`refit_keeps_precision`] says whether they suit the moved mesh.
    fn refit(&mut self, mesh: &TriangleMesh) -> Result<RefitReport, RefitError> {
        let _ = mesh;
        Err(RefitError::Unsupported)
    }

    /// Nearest hits for many rays, in parallel over the rayon pool.
    fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        rays.par_iter()
            .zip(hits.par_iter_mut())
            .with_min_len(BATCH_GRAIN)
            .for_each(|(r, h)| *h = self.intersect(r));
    }

    /// Occlusion for many rays, in parallel over the rayon pool.
    fn occluded_batch(&self, rays: &[Ray], occluded: &mut [bool]) {
        assert_eq!(rays.len(), occluded.len(), "one result per ray");
        rays.par_iter()
            .zip(occluded.par_iter_mut())
            .with_min_len(BATCH_GRAIN)
            .for_each(|(r, o)| *o = self.occluded(r));
    }
}
