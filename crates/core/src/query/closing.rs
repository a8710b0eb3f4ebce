//! The cap that closes a surface: triangles whose boundary cancels the
//! surface's own, so that surface and cap together enclose space and the
//! winding number of the pair is an integer, the signed count of any ray's
//! crossings.
//!
//! The generalized winding number of a surface `M` (Jacobson et al. 2013)
//! is the winding number of `M ∪ C` minus that of `C`, for any `C`. When
//! `C` closes `M`'s boundary, `M ∪ C` has no boundary, and its winding
//! number at `q` is the number of times a ray from `q` leaves through a
//! front face minus the times it enters through one (the degree of the
//! surface around `q`). Then `w_M(q) = crossings_{M ∪ C}(ray) - w_C(q)`:
//! one ray through both, plus the solid angle of the cap. The dragon and
//! the bunny need no cap at all; the teapot's lid rim and the engine's
//! open rims and seams get one.
//!
//! The boundary is found on the mesh's vertices welded by their exact
//! position (two triangles share an edge when its two end points are the
//! same `f32` triples, whether or not the mesh shares the vertices), with
//! orientation: an edge's net use is the number of
//! triangles running it `a → b` minus those running `b → a`, and every
//! edge with a net use is boundary, that many times. As many boundary
//! edges leave each corner as arrive, so the boundary splits into cycles,
//! and each cycle is closed by a triangulated disc facing against it.
//!
//! Any closing cap gives the same winding number; what the choice of cap
//! changes is the cost of its solid angle. A cone over the cycle from its
//! centre (the obvious cap) has long triangles only: a point near a large
//! open rim must sum all of them, one per boundary edge. The disc here is
//! cut by halving (a chord across each arc from its middle corner, then
//! the two half arcs), so its triangles shrink geometrically towards the
//! rim: seen from any point a few are large, and the many small ones
//! subtend a solid angle bounded by their area over the squared distance,
//! which occupancy adds up instead of summing them (see
//! [`super::winding`]).

use crate::mesh::TriangleMesh;
use glam::Vec3;
use rayon::prelude::*;

/// A vertex as a sort key: its position's bits (`-0.0` read as `0.0`) in
/// the high 96 bits, so that equal positions sort together, then its index.
fn key(p: Vec3, vertex: usize) -> u128 {
    let [x, y, z] = (p + Vec3::ZERO).to_array().map(f32::to_bits);
    (x as u128) << 96 | (y as u128) << 64 | (z as u128) << 32 | vertex as u128
}

/// The triangles that close the boundary of the surface `mesh` (see the
/// module documentation): none for a closed surface.
pub(crate) fn closing_cap(mesh: &TriangleMesh) -> Vec<[Vec3; 3]> {
    let (ids, positions) = weld(&mesh.positions);
    let mut boundary = boundary_edges(&mesh.indices, &ids, positions.len());
    if boundary.is_empty() {
        return Vec::new();
    }
    // Split the boundary into cycles: from each unused edge, follow unused
    // edges out of the corner reached until the walk comes back (every
    // corner has as many boundary edges leaving as arriving, so it does).
    boundary.sort_unstable();
    let mut used = vec![false; boundary.len()];
    let mut cap = Vec::new();
    let mut cycle: Vec<u32> = Vec::new();
    for start in 0..boundary.len() {
        if used[start] {
            continue;
        }
        used[start] = true;
        cycle.clear();
        cycle.push(boundary[start].0);
        let mut at = boundary[start].1;
        while at != boundary[start].0 {
            cycle.push(at);
            let from = boundary.partition_point(|&(a, _)| a < at);
            let next = (from..boundary.len())
                .take_while(|&e| boundary[e].0 == at)
                .find(|&e| !used[e])
                .expect("a boundary corner with as many edges out as in");
            used[next] = true;
            at = boundary[next].1;
        }
        let corners: Vec<Vec3> = cycle.iter().map(|&v| positions[v as usize]).collect();
        close_cycle(&corners, &mut cap);
    }
    cap
}

