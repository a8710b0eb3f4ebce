//! Multi-hit ray queries: every hit along a ray sorted by `t` (up to a
//! cap, which makes it the first `k` hits), the number of hits, and an
//! any-hit query that asks a filter callback about each hit found (for
//! example to skip back faces).
//!
//! Each crossing of the surface is reported exactly once, rays through
//! shared edges and corners included. The tree (a [`SurfaceBvh`]'s
//! ray-casting tree, or any [`Accel`]'s regions) is walked with its box
//! tests. On the ray-casting tree each triangle is classified by
//! Möller–Trumbore (1997) with its rounding-error bounds
//! ([`crate::tri::moller::Moller::crossing`]): without the tolerance band
//! of the nearest-hit tests, so that two neighbours do not both report one
//! crossing near their shared edge; and the crossings within rounding
//! error of an edge or a corner are decided by [`crossing_once`] (Woop et
//! al. 2013, exact edge signs with their ties broken alike for both
//! neighbours), which every triangle of an [`Accel`]'s regions goes
//! through. When the cap is reached, boxes entered beyond the farthest
//! kept hit are skipped. [`ray_hits_brute`] is the `f64` reference of the
//! tests.

use super::surface_bvh::{SurfaceBvh, EMPTY, WIDTH};
use crate::accel::{Accel, BATCH_GRAIN};
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::crossing_once;
use glam::DVec3;
use rayon::prelude::*;

/// Slab test of a ray against the eight boxes of a node: the entry
/// distances, NaN for boxes missed or unused (so that every comparison
/// with a reach rejects them).
#[inline(always)]
pub(crate) fn slab8(
    min: &[[f32; WIDTH]; 3],
    max: &[[f32; WIDTH]; 3],
    child: &[u32; WIDTH],
    ray: &Ray,
    tfar: f32,
) -> [f32; WIDTH] {
    let mut lo = [ray.tnear; WIDTH];
    let mut hi = [tfar; WIDTH];
    for a in 0..3 {
        let (o, inv) = (ray.origin[a], ray.inv_dir[a]);
        for k in 0..WIDTH {
            let t0 = (min[a][k] - o) * inv;
            let t1 = (max[a][k] - o) * inv;
            // Plain compares (one instruction each, unlike f32::min/max's
            // NaN rules). A NaN (a ray lying in a slab's plane) may keep or
            // drop the box, which matters only for triangles the ray grazes
            // at that plane.
            let (near, far) = if t0 < t1 { (t0, t1) } else { (t1, t0) };
            lo[k] = if near > lo[k] { near } else { lo[k] };
            hi[k] = if far < hi[k] { far } else { hi[k] };
        }
    }
    let mut entry = [f32::NAN; WIDTH];
    for k in 0..WIDTH {
        // Widened by a few ulps so rounding never drops a box the
        // triangle test would hit.
        if lo[k] <= hi[k] * (1.0 + 4.0 * f32::EPSILON) && child[k] != EMPTY {
            entry[k] = lo[k];
        }
    }
    entry
}

/// The hits kept by a query: all, sorted by `t`, up to a cap.
struct Kept<'a> {
    hits: &'a mut Vec<Hit>,
    cap: usize,
}

impl Kept<'_> {
    /// The farthest `t` still worth looking at.
    fn reach(&self, tfar: f32) -> f32 {
        if self.hits.len() >= self.cap {
            self.hits.last().map_or(tfar, |h| h.t)
        } else {
            tfar
        }
    }

    fn insert(&mut self, h: Hit) {
        let at = self
            .hits
            .partition_point(|x| (x.t, x.prim) <= (h.t, h.prim));
        if at >= self.cap {
            return;
        }
        self.hits.insert(at, h);
        self.hits.truncate(self.cap);
    }
}

