//! The ray-casting trees of a [`super::SurfaceBvh`]: 8-wide BVHs over packs
//! of four Möller triangles ([`Bvh8`], Wald et al. 2014's layout), made on
//! the first query that needs them: the surface's ([`RayTree`]) for the
//! multi-hit ray queries, and the closing cap's ([`CapTree`]) besides for
//! the crossing count behind occupancy.
//!
//! The point queries' tree keeps the triangles' corners, which the
//! closest-point and solid-angle kernels need; rays are faster through the
//! ray-casting tree's boxes, compiled box kernels and packs (on the full
//! dragon the multi-hit walk is bound by memory latency, and these nodes
//! and leaves are what the nearest-hit engine keeps hot). One tree holds
//! the surface's triangles that have area, built straight from the mesh
//! (see [`RayTree::build`]), so that a count never waits for the
//! point tree; the cap that closes the surface's boundary
//! ([`super::closing`]) has a tree of its own, so that its triangles, which
//! may be long, never slow the hit queries, and a count or a hit list never
//! waits for the cap to be made.

use crate::aabb::Aabb;
use crate::accel::bvh::{BuildOptions, Bvh8, CrossingVisitor};
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::moller::Crossing;
use crate::tri::{crossing_once, Moller};
use glam::Vec3;
use rayon::prelude::*;

/// Which way the crossing rays of occupancy leave a point: along the axis
/// to the nearest face of the box, tilted by these fixed amounts towards
/// the other two axes so that the ray does not run along axis-aligned
/// faces and edges.
const TILT: [f32; 2] = [0.013_1, 0.023_7];

/// A surface's ray-casting tree.
pub(crate) struct RayTree {
    /// Over the surface's triangles with area, in the mesh's order.
    surface: Bvh8<Moller>,
    /// The mesh's index of each of `surface`'s triangles, where some were
    /// left out for having no area; none when all were kept (the indices
    /// are the same).
    indices: Option<Vec<u32>>,
    /// Triangles of the surface, with area or not.
    triangles: usize,
    /// Bounds of the triangles in `surface`.
    bounds: Aabb,
}

/// The ray-casting tree of the cap that closes a surface
/// ([`super::closing`]), for the crossings behind occupancy.
pub(crate) struct CapTree {
    /// Over the cap's triangles; none for a closed surface.
    cap: Option<Bvh8<Moller>>,
    /// Whether crossings are counted at all (see [`CapTree::build`]).
    countable: bool,
    /// Bounds of surface and cap.
    lo: Vec3,
    hi: Vec3,
}

/// Whether a triangle's corners are not collinear: its edge vectors'
/// cross product is not zero, in `f64`, where the products of `f32`
/// differences are exact, so that only truly collinear corners fail.
fn has_area(t: &[Vec3; 3]) -> bool {
    let [a, b, c] = t.map(|v| v.as_dvec3());
    (b - a).cross(c - a) != glam::DVec3::ZERO
}

/// A tree over a mesh, built with the wide nodes' free slots filled
/// ([`BuildOptions::best`]): a walk to every crossing never stops early, so
/// every pack test it saves counts. Every triangle is in its leaves
/// ([`Bvh8::build_keeping_all`]): the crossings are classified exactly
/// from the corners.
fn crossing_tree(mesh: &TriangleMesh) -> Bvh8<Moller> {
    Bvh8::build_keeping_all(mesh, &BuildOptions::best())
}

impl RayTree {
    /// The tree of the `surface` mesh's triangles.
    ///
    /// Triangles without area (collinear corners: slivers that CAD
    /// tessellations leave, whose long boxes every ray along them must
    /// open) are left out of the surface's tree; no ray crosses them. An
    /// `f32` Möller test can still report a crossing of one, from rounding
    /// alone; the `f64` references never do, and neither does this tree.
    pub fn build(surface: &TriangleMesh) -> Self {
        let n = surface.num_triangles();
        let kept: Vec<u32> = (0..n as u32)
            .into_par_iter()
            .filter(|&i| has_area(&surface.triangle(i as usize)))
            .collect();
        let (indices, tree, bounds) = if kept.len() == n {
            (None, crossing_tree(surface), surface.bounds())
        } else {
            let with_area = TriangleMesh::new(
                surface.positions.clone(),
                kept.iter().map(|&i| surface.indices[i as usize]).collect(),
            );
            let tree = crossing_tree(&with_area);
            (Some(kept), tree, with_area.bounds())
        };
        RayTree {
            surface: tree,
            indices,
            triangles: n,
            bounds,
        }
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        use crate::accel::Accel;
        self.surface.stats().bytes + self.indices.as_ref().map_or(0, |p| 4 * p.len())
    }

