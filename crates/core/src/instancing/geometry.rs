//! A geometry of an instanced scene: one triangle mesh with its own
//! bottom-level BVH, stored once however many instances place it.

use crate::aabb::Aabb;
use crate::accel::{Accel, BuildOptions, Bvh8, FarRays, UnitScaled};
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::query::SurfaceBvh;
use crate::ray::Ray;
use crate::tri::{Moller, MAX_EDGE_TOLERANCE};
use crate::unit_scale::UnitScale;
use glam::Vec3;
use std::sync::OnceLock;

/// A triangle mesh in its own object space with the bottom-level
/// [`Bvh8`] over Möller–Trumbore triangles that answers nearest-hit and
/// occlusion queries, and, made on the first multi-hit query, the
/// [`SurfaceBvh`] behind all-hits, counts and filtered any-hit queries.
pub struct Geometry {
    mesh: TriangleMesh,
    /// The BVH over the mesh at its [`UnitScale`] (a tiny mesh is scaled
    /// up, so that the triangle tests' products stay in `f32`'s range),
    /// rays from far away moved up to the mesh ([`FarRays`]).
    bvh: FarRays<UnitScaled<Bvh8<Moller>>>,
    /// Bounds padded by the triangle tests' tolerance band, as the BVHs'
    /// own node boxes are (`accel/node_box.rs`).
    bounds: Aabb,
    mask: u32,
    surface: OnceLock<SurfaceBvh>,
}

impl Geometry {
    /// Build the bottom-level BVH over `mesh` (checked by the caller).
    pub(crate) fn build(mesh: TriangleMesh, mask: u32, options: &BuildOptions) -> Self {
        let (scale, scaled) = UnitScale::of(&mesh);
        let bvh = FarRays::around(
            Box::new(UnitScaled::new(Bvh8::build(&scaled, options), scale)),
            &mesh,
        );
        let b = mesh.bounds();
        let bounds = if mesh.indices.is_empty() {
            Aabb::EMPTY
        } else {
            let pad = Vec3::splat(4.0 * MAX_EDGE_TOLERANCE * b.extent().max_element());
            Aabb::new(b.min - pad, b.max + pad)
        };
        Geometry {
            mesh,
            bvh,
            bounds,
            mask,
            surface: OnceLock::new(),
        }
    }

    /// The mesh, in object space.
    pub fn mesh(&self) -> &TriangleMesh {
        &self.mesh
    }

    /// The nearest hit of `ray` (in object space) on the geometry.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.bvh.intersect(ray)
    }

    /// Whether `ray` (in object space) hits the geometry.
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.bvh.occluded(ray)
    }

    /// [`Geometry::intersect`] for many rays (the bottom-level BVH's
    /// packet path).
    pub fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        self.bvh.intersect_batch(rays, hits);
    }

    /// [`Geometry::occluded`] for many rays.
    pub fn occluded_batch(&self, rays: &[Ray], occluded: &mut [bool]) {
        self.bvh.occluded_batch(rays, occluded);
    }

    /// The mesh's bounds widened by the triangle tests' tolerance band
    /// (empty for a mesh without triangles).
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The geometry's ray mask: a ray with mask `m` sees it when
    /// `mask & m != 0`.
    pub fn mask(&self) -> u32 {
        self.mask
    }

    /// The surface behind the multi-hit queries, made on first use with
    /// its trees made on the first query that needs them.
    pub fn surface(&self) -> &SurfaceBvh {
        self.surface.get_or_init(|| SurfaceBvh::build(&self.mesh))
    }

    /// `e1 × e2` of triangle `prim` in object space, at the BVH's scale
    /// (the direction is the same; its length does not underflow).
    pub(crate) fn face_cross(&self, prim: u32) -> Vec3 {
        let [a, b, c] = self
            .mesh
            .triangle(prim as usize)
            .map(|p| self.bvh.inner().scale().point(p));
        (b - a).cross(c - a)
    }

    /// Bytes held: the mesh's positions and indices, the bottom-level BVH,
    /// and the multi-hit trees if they have been made.
    pub fn bytes(&self) -> usize {
        let mesh = self.mesh.positions.len() * std::mem::size_of::<Vec3>()
            + self.mesh.indices.len() * std::mem::size_of::<[u32; 3]>();
        let surface = self.surface.get().map_or(0, SurfaceBvh::bytes);
        mesh + self.bvh.stats().bytes + surface
    }
}