impl SurfaceBvh {
    /// Walk the hits of `ray` within `reach` (which `visit` may lower;
    /// boxes entered beyond it are skipped): `visit` gets each and returns
    /// false to stop. Through the ray-casting tree ([`super::ray_tree`]),
    /// nearest children first when `NEAR_FIRST`.
    #[inline(always)]
    fn walk_hits<const NEAR_FIRST: bool, V: FnMut(Hit, &mut f32) -> bool>(
        &self,
        ray: &Ray,
        mut visit: V,
    ) {
        if self.mesh.indices.is_empty() {
            return;
        }
        let scale = self.scale;
        // The walk is at the tree's scale; `visit` sees hits and the reach
        // in the mesh's units.
        self.ray_tree()
            .surface_hits::<NEAR_FIRST>(&scale.ray(ray), &self.mesh, |c, p, reach| {
                let hit = Hit {
                    t: scale.to_model(c.t),
                    u: c.u,
                    v: c.v,
                    prim: p,
                };
                let mut model_reach = scale.to_model(*reach);
                let more = visit(hit, &mut model_reach);
                *reach = scale.length(model_reach);
                more
            });
    }

    /// The hits along `ray` with `t` in `[ray.tnear, ray.tfar]` that
    /// `accept` keeps, sorted by `t` (then triangle), at most `max_hits` of
    /// them (the nearest): every hit with `usize::MAX`, the first `k` with
    /// `k`. Written to `out` (cleared first). A ray that is not valid
    /// (NaN, infinite origin, zero direction) has no hits.
    pub fn ray_hits_filtered<F: FnMut(&Hit) -> bool>(
        &self,
        ray: &Ray,
        max_hits: usize,
        mut accept: F,
        out: &mut Vec<Hit>,
    ) {
        out.clear();
        if max_hits == 0 {
            return;
        }
        let mut kept = Kept {
            hits: out,
            cap: max_hits,
        };
        self.walk_hits::<true, _>(ray, |h, reach| {
            if h.t <= kept.reach(*reach) && accept(&h) {
                kept.insert(h);
                *reach = kept.reach(*reach);
            }
            true
        });
    }

    /// Every hit along `ray`, sorted by `t`, at most `max_hits` (the
    /// nearest); see [`SurfaceBvh::ray_hits_filtered`].
    pub fn ray_hits(&self, ray: &Ray, max_hits: usize) -> Vec<Hit> {
        let mut out = Vec::new();
        self.ray_hits_filtered(ray, max_hits, |_| true, &mut out);
        out
    }

    /// Number of triangles `ray` crosses with `t` in `[ray.tnear, ray.tfar]`.
    pub fn count_hits(&self, ray: &Ray) -> u32 {
        let mut n = 0u32;
        self.walk_hits::<true, _>(ray, |_, _| {
            n += 1;
            true
        });
        n
    }

    /// Any hit that `accept` takes (the first found, not the nearest), for
    /// example `|h| !back_face(h)`; stops at the first accepted hit.
    pub fn any_hit<F: FnMut(&Hit) -> bool>(&self, ray: &Ray, mut accept: F) -> Option<Hit> {
        let mut found = None;
        self.walk_hits::<false, _>(ray, |h, _| {
            if accept(&h) {
                found = Some(h);
                false
            } else {
                true
            }
        });
        found
    }

    /// [`SurfaceBvh::count_hits`] for many rays, in parallel.
    pub fn count_hits_batch(&self, rays: &[Ray], out: &mut [u32]) {
        assert_eq!(rays.len(), out.len(), "one count per ray");
        if self.mesh.indices.is_empty() {
            out.fill(0);
            return;
        }
        let tree = self.ray_tree();
        rays.par_chunks(BATCH_GRAIN)
            .zip(out.par_chunks_mut(BATCH_GRAIN))
            .for_each(|(rays, out)| tree.count_hits(&self.scale.rays(rays), &self.mesh, out));
    }