    /// Walk the surface's hits along `ray`: `visit(c, p, reach)` with `p`
    /// the triangle's index in the `surface` mesh (the tree's); see
    /// [`Bvh8::crossings`] and [`Settle::settle`] for which crossings are
    /// hits.
    #[inline(always)]
    pub fn surface_hits<const NEAR_FIRST: bool>(
        &self,
        ray: &Ray,
        surface: &TriangleMesh,
        mut visit: impl FnMut(&Crossing, u32, &mut f32) -> bool,
    ) {
        let settle = self.settle(ray, surface);
        let _ = self.surface.crossings::<NEAR_FIRST, true, _>(
            ray,
            |c: &Crossing, p, reach: &mut f32| match settle.settle(c, p, *reach) {
                Some(c) => visit(&c, self.mesh_index(p), reach),
                None => true,
            },
        );
    }

    /// The number of the surface's hits along each of `rays`, walked in
    /// turn (see [`Bvh8::crossings_batch`]); `surface` as for
    /// [`RayTree::surface_hits`].
    pub fn count_hits(&self, rays: &[Ray], surface: &TriangleMesh, out: &mut [u32]) {
        self.surface.crossings_batch::<true, _>(
            rays,
            |ray| HitCount(0, self.settle(ray, surface)),
            |i, v| out[i] = v.0,
        );
    }

    /// The surface's hits along each of `rays`, unsorted, with the
    /// triangles' indices in the mesh, walked in turn (see
    /// [`Bvh8::crossings_batch`]): `done(i, hits, indices)` may take ray
    /// `i`'s; `surface` as for [`RayTree::surface_hits`].
    pub fn hits(
        &self,
        rays: &[Ray],
        surface: &TriangleMesh,
        mut done: impl FnMut(usize, &mut Vec<Crossing>, &[u32]),
    ) {
        self.surface.crossings_batch::<true, _>(
            rays,
            |ray| HitList::new(self.settle(ray, surface)),
            |i, v| done(i, &mut v.hits, &v.prims),
        );
    }

    fn settle<'a>(&'a self, ray: &Ray, surface: &'a TriangleMesh) -> Settle<'a> {
        Settle {
            ray: *ray,
            tree: self,
            surface,
        }
    }

    /// The mesh's index of the surface tree's triangle `p`.
    #[inline(always)]
    fn mesh_index(&self, p: u32) -> u32 {
        self.indices.as_ref().map_or(p, |m| m[p as usize])
    }
}

impl CapTree {
    /// The tree of the `cap` that closes `surface` ([`RayTree::build`]'s
    /// triangles). A cap of more than a quarter as many triangles as the
    /// surface (a soup rather than a surface with holes) is left out, and
    /// crossings are not counted: through such a cap, counting costs more
    /// than summing the solid angles (BENCHMARKS.md).
    pub fn build(surface: &RayTree, cap: &[[Vec3; 3]]) -> Self {
        let mut b = surface.bounds;
        let countable = cap.len() <= surface.triangles / 4;
        let cap = (countable && !cap.is_empty()).then(|| {
            let mesh = TriangleMesh::from_triangles(cap);
            let tree = crossing_tree(&mesh);
            b = b.union(mesh.bounds());
            tree
        });
        CapTree {
            cap,
            countable,
            lo: b.min,
            hi: b.max,
        }
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        use crate::accel::Accel;
        self.cap.as_ref().map_or(0, |c| c.stats().bytes)
    }

    /// Whether [`CapTree::signed_crossings`] counts: false when the cap
    /// was left out (see [`CapTree::build`]).
    pub fn countable(&self) -> bool {
        self.countable
    }

