//! Spatial queries for games on every acceleration structure: which
//! triangles or objects lie at least partly inside a view frustum, a box or a
//! ball. Kim (2013, "Tree build heuristics for spatial partitioning trees of
//! 3D games") builds its kd-trees for exactly these: frustum culling and
//! collision detection.
//!
//! - [`frustum`]: [`Plane`] and [`Frustum`] (from a [`crate::Camera`] or six
//!   planes).
//! - [`exact`]: the triangle tests in f64 — clipping by half-spaces for
//!   frustums and boxes, Ericson's closest point for balls.
//! - [`shapes`]: [`QueryShape`], the conservative region test (p-vertex for
//!   frustums, box/box, closest point for balls) with the exact test, and
//!   [`Sphere`].
//! - [`walk`]: the tree queries through [`Accel::visit_regions`], with
//!   [`QueryStats`], and the brute-force references.
//!
//! - [`surface_bvh`]: [`SurfaceBvh`], a surface for the point and
//!   multi-hit ray queries below, with the trees it makes on first use: the
//!   8-wide point tree (`point_tree`), and the ray-casting trees
//!   (`ray_tree`, [`crate::accel::Bvh8`]s walked to every crossing) over the
//!   surface and the cap that closes its boundary (`closing`).
//! - [`closest`]: closest point on the surface and unsigned distance
//!   (Ericson 2005), nearest box first.
//! - [`winding`]: generalized winding number (Jacobson et al. 2013) with
//!   Barill et al.'s 2018 far-field approximation, and counted by one ray
//!   through the closed surface: occupancy and signed distance that are
//!   right on open and self-intersecting meshes.
//! - [`all_hits`]: all hits along a ray sorted by `t` (with a cap), their
//!   count, and any-hit with a filter callback.
//!
//! Every region query returns sorted unique ids; a tree query returns exactly what
//! its brute-force reference returns, which the tests check on every
//! [`crate::accel::AccelKind`].

pub mod all_hits;
pub mod answers;
pub(crate) mod batch;
pub mod closest;
mod closing;
mod corner_groups;
pub mod exact;
pub mod frustum;
mod moments;
pub(crate) mod point_tree;
mod ray_tree;
pub mod shapes;
pub mod surface_bvh;
mod surface_node;
pub mod walk;
pub mod winding;

pub use answers::{Answers, QueryKind};
pub use closest::ClosestPoint;
pub use exact::Triangle64;
pub use frustum::{Frustum, Plane};
pub use shapes::{QueryShape, Sphere};
pub use surface_bvh::SurfaceBvh;
pub use walk::{
    parts_overlapping, parts_overlapping_brute, triangles_overlapping, triangles_overlapping_brute,
    QueryResult, QueryStats,
};

use crate::aabb::Aabb;
use crate::accel::Accel;
use crate::mesh::TriangleMesh;

/// Frustum culling (Kim 2013): the triangles of `mesh` at least partly
/// inside `frustum`, sorted, through `accel` built over `mesh`.
pub fn triangles_in_frustum(accel: &dyn Accel, mesh: &TriangleMesh, frustum: &Frustum) -> Vec<u32> {
    triangles_overlapping(accel, mesh, frustum).ids
}

/// Box overlap query (the collision queries of Kim 2013): the triangles of
/// `mesh` sharing a point with the closed box `query`, sorted.
pub fn triangles_in_box(accel: &dyn Accel, mesh: &TriangleMesh, query: &Aabb) -> Vec<u32> {
    triangles_overlapping(accel, mesh, query).ids
}

/// Ball overlap query (the collision queries of Kim 2013): the triangles of
/// `mesh` within `sphere.radius` of its centre, sorted.
pub fn triangles_in_sphere(accel: &dyn Accel, mesh: &TriangleMesh, sphere: &Sphere) -> Vec<u32> {
    triangles_overlapping(accel, mesh, sphere).ids
}

/// Object-level frustum culling (Kim 2013): the parts of `mesh` with a
/// triangle at least partly inside `frustum`, sorted.
pub fn parts_in_frustum(accel: &dyn Accel, mesh: &TriangleMesh, frustum: &Frustum) -> Vec<u32> {
    parts_overlapping(accel, mesh, frustum).ids
}

/// Object-level box query (Kim 2013): the parts of `mesh` with a triangle
/// sharing a point with the box `query`, sorted.
pub fn parts_in_box(accel: &dyn Accel, mesh: &TriangleMesh, query: &Aabb) -> Vec<u32> {
    parts_overlapping(accel, mesh, query).ids
}

/// Object-level ball query (Kim 2013): the parts of `mesh` with a triangle
/// within `sphere.radius` of its centre, sorted.
pub fn parts_in_sphere(accel: &dyn Accel, mesh: &TriangleMesh, sphere: &Sphere) -> Vec<u32> {
    parts_overlapping(accel, mesh, sphere).ids
}
