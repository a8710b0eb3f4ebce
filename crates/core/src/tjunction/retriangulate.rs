//! Kim's (2013) re-tessellation step: insert the T-junction points into the
//! edges of each triangle and triangulate the convex polygon they form.
//!
//! The polygon has three straight chains (one per original edge) and no
//! interior points. Any triangle whose three corners come from one chain
//! would be flat, so the triangulation is a fan from a corner that is not on
//! the chain being fanned, in two levels:
//! 1. take the edge with the most points (ties: the lowest edge number),
//!    `X → P1 … Pk → Y`, and fan it from the opposite corner `Z`:
//!    `(Z, X, P1), (Z, P1, P2), …, (Z, Pk, Y)`;
//! 2. the first of those triangles has the chain `Z → X` as an edge and the
//!    last the chain `Y → Z`; if that chain has points, the triangle is
//!    replaced by a fan of the chain from `P1` (resp. `Pk`), which lies on
//!    `X → Y` and so on neither chain.
//!
//! Every triangle has two corners on one chain and the third off its line, so
//! none is flat (up to points lying within the tolerance of each other); all
//! keep the source triangle's orientation. No new vertices: an inserted
//! point reuses its vertex index. A triangle with `n` inserted points becomes
//! `n + 1` triangles.

use super::{EdgeVertex, Prepared};
use crate::mesh::TriangleMesh;

/// The mesh with the kept triangles re-triangulated around the points of
/// `found` (canonical order, T-junctions of `mesh`'s kept triangles) and the
/// other triangles dropped, and the number of points inserted. Pieces keep
/// their source triangle's material and part, in the order of the source
/// triangles. Of consecutive points of one edge at the same place (within
/// the rounding allowance), only the first is inserted; a point found on two
/// edges of one triangle (next to their shared corner) goes into the first.
pub(crate) fn retriangulate(
    mesh: &TriangleMesh,
    prep: &Prepared,
    found: &[EdgeVertex],
) -> (TriangleMesh, usize) {
    let kept = &prep.kept;
    let abs2 = prep.tol.abs * prep.tol.abs;
    let at = |v: u32| mesh.positions[v as usize].as_dvec3();
    let mut inserted = 0;
    let mut indices = Vec::with_capacity(kept.len() + found.len());
    let mut source = Vec::with_capacity(kept.len() + found.len());
    let mut rest = found;
    let mut lists: [Vec<u32>; 3] = Default::default();
    for &tri in kept {
        let n = rest.iter().take_while(|f| f.tri == tri).count();
        let (mine, others) = rest.split_at(n);
        rest = others;
        for k in 0..3 {
            let (done, todo) = lists.split_at_mut(k);
            let list = &mut todo[0];
            list.clear();
            for f in mine.iter().filter(|f| f.edge as usize == k) {
                let same_place = list
                    .last()
                    .is_some_and(|&p| at(p).distance_squared(at(f.vertex)) <= abs2);
                // A point near a corner can lie on both edges there: it goes
                // into the first only (twice would repeat a vertex).
                let listed = done.iter().any(|l| l.contains(&f.vertex));
                if !same_place && !listed {
                    list.push(f.vertex);
                }
            }
            inserted += list.len();
        }
        let before = indices.len();
        triangulate(mesh.indices[tri as usize], &lists, &mut indices);
        source.extend(std::iter::repeat_n(tri as usize, indices.len() - before));
    }
    debug_assert!(rest.is_empty(), "T-junctions of dropped triangles");
    let per_tri = |attr: &Vec<u32>| -> Vec<u32> {
        if attr.is_empty() {
            Vec::new()
        } else {
            source.iter().map(|&t| attr[t]).collect()
        }
    };
    let out = TriangleMesh {
        positions: mesh.positions.clone(),
        indices,
        normals: mesh.normals.clone(),
        uvs: mesh.uvs.clone(),
        materials: mesh.materials.clone(),
        tri_material: per_tri(&mesh.tri_material),
        parts: mesh.parts.clone(),
        tri_part: per_tri(&mesh.tri_part),
    };
    (out, inserted)
}