    /// The winding number of surface and cap together at `q`: the signed
    /// crossings of one ray (leaving through a front face +1, entering
    /// through one -1), towards the nearest face of the box. When a
    /// crossing is too close to an edge, a corner or `q` itself to be sure
    /// of, the rays towards the next two nearest faces are tried. None
    /// when all three are unsure, `q` is not finite, or the tree does not
    /// count.
    pub fn signed_crossings(&self, surface: &RayTree, q: Vec3) -> Option<i32> {
        if !q.is_finite() || !self.countable {
            return None;
        }
        let mut exits = [
            (self.hi.x - q.x, 0),
            (q.x - self.lo.x, 1),
            (self.hi.y - q.y, 2),
            (q.y - self.lo.y, 3),
            (self.hi.z - q.z, 4),
            (q.z - self.lo.z, 5),
        ];
        exits.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        // Outside the box on that side the ray moves away from everything.
        if exits[0].0 < 0.0 {
            return Some(0);
        }
        exits[..3]
            .iter()
            .find_map(|&(_, face)| self.crossings_towards(surface, q, face))
    }

    /// The signed crossings of the ray from `q` towards box face `face`
    /// (`+x, -x, +y, -y, +z, -z`), tilted off the axis; None when one is
    /// unsure.
    fn crossings_towards(&self, surface: &RayTree, q: Vec3, face: usize) -> Option<i32> {
        let (axis, sign) = (face / 2, if face.is_multiple_of(2) { 1.0 } else { -1.0 });
        let mut dir = Vec3::ZERO;
        dir[axis] = sign;
        dir[(axis + 1) % 3] = TILT[0];
        dir[(axis + 2) % 3] = TILT[1];
        let ray = Ray::new(q, dir.normalize());
        let mut sum = SignedCount::default();
        for tree in std::iter::once(&surface.surface).chain(&self.cap) {
            if sum.sure {
                sum = tree.crossings::<false, true, _>(&ray, sum);
            }
        }
        sum.sure.then_some(sum.count)
    }
}

/// Which of a ray's crossings are hits, each counted once.
struct Settle<'a> {
    ray: Ray,
    tree: &'a RayTree,
    surface: &'a TriangleMesh,
}

impl Settle<'_> {
    /// The hit that crossing `c` of the surface tree's triangle `p` is, if
    /// any: the textbook test's where [`Moller::crossing`] is sure of it,
    /// else [`crossing_once`]'s on the triangle's corners, which counts a
    /// ray through a shared edge or corner exactly once. Unsure crossings
    /// are rare (within rounding error of an edge or a corner).
    #[inline(always)]
    fn settle(&self, c: &Crossing, p: u32, reach: f32) -> Option<Crossing> {
        if c.sure {
            return c.hit.then_some(*c);
        }
        self.exact(p, reach).map(|h| Crossing {
            t: h.t,
            u: h.u,
            v: h.v,
            hit: true,
            sure: true,
            ..*c
        })
    }

    #[cold]
    #[inline(never)]
    fn exact(&self, p: u32, reach: f32) -> Option<crate::tri::TriHit> {
        let at = self.tree.mesh_index(p);
        crossing_once(&self.surface.triangle(at as usize), &self.ray, reach)
    }
}

/// Counts hits.
struct HitCount<'a>(u32, Settle<'a>);

impl CrossingVisitor for HitCount<'_> {
    #[inline(always)]
    fn visit(&mut self, c: &Crossing, p: u32, reach: &mut f32) -> bool {
        self.0 += self.1.settle(c, p, *reach).is_some() as u32;
        true
    }
}

/// Collects hits and their triangles' indices in the mesh.
struct HitList<'a> {
    hits: Vec<Crossing>,
    prims: Vec<u32>,
    settle: Settle<'a>,
}

impl<'a> HitList<'a> {
    fn new(settle: Settle<'a>) -> Self {
        HitList {
            hits: Vec::new(),
            prims: Vec::new(),
            settle,
        }
    }
}

impl CrossingVisitor for HitList<'_> {
    #[inline(always)]
    fn visit(&mut self, c: &Crossing, p: u32, reach: &mut f32) -> bool {
        if let Some(c) = self.settle.settle(c, p, *reach) {
            self.hits.push(c);
            self.prims.push(self.settle.tree.mesh_index(p));
        }
        true
    }
}

/// Counts crossings by side, and stops at the first unsure one.
struct SignedCount {
    count: i32,
    sure: bool,
}

impl Default for SignedCount {
    fn default() -> Self {
        SignedCount {
            count: 0,
            sure: true,
        }
    }
}

impl CrossingVisitor for SignedCount {
    #[inline(always)]
    fn visit(&mut self, c: &Crossing, _: u32, _: &mut f32) -> bool {
        if !self.sure || !c.sure {
            self.sure = false;
            return false;
        }
        if c.hit {
            self.count += if c.det < 0.0 { 1 } else { -1 };
        }
        true
    }
}
