//! Test support for T-junction elimination (Kim 2013), written independently
//! of `raykit_core::tjunction`: meshes, a plane cutter that makes real
//! T-junctions the way a kd-tree build that cuts polygons does, and a
//! brute-force f64 checker. Also used by the root package's real-mesh tests.
#![allow(dead_code)]

use raykit_core::rng::Pcg32;
use raykit_core::{TriangleMesh, Vec3};
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};

/// A wavy n × n grid of quads over [0, 1]², vertices shared.
pub fn grid(n: u32) -> TriangleMesh {
    let mut pos = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
            pos.push(Vec3::new(x, y, 0.05 * (3.0 * x).sin() * (2.0 * y).cos()));
        }
    }
    let mut idx = Vec::new();
    let v = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            idx.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            idx.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    TriangleMesh::new(pos, idx)
}

/// A closed unit sphere: an octahedron subdivided `levels` times, vertices
/// shared.
pub fn sphere(levels: u32) -> TriangleMesh {
    let mut pos = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let mut idx: Vec<[u32; 3]> = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    for _ in 0..levels {
        let mut mid = HashMap::new();
        let mut next = Vec::new();
        for [a, b, c] in idx {
            let mut m = |x: u32, y: u32| {
                *mid.entry((x.min(y), x.max(y))).or_insert_with(|| {
                    pos.push((pos[x as usize] + pos[y as usize]).normalize());
                    pos.len() as u32 - 1
                })
            };
            let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
            next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        idx = next;
    }
    TriangleMesh::new(pos, idx)
}

/// `n` random triangles in the unit cube, not connected.
pub fn soup(n: u32, seed: u64) -> TriangleMesh {
    let mut rng = Pcg32::new(seed);
    let mut pos = Vec::new();
    for _ in 0..n {
        let c = rng.in_box(Vec3::ZERO, Vec3::ONE);
        for _ in 0..3 {
            pos.push(c + 0.15 * rng.unit_vector());
        }
    }
    TriangleMesh::new(pos, (0..n).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect())
}

/// An axis-aligned cutting plane `p[axis] = at`, applied only to polygons
/// whose centroid lies in the box `region` (a kd-tree node cuts only its own
/// polygons: that is what leaves T-junctions on its neighbours' edges).
#[derive(Clone, Copy, Debug)]
pub struct Plane {
    pub axis: usize,
    pub at: f32,
    pub region: (Vec3, Vec3),
}

/// The planes of a random kd-tree of `depth` levels over the box of `mesh`
/// (parents before children): each node splits its box at a random position
/// (20..80 %) of a random axis, as a game-heuristic build would.
pub fn random_planes(mesh: &TriangleMesh, depth: u32, seed: u64) -> Vec<Plane> {
    let b = mesh.bounds();
    let mut rng = Pcg32::with_stream(seed, 7);
    let mut planes = Vec::new();
    let mut nodes = vec![(
        b.min - Vec3::splat(1.0),
        b.max + Vec3::splat(1.0),
        b.min,
        b.max,
        0,
    )];
    while let Some((lo, hi, mlo, mhi, level)) = nodes.pop() {
        if level == depth {
            continue;
        }
        let axis = rng.below(3) as usize;
        let at = mlo[axis] + (0.2 + 0.6 * rng.next_f32()) * (mhi[axis] - mlo[axis]);
        planes.push(Plane {
            axis,
            at,
            region: (lo, hi),
        });
        let (mut hi_left, mut lo_right) = (hi, lo);
        hi_left[axis] = at;
        lo_right[axis] = at;
        let (mut mhi_left, mut mlo_right) = (mhi, mlo);
        mhi_left[axis] = at;
        mlo_right[axis] = at;
        nodes.push((lo_right, hi, mlo_right, mhi, level + 1));
        nodes.push((lo, hi_left, mlo, mhi_left, level + 1));
    }
    planes
}

/// A polygon corner; `support` is the full segment its outgoing edge lies on
/// (an original triangle edge or a whole cut segment), ends in canonical
/// order, so that both polygons along it compute a cut point identically.
#[derive(Clone, Copy)]
struct Corner {
    pos: Vec3,
    support: (Vec3, Vec3),
}

fn canonical(a: Vec3, b: Vec3) -> (Vec3, Vec3) {
    if a.to_array() < b.to_array() {
        (a, b)
    } else {
        (b, a)
    }
}

/// Cut every triangle by the planes (each only inside its region) into
/// convex polygons, fan them, and return a triangle soup: every triangle
/// has its own three vertices (no cut vertex is shared with a neighbour).
/// Part of each output triangle = index of its source triangle modulo 5.
pub fn cut(mesh: &TriangleMesh, planes: &[Plane]) -> TriangleMesh {
    let b = mesh.bounds();
    let eps = 1e-4 * (b.max - b.min).max_element();
    let mut out = TriangleMesh::default();
    for t in 0..mesh.num_triangles() {
        let tri = mesh.triangle(t);
        let mut polys = vec![(0..3)
            .map(|k| Corner {
                pos: tri[k],
                support: canonical(tri[k], tri[(k + 1) % 3]),
            })
            .collect::<Vec<_>>()];
        for pl in planes {
            let mut next = Vec::new();
            for poly in polys {
                let centroid = poly.iter().map(|c| c.pos).sum::<Vec3>() / poly.len() as f32;
                let (lo, hi) = pl.region;
                if centroid.cmplt(lo).any() || centroid.cmpge(hi).any() {
                    next.push(poly);
                    continue;
                }
                next.extend(split(&poly, pl, eps));
            }
            polys = next;
        }
        for poly in polys {
            for i in 1..poly.len() - 1 {
                let base = out.positions.len() as u32;
                out.positions
                    .extend([poly[0].pos, poly[i].pos, poly[i + 1].pos]);
                out.indices.push([base, base + 1, base + 2]);
                out.tri_part.push(t as u32 % 5);
            }
        }
    }
    out.parts = (0..5)
        .map(|i| raykit_core::Part {
            name: format!("p{i}"),
            node: None,
        })
        .collect();
    out
}

/// Split a convex polygon by a plane; pieces with fewer than 3 corners go.
fn split(poly: &[Corner], pl: &Plane, eps: f32) -> Vec<Vec<Corner>> {
    let side = |p: Vec3| {
        let d = p[pl.axis] - pl.at;
        if d.abs() <= eps {
            0
        } else if d > 0.0 {
            1
        } else {
            -1
        }
    };
    if poly.iter().all(|c| side(c.pos) >= 0) || poly.iter().all(|c| side(c.pos) <= 0) {
        return vec![poly.to_vec()];
    }
    // (corner, on_edge): on_edge = index of the source edge the point lies on.
    let mut front: Vec<(Corner, usize, bool)> = Vec::new();
    let mut back = Vec::new();
    let n = poly.len();
    for i in 0..n {
        let (p, q) = (poly[i], poly[(i + 1) % n]);
        let (sp, sq) = (side(p.pos), side(q.pos));
        if sp >= 0 {
            front.push((p, i, false));
        }
        if sp <= 0 {
            back.push((p, i, false));
        }
        if sp * sq < 0 {
            let (s0, s1) = p.support;
            let s = (pl.at as f64 - s0[pl.axis] as f64) / (s1[pl.axis] as f64 - s0[pl.axis] as f64);
            let mut r = (s0.as_dvec3() + (s1.as_dvec3() - s0.as_dvec3()) * s).as_vec3();
            r[pl.axis] = pl.at;
            let c = Corner {
                pos: r,
                support: p.support,
            };
            front.push((c, i, true));
            back.push((c, i, true));
        }
    }
    [front, back]
        .into_iter()
        .filter(|p| p.len() >= 3)
        .map(|p| {
            // An edge U → V stays on source edge i when U is corner i or a
            // cut of edge i and V is corner i + 1 or a cut of edge i;
            // otherwise it is a new cut segment on the plane.
            let m = p.len();
            (0..m)
                .map(|j| {
                    let (u, v) = (p[j], p[(j + 1) % m]);
                    let same = (v.2 && v.1 == u.1) || (!v.2 && v.1 == (u.1 + 1) % n);
                    Corner {
                        pos: u.0.pos,
                        support: if same {
                            poly[u.1].support
                        } else {
                            canonical(u.0.pos, v.0.pos)
                        },
                    }
                })
                .collect()
        })
        .collect()
}

/// f64 relative tolerance and f32-ulp allowance of the checker (the
/// defaults of `TJunctionOptions`, restated).
pub const TOL: f64 = 1e-6;
pub const ULPS: f64 = 4.0;

/// `ULPS · 2^-23 · M`, `M` the largest coordinate magnitude of the mesh:
/// points closer than this are at the same place.
pub fn rounding_allowance(mesh: &TriangleMesh) -> f64 {
    let m = mesh
        .positions
        .iter()
        .flat_map(|p| p.to_array())
        .fold(0.0f64, |m, c| m.max(c.abs() as f64));
    ULPS * f32::EPSILON as f64 * m
}

/// Independent brute force: every (triangle, edge, point) where a distinct
/// referenced position V lies strictly inside the edge AB (projection in
/// (0, 1), farther than the rounding allowance `r` from A and B) within
/// `TOL · |AB| + r` of its line. Edges no longer than `r` have no inside.
/// Computed by projection (the library uses a cross product). Sorted.
pub fn brute_t_junctions(mesh: &TriangleMesh) -> Vec<(u32, u8, [u32; 3])> {
    let key = |p: Vec3| p.to_array().map(|c| (c + 0.0).to_bits());
    let r = rounding_allowance(mesh);
    let pts: Vec<Vec3> = {
        let mut seen = HashSet::new();
        let mut v = Vec::new();
        for &i in mesh.indices.iter().flatten() {
            let p = mesh.positions[i as usize];
            if seen.insert(key(p)) {
                v.push(p);
            }
        }
        v
    };
    let mut found: Vec<_> = (0..mesh.num_triangles())
        .into_par_iter()
        .flat_map_iter(|ti| {
            let tri = mesh.triangle(ti);
            let mut out = Vec::new();
            for e in 0..3 {
                let (a, b) = (tri[e].as_dvec3(), tri[(e + 1) % 3].as_dvec3());
                let d = b - a;
                let len = d.length();
                if len <= r {
                    continue;
                }
                for &pv in &pts {
                    let v = pv.as_dvec3();
                    if v.distance(a) <= r || v.distance(b) <= r {
                        continue;
                    }
                    let t = (v - a).dot(d) / (len * len);
                    if t > 0.0 && t < 1.0 && (a + d * t).distance(v) <= TOL * len + r {
                        out.push((ti as u32, e as u8, key(pv)));
                    }
                }
            }
            out
        })
        .collect();
    found.sort_unstable();
    found
}

/// Signed-free f64 area of triangle `t`.
pub fn tri_area(mesh: &TriangleMesh, t: usize) -> f64 {
    let [a, b, c] = mesh.triangle(t).map(|p| p.as_dvec3());
    0.5 * (b - a).cross(c - a).length()
}

/// Area per part (f64).
pub fn area_by_part(mesh: &TriangleMesh) -> Vec<f64> {
    let mut by = vec![0.0; mesh.parts.len().max(1)];
    for t in 0..mesh.num_triangles() {
        by[mesh.part_of(t) as usize] += tri_area(mesh, t);
    }
    by
}

/// Undirected edges of the mesh welded by exact position, with the number of
/// triangles using each.
pub fn edge_uses(mesh: &TriangleMesh) -> HashMap<(u32, u32), u32> {
    let mut id = HashMap::new();
    let weld: Vec<u32> = mesh
        .positions
        .iter()
        .map(|p| {
            let n = id.len() as u32;
            *id.entry(p.to_array().map(|c| (c + 0.0).to_bits()))
                .or_insert(n)
        })
        .collect();
    let mut uses = HashMap::new();
    for tri in &mesh.indices {
        for e in 0..3 {
            let (a, b) = (weld[tri[e] as usize], weld[tri[(e + 1) % 3] as usize]);
            *uses.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    uses
}