/// Triangulate triangle `corners` with `lists[k]` inserted into edge `k`
/// (corner `k` → corner `k + 1`, points in order from corner `k`), appending
/// to `out`.
pub(crate) fn triangulate(corners: [u32; 3], lists: &[Vec<u32>; 3], out: &mut Vec<[u32; 3]>) {
    let counts = lists.each_ref().map(|l| l.len());
    let most = counts.iter().copied().max().unwrap_or(0);
    if most == 0 {
        out.push(corners);
        return;
    }
    let e = counts.iter().position(|&c| c == most).unwrap_or(0);
    let (x, y, z) = (corners[e], corners[(e + 1) % 3], corners[(e + 2) % 3]);
    let (m0, m1, m2) = (&lists[e], &lists[(e + 1) % 3], &lists[(e + 2) % 3]);
    let chain: Vec<u32> = std::iter::once(x)
        .chain(m0.iter().copied())
        .chain(std::iter::once(y))
        .collect();
    let last = chain.len() - 2;
    for (i, pair) in chain.windows(2).enumerate() {
        let (p, q) = (pair[0], pair[1]);
        if i == 0 && !m2.is_empty() {
            // (Z, X, P1) with points on Z → X: fan them from P1.
            fan(q, z, m2, x, out);
        } else if i == last && !m1.is_empty() {
            // (Z, Pk, Y) with points on Y → Z: fan them from Pk.
            fan(p, y, m1, z, out);
        } else {
            out.push([z, p, q]);
        }
    }
}

/// Triangles `(apex, c_i, c_i+1)` over the chain `from, mid…, to`.
fn fan(apex: u32, from: u32, mid: &[u32], to: u32, out: &mut Vec<[u32; 3]>) {
    let mut prev = from;
    for &c in mid.iter().chain(std::iter::once(&to)) {
        out.push([apex, prev, c]);
        prev = c;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec3, Vec3};

    /// Triangle (0,0)-(4,0)-(0,4) with points 3.. on its edges.
    fn points() -> Vec<Vec3> {
        let mut p = vec![
            Vec3::ZERO,
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(0.0, 4.0, 0.0),
        ];
        for i in 1..4 {
            p.push(Vec3::new(i as f32, 0.0, 0.0)); // 3,4,5 on edge 0
        }
        for i in 1..4 {
            p.push(Vec3::new(4.0 - i as f32, i as f32, 0.0)); // 6,7,8 on edge 1
        }
        for i in 1..4 {
            p.push(Vec3::new(0.0, 4.0 - i as f32, 0.0)); // 9,10,11 on edge 2
        }
        p
    }

    fn area(p: &[Vec3], t: [u32; 3]) -> f64 {
        let [a, b, c] = t.map(|i| p[i as usize].as_dvec3());
        0.5 * (b - a).cross(c - a).dot(DVec3::Z) // signed: +z is front
    }

    #[test]
    fn every_combination_covers_the_triangle_without_flat_pieces() {
        let p = points();
        for n0 in 0..4 {
            for n1 in 0..4 {
                for n2 in 0..4 {
                    let lists = [
                        (3..3 + n0).collect::<Vec<u32>>(),
                        (6..6 + n1).collect(),
                        (9..9 + n2).collect(),
                    ];
                    let mut out = Vec::new();
                    triangulate([0, 1, 2], &lists, &mut out);
                    assert_eq!(out.len() as u32, 1 + n0 + n1 + n2);
                    let total: f64 = out.iter().map(|&t| area(&p, t)).sum();
                    assert!((total - 8.0).abs() < 1e-12, "{n0} {n1} {n2}: {total}");
                    for &t in &out {
                        // positive: same orientation, and not flat
                        assert!(area(&p, t) > 1e-3, "{n0} {n1} {n2}: {t:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn one_split_side_is_a_fan_from_the_opposite_corner() {
        let mut out = Vec::new();
        triangulate([0, 1, 2], &[vec![4], vec![], vec![]], &mut out);
        assert_eq!(out, vec![[2, 0, 4], [2, 4, 1]]);
    }
}