/// The vertices welded by exact position: each vertex's welded index, and
/// the welded positions in the order of their keys.
fn weld(points: &[Vec3]) -> (Vec<u32>, Vec<Vec3>) {
    let mut keys: Vec<u128> = points
        .par_iter()
        .enumerate()
        .map(|(i, &p)| key(p, i))
        .collect();
    keys.par_sort_unstable();
    let mut ids = vec![0u32; keys.len()];
    let mut positions: Vec<Vec3> = Vec::new();
    for (i, &k) in keys.iter().enumerate() {
        if i == 0 || k >> 32 != keys[i - 1] >> 32 {
            let bits = [(k >> 96) as u32, (k >> 64) as u32, (k >> 32) as u32];
            positions.push(Vec3::from_array(bits.map(f32::from_bits)));
        }
        ids[k as u32 as usize] = positions.len() as u32 - 1;
    }
    (ids, positions)
}

/// The boundary edges `a → b` of triangles `indices` over `n` welded
/// vertices (`ids` maps the triangles' vertices to them), each as often as
/// its net use: the triangles running it `a → b` less those running it
/// `b → a`. The edges are grouped by their lower vertex (a counting sort)
/// and each group's uses summed by its upper vertex.
fn boundary_edges(indices: &[[u32; 3]], ids: &[u32], n: usize) -> Vec<(u32, u32)> {
    let edges = || {
        indices.iter().flat_map(|t| {
            let v = t.map(|i| ids[i as usize]);
            (0..3).filter_map(move |k| {
                let (a, b) = (v[k], v[(k + 1) % 3]);
                (a != b).then_some((a.min(b), a.max(b), if a < b { 1i32 } else { -1 }))
            })
        })
    };
    let mut start = vec![0u32; n + 1];
    for (lo, _, _) in edges() {
        start[lo as usize + 1] += 1;
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut at = start.clone();
    let mut uses = vec![(0u32, 0i32); start[n] as usize];
    for (lo, hi, s) in edges() {
        uses[at[lo as usize] as usize] = (hi, s);
        at[lo as usize] += 1;
    }
    let mut groups: Vec<(u32, &mut [(u32, i32)])> = Vec::with_capacity(n);
    let mut rest = &mut uses[..];
    for v in 0..n {
        let (group, tail) = rest.split_at_mut((start[v + 1] - start[v]) as usize);
        groups.push((v as u32, group));
        rest = tail;
    }
    groups
        .into_par_iter()
        .with_min_len(1 << 12)
        .flat_map_iter(|(lo, g)| {
            g.sort_unstable_by_key(|&(hi, _)| hi);
            let mut open = Vec::new();
            for run in g.chunk_by(|x, y| x.0 == y.0) {
                let net: i32 = run.iter().map(|&(_, s)| s).sum();
                let hi = run[0].0;
                let edge = if net > 0 { (lo, hi) } else { (hi, lo) };
                open.extend(std::iter::repeat_n(edge, net.unsigned_abs() as usize));
            }
            open
        })
        .collect()
}

/// Appends the triangles that close one boundary cycle `c[0] → c[1] → …
/// → c[0]`, facing against it: the cycle is cut in three arcs at thirds
/// of its length, and each arc `c[i] … c[j]` is closed by its chord,
/// triangle `(c[j], c[m], c[i])` from its middle corner `m` and the two
/// half arcs in turn. Triangles shrink towards the boundary, so that
/// seen from any point only a few are large and the many small ones are
/// bounded by their area (see [`super::winding`]).
fn close_cycle(c: &[Vec3], cap: &mut Vec<[Vec3; 3]>) {
    fn arc(c: &[Vec3], i: usize, j: usize, cap: &mut Vec<[Vec3; 3]>) {
        if j - i < 2 {
            return;
        }
        let m = (i + j) / 2;
        cap.push([c[j % c.len()], c[m], c[i]]);
        arc(c, i, m, cap);
        arc(c, m, j, cap);
    }
    let n = c.len();
    if n < 3 {
        return;
    }
    let (a, b) = (n / 3, 2 * n / 3);
    cap.push([c[b], c[a], c[0]]);
    arc(c, 0, a, cap);
    arc(c, a, b, cap);
    arc(c, b, n, cap);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::icosphere::Icosphere;

    /// A position's bits, `-0.0` read as `0.0`.
    fn bits(p: Vec3) -> [u32; 3] {
        (p + Vec3::ZERO).to_array().map(f32::to_bits)
    }

    /// Net use of every undirected edge of `tris`, welded by position.
    fn net_uses(tris: &[[Vec3; 3]]) -> std::collections::HashMap<([u32; 3], [u32; 3]), i32> {
        let mut net = std::collections::HashMap::new();
        for t in tris {
            for k in 0..3 {
                let (a, b) = (bits(t[k]), bits(t[(k + 1) % 3]));
                if a == b {
                    continue;
                }
                let (e, s) = if a < b { ((a, b), 1) } else { ((b, a), -1) };
                *net.entry(e).or_insert(0) += s;
            }
        }
        net
    }

    fn sphere_tris(level: u32) -> Vec<[Vec3; 3]> {
        let s = Icosphere::new(level);
        s.indices
            .iter()
            .map(|t| t.map(|i| s.positions[i as usize]))
            .collect()
    }

    #[test]
    fn a_closed_surface_needs_no_cap() {
        assert!(closing_cap(&TriangleMesh::from_triangles(&sphere_tris(2))).is_empty());
    }

    /// An indexed mesh gets the cap of the same triangles as a soup (each
    /// corner a vertex of its own): welding by position makes them the
    /// same surface. Edits open the sphere, or keep it closed (a triangle
    /// and its reverse, a collapsed triangle), as an independent count of
    /// net edge uses by index says.
    #[test]
    fn an_indexed_mesh_and_its_soup_get_one_cap() {
        let s = Icosphere::new(2);
        let mut rng = crate::rng::Pcg32::new(9);
        for round in 0..200 {
            let mut idx = s.indices.clone();
            let pick = |rng: &mut crate::rng::Pcg32, idx: &Vec<[u32; 3]>| {
                idx[rng.below(idx.len() as u32) as usize]
            };
            match round % 5 {
                0 => {
                    idx.remove(rng.below(idx.len() as u32) as usize);
                }
                1 => {
                    let t = pick(&mut rng, &idx);
                    idx.push(t);
                }
                2 => {
                    let t = rng.below(idx.len() as u32) as usize;
                    idx[t].swap(0, 1);
                }
                3 => {
                    let t = pick(&mut rng, &idx);
                    idx.push(t);
                    idx.push([t[1], t[0], t[2]]);
                }
                _ => {
                    let t = pick(&mut rng, &idx);
                    idx.push([t[0], t[0], t[1]]);
                }
            }
            let mut net = std::collections::HashMap::new();
            for t in &idx {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    if a != b {
                        *net.entry((a.min(b), a.max(b))).or_insert(0) += if a < b { 1 } else { -1 };
                    }
                }
            }
            let closed = net.values().all(|&n| n == 0);
            assert_eq!(closed, round % 5 >= 3, "round {round}");
            let mesh = TriangleMesh::new(s.positions.clone(), idx);
            let tris: Vec<[Vec3; 3]> = (0..mesh.num_triangles())
                .map(|t| mesh.triangle(t))
                .collect();
            let cap = closing_cap(&mesh);
            assert_eq!(cap, closing_cap(&TriangleMesh::from_triangles(&tris)));
            assert_eq!(cap.is_empty(), closed, "round {round}");
        }
    }

    #[test]
    fn surface_and_cap_together_have_no_boundary() {
        let mut tris = sphere_tris(2);
        // Two holes, a duplicated triangle and a flipped one.
        tris.drain(10..14);
        tris.remove(100);
        let dup = tris[50];
        tris.push(dup);
        tris[70].swap(0, 1);
        let open = net_uses(&tris).values().filter(|&&n| n != 0).count();
        assert!(open > 0);
        let cap = closing_cap(&TriangleMesh::from_triangles(&tris));
        let mut all = tris.clone();
        all.extend(&cap);
        let left: Vec<_> = net_uses(&all)
            .into_iter()
            .filter(|&(_, n)| n != 0)
            .collect();
        assert!(left.is_empty(), "{} edges still open", left.len());
    }
}