    /// [`SurfaceBvh::ray_hits`] for many rays, in parallel: one sorted list
    /// per ray. The rays are walked in turn, each collecting all its hits,
    /// which are then sorted and cut to `max_hits`: the same lists as one
    /// [`SurfaceBvh::ray_hits`] per ray.
    pub fn ray_hits_batch(&self, rays: &[Ray], max_hits: usize) -> Vec<Vec<Hit>> {
        let mut lists: Vec<Vec<Hit>> = (0..rays.len()).map(|_| Vec::new()).collect();
        if self.mesh.indices.is_empty() || max_hits == 0 {
            return lists;
        }
        let tree = self.ray_tree();
        rays.par_chunks(BATCH_GRAIN)
            .zip(lists.par_chunks_mut(BATCH_GRAIN))
            .for_each(|(rays, lists)| {
                tree.hits(&self.scale.rays(rays), &self.mesh, |i, found, at| {
                    let mut hits: Vec<Hit> = found
                        .iter()
                        .zip(at)
                        .map(|(c, &p)| Hit {
                            t: self.scale.to_model(c.t),
                            u: c.u,
                            v: c.v,
                            prim: p,
                        })
                        .collect();
                    hits.sort_by(|a, b| {
                        (a.t, a.prim)
                            .partial_cmp(&(b.t, b.prim))
                            .unwrap_or(std::cmp::Ordering::Equal)
                    });
                    hits.truncate(max_hits);
                    lists[i] = hits;
                })
            });
        lists
    }
}

/// Every hit along `ray` through any structure's regions
/// ([`Accel::visit_regions`], `accel` built over `mesh`), sorted by `t`
/// (then triangle), at most `max_hits`; a triangle stored in several leaves
/// is reported once.
pub fn ray_hits_in(accel: &dyn Accel, mesh: &TriangleMesh, ray: &Ray, max_hits: usize) -> Vec<Hit> {
    let mut hits: Vec<Hit> = Vec::new();
    if !ray.is_valid() || max_hits == 0 {
        return hits;
    }
    let n = mesh.num_triangles();
    accel.visit_regions(
        &mut |region| {
            region
                .clip(ray, ray.tnear, ray.tfar * (1.0 + 4.0 * f32::EPSILON))
                .is_some()
        },
        &mut |prims| {
            for &t in prims {
                if (t as usize) < n {
                    if let Some(h) = crossing_once(&mesh.triangle(t as usize), ray, ray.tfar) {
                        hits.push(Hit {
                            t: h.t,
                            u: h.u,
                            v: h.v,
                            prim: t,
                        });
                    }
                }
            }
        },
    );
    hits.sort_by(|a, b| (a.t, a.prim).partial_cmp(&(b.t, b.prim)).unwrap());
    let mut seen = std::collections::HashSet::new();
    hits.retain(|h| seen.insert(h.prim));
    hits.truncate(max_hits);
    hits
}

/// A crossing found by [`ray_hits_brute`]: `t`, the triangle, and how far
/// inside the triangle it is (the smallest barycentric coordinate; near 0
/// the crossing is at an edge, where `f32` tests may disagree).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing64 {
    /// Distance along the ray.
    pub t: f64,
    /// Triangle index.
    pub prim: u32,
    /// Smallest barycentric coordinate of the crossing.
    pub margin: f64,
}

/// Reference: every triangle against `ray` in `f64` (Möller–Trumbore on
/// the `f64` corners), the crossings with `t` in `[tnear, tfar]` sorted by
/// `t`.
pub fn ray_hits_brute(mesh: &TriangleMesh, ray: &Ray) -> Vec<Crossing64> {
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let mut out = Vec::new();
    for t in 0..mesh.num_triangles() {
        let [a, b, c]: [DVec3; 3] = mesh.triangle(t).map(|v| v.as_dvec3());
        let (e1, e2) = (b - a, c - a);
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det == 0.0 {
            continue;
        }
        let s = o - a;
        let u = s.dot(p) / det;
        let q = s.cross(e1);
        let v = d.dot(q) / det;
        let th = e2.dot(q) / det;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && th >= ray.tnear as f64 && th <= ray.tfar as f64 {
            out.push(Crossing64 {
                t: th,
                prim: t as u32,
                margin: u.min(v).min(1.0 - u - v),
            });
        }
    }
    out.sort_by(|a, b| a.t.total_cmp(&b.t));
    out
}
