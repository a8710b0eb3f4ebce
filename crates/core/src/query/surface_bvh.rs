//! [`SurfaceBvh`]: a surface's point and multi-hit ray queries, and the
//! owner of the trees behind them, each made on the first query that needs
//! it: the point tree (`super::point_tree`) of closest points,
//! distances and winding numbers; the ray-casting tree
//! (`super::ray_tree`) of counts, hit lists and occupancy; and the cap
//! that closes the surface's boundary with its trees (occupancy and signed
//! distance). Building only keeps the mesh, so a count never waits for the
//! point tree, nor a closest point for the ray-casting tree.
//!
//! A tree made on first use inside a parallel loop could deadlock: the
//! thread making it may be handed, while it waits on its own parallel
//! build, another iteration that waits for the same tree. The batch
//! queries therefore make what they need before their loops, and
//! [`SurfaceBvh::prepare`] makes it for callers that query from their own
//! parallel loops.

use super::closing::closing_cap;
use super::point_tree::PointTree;
use super::ray_tree::{CapTree, RayTree};
use crate::aabb::Aabb;
use crate::accel::bvh::BuildOptions;
use crate::mesh::TriangleMesh;
use crate::unit_scale::UnitScale;
use std::borrow::Cow;
use std::sync::atomic::AtomicUsize;
use std::sync::OnceLock;

pub use super::surface_node::WIDTH;
pub(crate) use super::surface_node::{stack_of, EMPTY, SMALL_STACK};

/// A triangle mesh's surface for point queries (Ericson 2005's closest
/// point; Jacobson et al. 2013's winding number with Barill et al. 2018's
/// far field) and multi-hit ray queries, with the trees behind them made
/// on first use.
pub struct SurfaceBvh {
    /// The scale the mesh and the trees made from it are at
    /// ([`UnitScale`]): every query scales its points or rays in and its
    /// lengths back.
    pub(crate) scale: UnitScale,
    /// The mesh, at [`SurfaceBvh::scale`].
    pub(crate) mesh: TriangleMesh,
    /// Bounds of the triangles, in the mesh's units.
    pub(crate) bounds: Aabb,
    /// How the point tree is built.
    options: BuildOptions,
    /// The point queries' tree, made on first use.
    pub(crate) points: OnceLock<PointTree>,
    /// The ray-casting tree of the multi-hit queries and occupancy, made on
    /// first use.
    pub(crate) rays: OnceLock<RayTree>,
    /// The ray-casting tree of the cap that closes the surface, and the
    /// cap's own surface for its winding number (none when the surface is
    /// closed or crossings are not counted), made on the first occupancy
    /// query.
    closing: OnceLock<(CapTree, Option<Box<SurfaceBvh>>)>,
    /// Points summed over every triangle so far, while the point tree was
    /// not made (see [`super::winding::SUM_DIRECTLY_IN_ALL`]).
    pub(crate) summed_directly: AtomicUsize,
}

impl SurfaceBvh {
    /// The surface of all triangles of `mesh`, its point tree to be built
    /// with the default build options.
    pub fn build(mesh: &TriangleMesh) -> Self {
        Self::build_with(mesh, &BuildOptions::default())
    }

    /// The surface of all triangles of `mesh`, at unit scale when the mesh
    /// is tiny ([`UnitScale`]); its point tree, when a query needs it, is
    /// the binned SAH or linear BVH that `options.quality` names, leaves of
    /// up to `options.max_leaf_size`.
    ///
    /// # Panics
    /// When a triangle refers to a vertex the mesh does not have
    /// ([`TriangleMesh::assert_indices_in_range`]).
    pub fn build_with(mesh: &TriangleMesh, options: &BuildOptions) -> Self {
        mesh.assert_indices_in_range();
        let (scale, scaled) = UnitScale::of(mesh);
        let mesh = match scaled {
            Cow::Owned(m) => TriangleMesh::new(m.positions, m.indices),
            Cow::Borrowed(m) => TriangleMesh::new(m.positions.clone(), m.indices.clone()),
        };
        let bounds = mesh.bounds();
        SurfaceBvh {
            scale,
            mesh,
            bounds: scale.aabb_to_model(&bounds),
            options: options.clone(),
            points: OnceLock::new(),
            rays: OnceLock::new(),
            closing: OnceLock::new(),
            summed_directly: AtomicUsize::new(0),
        }
    }

    /// The point tree over the triangles; made on first use.
    pub(crate) fn points(&self) -> &PointTree {
        self.points
            .get_or_init(|| PointTree::build(&self.mesh, &self.options))
    }

    /// The point tree and its winding-number moments; made on first use.
    pub(crate) fn winding_tree(&self) -> &PointTree {
        let points = self.points();
        points.moments();
        points
    }

    /// Whether the ray-casting tree has been made.
    pub(crate) fn has_ray_tree(&self) -> bool {
        self.rays.get().is_some()
    }

    /// Whether the ray-casting trees of the surface and its closing cap
    /// have been made ([`SurfaceBvh::closed_trees`]).
    pub(crate) fn has_closing(&self) -> bool {
        self.closing.get().is_some()
    }

    /// Whether the point tree has been made.
    pub(crate) fn has_point_tree(&self) -> bool {
        self.points.get().is_some()
    }

    /// The ray-casting tree over the triangles; made on first use.
    pub(crate) fn ray_tree(&self) -> &RayTree {
        self.rays.get_or_init(|| RayTree::build(&self.mesh))
    }

    /// The ray-casting trees over the triangles and over the cap that
    /// closes them ([`super::closing`]), and the cap's own point tree for
    /// its winding number (none when the surface is closed); made on first
    /// use.
    pub(crate) fn closed_trees(&self) -> (&RayTree, &CapTree, Option<&SurfaceBvh>) {
        let tree = self.ray_tree();
        let (cap_tree, cap) = self.closing.get_or_init(|| {
            let cap = closing_cap(&self.mesh);
            let cap_tree = CapTree::build(tree, &cap);
            let winding = (cap_tree.countable() && !cap.is_empty()).then(|| {
                let cap = Box::new(SurfaceBvh::build(&TriangleMesh::from_triangles(&cap)));
                // Made here rather than at the cap's first winding number,
                // which the batches ask for inside their parallel loops.
                cap.winding_tree();
                cap
            });
            (cap_tree, winding)
        });
        (tree, cap_tree, cap.as_deref())
    }

    /// Bytes held: the mesh, and the trees and winding-number moments that
    /// have been made.
    pub fn bytes(&self) -> usize {
        let own = std::mem::size_of_val(&self.mesh.positions[..])
            + std::mem::size_of_val(&self.mesh.indices[..]);
        let points = self.points.get().map_or(0, PointTree::bytes);
        let rays = self.rays.get().map_or(0, RayTree::bytes);
        let closing = self.closing.get().map_or(0, |(tree, cap)| {
            tree.bytes() + cap.as_ref().map_or(0, |c| c.bytes())
        });
        own + points + rays + closing
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.mesh.num_triangles()
    }

    /// Bounds of all triangles.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }
}
