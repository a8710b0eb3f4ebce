//! Kim's (2013) split-plane heuristic for kd-trees in games.
//!
//! Every candidate plane (the bounds of the triangle pieces in the node,
//! along each axis) sorts the pieces into front, back and straddling
//! ("splits"); the plane with the lowest score
//! `|front − back| · (20 − H) + splits · H` wins, for an integer weight `H`
//! in `0..=20` (0: balance only, 20: fewest cuts only). Straddling pieces
//! are cut in two, one part to each side, so the tree ends with a *cut
//! mesh*: every triangle replaced by its pieces, which share the vertices a
//! cut creates but leave T-junctions against neighbours that were not cut
//! there ([`crate::tjunction`] removes them).
//!
//! For ray queries the leaves list whole triangles (every triangle whose
//! tolerance band meets the cell, as in the other builds), so rays see the
//! original surface and agree with brute force; the pieces are what the
//! heuristic counts and what [`cut_mesh`] returns.

use super::clip::{clip_triangle_bounds, reference_box, round_down, round_up};
use super::refs::{leaf_of, root_refs, Ref};
use super::tree::{split_cell, KdBuildNode};
use super::{KdOptions, TriangleSet};
use crate::aabb::Aabb;
use crate::mesh::TriangleMesh;
use glam::DVec3;
use rayon::prelude::*;
use std::collections::HashMap;

/// A triangle in a node: its ray reference and the exact bounds of its
/// piece in the cell (`None` when only its tolerance band reaches in).
#[derive(Clone, Copy)]
struct GameRef {
    r: Ref,
    piece: Option<(DVec3, DVec3)>,
}

/// A leaf's cell and the triangles with a piece in it.
#[derive(Clone, Debug)]
pub struct GameLeaf {
    /// The leaf's cell.
    pub cell: Aabb,
    /// Triangles with a piece in the cell, ascending.
    pub pieces: Vec<u32>,
}

/// What the game build returns besides the tree.
pub struct GameBuild {
    /// Leaves in tree order with their pieces.
    pub leaves: Vec<GameLeaf>,
    /// Pieces cut by a split plane, summed over all splits (Kim's (2013)
    /// "number of split polygons").
    pub cuts: usize,
}

/// Build Kim's (2013) tree with weight `h` over `mesh`: the tree, its root
/// cell, and the leaves' pieces (for [`cut_mesh`]).
pub fn build_game(mesh: &TriangleMesh, h: u8, opts: &KdOptions) -> (KdBuildNode, Aabb, GameBuild) {
    let set = TriangleSet::new(mesh);
    let cell = set.root_cell();
    if set.ids.is_empty() {
        let empty = GameBuild {
            leaves: Vec::new(),
            cuts: 0,
        };
        return (KdBuildNode::Leaf(Vec::new()), cell, empty);
    }
    let (root, game) = build(&set, &cell, h, opts);
    (root, cell, game)
}

/// Build with weight `h` over `set` with root cell `cell`.
pub(crate) fn build(
    set: &TriangleSet,
    cell: &Aabb,
    h: u8,
    opts: &KdOptions,
) -> (KdBuildNode, GameBuild) {
    let refs: Vec<GameRef> = root_refs(set, cell)
        .into_iter()
        .map(|r| {
            let t = &set.corners[r.tri as usize];
            GameRef {
                r,
                piece: Some((t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]))),
            }
        })
        .collect();
    let max_depth = opts.depth_limit(refs.len());
    let ctx = Ctx {
        set,
        h: h.min(20) as i64,
        max_depth,
        opts,
    };
    let (root, leaves, cuts) = ctx.node(refs, *cell, 0);
    (root, GameBuild { leaves, cuts })
}

struct Ctx<'a> {
    set: &'a TriangleSet,
    h: i64,
    max_depth: u32,
    opts: &'a KdOptions,
}

impl Ctx<'_> {
    fn node(
        &self,
        refs: Vec<GameRef>,
        cell: Aabb,
        depth: u32,
    ) -> (KdBuildNode, Vec<GameLeaf>, usize) {
        let pieces = refs.iter().filter(|g| g.piece.is_some()).count();
        let plane = if pieces <= self.opts.max_leaf_size.max(1) || depth >= self.max_depth {
            None
        } else {
            self.best_plane(&refs, &cell)
        };
        let Some((axis, pos)) = plane else {
            let rays: Vec<Ref> = refs.iter().map(|g| g.r).collect();
            let mut with_piece: Vec<u32> = refs
                .iter()
                .filter(|g| g.piece.is_some())
                .map(|g| g.r.tri)
                .collect();
            with_piece.sort_unstable();
            let leaf = GameLeaf {
                cell,
                pieces: with_piece,
            };
            return (leaf_of(&rays), vec![leaf], 0);
        };
        let (l, r, cuts) = self.split(&refs, &cell, axis, pos);
        drop(refs);
        let [lc, rc] = split_cell(&cell, axis, pos);
        let n = l.len() + r.len();
        let ((ln, mut ll, lcuts), (rn, rl, rcuts)) = if n > self.opts.parallel_threshold {
            rayon::join(
                || self.node(l, lc, depth + 1),
                || self.node(r, rc, depth + 1),
            )
        } else {
            (self.node(l, lc, depth + 1), self.node(r, rc, depth + 1))
        };
        ll.extend(rl);
        let inner = KdBuildNode::Inner {
            axis: axis as u8,
            split: pos,
            children: Box::new([ln, rn]),
        };
        (inner, ll, cuts + lcuts + rcuts)
    }

    /// The lowest-scoring plane that leaves at least one whole piece on each
    /// side (ties: the first by axis, then position).
    fn best_plane(&self, refs: &[GameRef], cell: &Aabb) -> Option<(usize, f32)> {
        let mut best: Option<(i64, usize, f32)> = None;
        for axis in 0..3 {
            let mut mins = Vec::with_capacity(refs.len());
            let mut maxs = Vec::with_capacity(refs.len());
            let mut planar = Vec::new();
            for (lo, hi) in refs.iter().filter_map(|g| g.piece) {
                mins.push(lo[axis]);
                maxs.push(hi[axis]);
                if lo[axis] == hi[axis] {
                    planar.push(lo[axis]);
                }
            }
            let m = mins.len();
            let key = |a: &f64, b: &f64| a.partial_cmp(b).unwrap();
            mins.sort_unstable_by(key);
            maxs.sort_unstable_by(key);
            planar.sort_unstable_by(key);
            // Candidates: piece bounds rounded outwards to f32, so the piece
            // that proposes a plane lies wholly on one side of it.
            let one = |v: f64, up: bool| {
                let d = DVec3::splat(v);
                if up {
                    round_up(d).x
                } else {
                    round_down(d).x
                }
            };
            let mut cands: Vec<f32> = mins
                .iter()
                .map(|&v| one(v, false))
                .chain(maxs.iter().map(|&v| one(v, true)))
                .filter(|&p| p > cell.min[axis] && p < cell.max[axis])
                .collect();
            cands.sort_unstable_by(|a, b| a.partial_cmp(b).unwrap());
            cands.dedup();
            for p in cands {
                let pf = p as f64;
                let back = maxs.partition_point(|&x| x <= pf);
                let at_or_above = m - mins.partition_point(|&x| x < pf);
                let planar_here =
                    planar.partition_point(|&x| x <= pf) - planar.partition_point(|&x| x < pf);
                let front = at_or_above - planar_here;
                if back == 0 || front == 0 {
                    continue;
                }
                let splits = (m - back - front) as i64;
                let score = (front as i64 - back as i64).abs() * (20 - self.h) + splits * self.h;
                if best.is_none_or(|b| score < b.0) {
                    best = Some((score, axis, p));
                }
            }
        }
        best.map(|(_, a, p)| (a, p))
    }

    /// Distribute the references: ray references by their band boxes,
    /// pieces by their exact bounds, straddling pieces cut in two.
    fn split(
        &self,
        refs: &[GameRef],
        cell: &Aabb,
        axis: usize,
        pos: f32,
    ) -> (Vec<GameRef>, Vec<GameRef>, usize) {
        let cells = split_cell(cell, axis, pos);
        let pf = pos as f64;
        let mut sides: [Vec<GameRef>; 2] = [Vec::new(), Vec::new()];
        let mut cuts = 0;
        for g in refs {
            let t = g.r.tri as usize;
            let tri = &self.set.corners[t];
            let pieces: [Option<(DVec3, DVec3)>; 2] = match g.piece {
                None => [None, None],
                Some((_, hi)) if hi[axis] <= pf => [g.piece, None],
                Some((lo, _)) if lo[axis] >= pf => [None, g.piece],
                Some(_) => {
                    cuts += 1;
                    cells.map(|c| clip_triangle_bounds(tri, c.min.as_dvec3(), c.max.as_dvec3()))
                }
            };
            for s in 0..2 {
                let below = s == 0;
                let one_sided = if below {
                    g.r.bounds.max[axis] <= pos && g.r.bounds.min[axis] < pos
                } else {
                    g.r.bounds.min[axis] >= pos && g.r.bounds.max[axis] > pos
                };
                let other_only = if below {
                    g.r.bounds.min[axis] >= pos && g.r.bounds.max[axis] > pos
                } else {
                    g.r.bounds.max[axis] <= pos && g.r.bounds.min[axis] < pos
                };
                let bounds = if one_sided {
                    Some(g.r.bounds)
                } else if other_only {
                    None
                } else {
                    reference_box(tri, self.set.band[t], &cells[s])
                        .map(|b| b.intersection(g.r.bounds))
                };
                let bounds = match (bounds, pieces[s]) {
                    (Some(b), _) => Some(b),
                    // The piece is there though rounding dropped the band
                    // box: keep the piece's own box.
                    (None, Some((lo, hi))) => {
                        Some(Aabb::new(round_down(lo), round_up(hi)).intersection(cells[s]))
                    }
                    (None, None) => None,
                };
                if let Some(bounds) = bounds {
                    sides[s].push(GameRef {
                        r: Ref {
                            tri: g.r.tri,
                            bounds,
                        },
                        piece: pieces[s],
                    });
                }
            }
        }
        let [l, r] = sides;
        (l, r, cuts)
    }
}

/// The mesh of pieces a game build cut the triangles into.
#[derive(Clone, Debug)]
pub struct CutMesh {
    /// The pieces, triangulated; the original vertices keep their indices
    /// and cut points are appended, shared by all pieces that meet there.
    pub mesh: TriangleMesh,
    /// For each triangle of `mesh`, the original triangle it came from.
    pub source: Vec<u32>,
    /// Original triangles that ended up in more than one piece.
    pub split_triangles: usize,
}

/// Symbolic name of a polygon vertex, so that a cut point computed for two
/// neighbouring triangles (or two cells) gets one vertex and one position.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
enum Key {
    /// A mesh vertex.
    Vertex(u32),
    /// Mesh edge `(a, b)`, `a < b`, cut by the plane `x[axis] = pos`.
    Edge(u32, u32, u8, u32),
    /// Inside triangle `tri`: the point on two cut planes (axis, pos bits).
    Face(u32, u8, u32, u8, u32),
}

/// What an edge of a clipped polygon lies on.
#[derive(Clone, Copy)]
enum Support {
    /// A mesh edge `(a, b)`, `a < b`.
    Edge(u32, u32),
    /// A cut plane (axis, position).
    Plane(u8, f32),
}

#[derive(Clone, Copy)]
struct PolyVertex {
    key: Key,
    p: DVec3,
    /// Support of the edge from this vertex to the next.
    next: Support,
}

/// The cut mesh of a game build over `mesh` (see the module docs).
pub fn cut_mesh(mesh: &TriangleMesh, build: &GameBuild) -> CutMesh {
    let polys: Vec<Vec<(u32, Vec<PolyVertex>)>> = build
        .leaves
        .par_iter()
        .map(|leaf| {
            leaf.pieces
                .iter()
                .filter_map(|&t| {
                    let poly = clip_symbolic(mesh, t, &leaf.cell);
                    (poly.len() >= 3).then_some((t, poly))
                })
                .collect()
        })
        .collect();
    let mut positions = mesh.positions.clone();
    let mut index: HashMap<Key, u32> = HashMap::new();
    let mut indices = Vec::new();
    let mut source = Vec::new();
    let mut pieces_of = vec![0u32; mesh.num_triangles()];
    let named: Vec<(u32, Vec<u32>)> = polys
        .iter()
        .flatten()
        .map(|(t, poly)| {
            let ids = poly
                .iter()
                .map(|v| match v.key {
                    Key::Vertex(i) => i,
                    k => *index.entry(k).or_insert_with(|| {
                        positions.push(v.p.as_vec3());
                        positions.len() as u32 - 1
                    }),
                })
                .collect();
            (*t, ids)
        })
        .collect();
    let same = weld_new_vertices(&positions, mesh.positions.len());
    for (t, ids) in &named {
        pieces_of[*t as usize] += 1;
        let ids: Vec<u32> = ids.iter().map(|&i| same[i as usize]).collect();
        for i in 1..ids.len() - 1 {
            let tri = [ids[0], ids[i], ids[i + 1]];
            let [a, b, c] = tri.map(|k| positions[k as usize].as_dvec3());
            if tri[0] != tri[1]
                && tri[1] != tri[2]
                && tri[0] != tri[2]
                && (b - a).cross(c - a).length_squared() > 0.0
            {
                indices.push(tri);
                source.push(*t);
            }
        }
    }
    let mut out = TriangleMesh::new(positions, indices);
    out.parts = mesh.parts.clone();
    out.materials = mesh.materials.clone();
    if !mesh.tri_part.is_empty() {
        out.tri_part = source.iter().map(|&t| mesh.tri_part[t as usize]).collect();
    }
    if !mesh.tri_material.is_empty() {
        out.tri_material = source
            .iter()
            .map(|&t| mesh.tri_material[t as usize])
            .collect();
    }
    CutMesh {
        mesh: out,
        source,
        split_triangles: pieces_of.iter().filter(|&&c| c > 1).count(),
    }
}

/// For each vertex, the vertex it stands for: cut points (from `first_new`
/// on) that land within 4 f32 ulps of the largest coordinate of an earlier
/// vertex are that vertex. A split plane can pass a rounding step away from
/// a vertex (planes are `f32`, cut points `f64` rounded), and would otherwise
/// leave two vertices at what is one point and sliver triangles between
/// them.
fn weld_new_vertices(positions: &[glam::Vec3], first_new: usize) -> Vec<u32> {
    let m = positions
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0f32, f32::max) as f64;
    let same = 4.0 * m * f32::EPSILON as f64;
    let mut map: Vec<u32> = (0..positions.len() as u32).collect();
    if same <= 0.0 || first_new >= positions.len() {
        return map;
    }
    let cell = |p: DVec3| (p / same).floor().as_i64vec3();
    let mut grid: HashMap<glam::I64Vec3, Vec<u32>> = HashMap::new();
    for (i, p) in positions.iter().enumerate() {
        let p = p.as_dvec3();
        let c = cell(p);
        if i >= first_new {
            let mut found: Option<u32> = None;
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        for &j in grid
                            .get(&(c + glam::I64Vec3::new(dx, dy, dz)))
                            .into_iter()
                            .flatten()
                        {
                            if (positions[j as usize].as_dvec3() - p).length() <= same
                                && found.is_none_or(|f| j < f)
                            {
                                found = Some(j);
                            }
                        }
                    }
                }
            }
            if let Some(j) = found {
                map[i] = j;
                continue;
            }
        }
        grid.entry(c).or_default().push(i as u32);
    }
    map
}

/// Clip triangle `t` of `mesh` to `cell`, naming every vertex symbolically
/// and computing each position from its name alone.
fn clip_symbolic(mesh: &TriangleMesh, t: u32, cell: &Aabb) -> Vec<PolyVertex> {
    let idx = mesh.indices[t as usize];
    let pos = |i: u32| mesh.positions[i as usize].as_dvec3();
    let edge = |a: u32, b: u32| Support::Edge(a.min(b), a.max(b));
    let mut poly: Vec<PolyVertex> = (0..3)
        .map(|k| PolyVertex {
            key: Key::Vertex(idx[k]),
            p: pos(idx[k]),
            next: edge(idx[k], idx[(k + 1) % 3]),
        })
        .collect();
    let [a, b, c] = idx.map(pos);
    let normal = (b - a).cross(c - a);
    let offset = normal.dot(a);
    for axis in 0..3 {
        for (bound, keep_below) in [(cell.min[axis], false), (cell.max[axis], true)] {
            let s = bound as f64;
            let inside = |p: DVec3| {
                if keep_below {
                    p[axis] <= s
                } else {
                    p[axis] >= s
                }
            };
            if poly.iter().all(|v| inside(v.p)) {
                continue;
            }
            let n = poly.len();
            let mut out = Vec::with_capacity(n + 2);
            for i in 0..n {
                let (p, q) = (poly[i], poly[(i + 1) % n]);
                let (pin, qin) = (inside(p.p), inside(q.p));
                if pin {
                    if !qin && p.p[axis] == s {
                        // P is on the plane: it is the exit point itself.
                        out.push(PolyVertex {
                            next: Support::Plane(axis as u8, bound),
                            ..p
                        });
                        continue;
                    }
                    out.push(p);
                }
                if pin != qin {
                    if qin && q.p[axis] == s {
                        continue;
                    }
                    let x = cut_point(mesh, t, p.next, axis, bound, normal, offset, p.p, q.p);
                    let next = if pin {
                        Support::Plane(axis as u8, bound)
                    } else {
                        p.next
                    };
                    out.push(PolyVertex { next, ..x });
                }
            }
            poly = out;
            if poly.len() < 3 {
                return Vec::new();
            }
        }
    }
    poly
}

/// The point where an edge with support `sup` (from `p` to `q`) crosses
/// the plane `x[axis] = bound`, named and computed canonically.
#[allow(clippy::too_many_arguments)]
fn cut_point(
    mesh: &TriangleMesh,
    t: u32,
    sup: Support,
    axis: usize,
    bound: f32,
    normal: DVec3,
    offset: f64,
    p: DVec3,
    q: DVec3,
) -> PolyVertex {
    let s = bound as f64;
    let lerp = |a: DVec3, b: DVec3| {
        let mut x = a + (b - a) * ((s - a[axis]) / (b[axis] - a[axis]));
        x[axis] = s;
        x
    };
    let placeholder = Support::Plane(axis as u8, bound);
    match sup {
        Support::Edge(a, b) => {
            let pa = mesh.positions[a as usize].as_dvec3();
            let pb = mesh.positions[b as usize].as_dvec3();
            PolyVertex {
                key: Key::Edge(a, b, axis as u8, bound.to_bits()),
                p: lerp(pa, pb),
                next: placeholder,
            }
        }
        Support::Plane(a1, s1) => {
            let (first, second) = if (a1 as usize) < axis {
                ((a1, s1), (axis as u8, bound))
            } else {
                ((axis as u8, bound), (a1, s1))
            };
            let key = Key::Face(t, first.0, first.1.to_bits(), second.0, second.1.to_bits());
            let third = 3 - first.0 as usize - second.0 as usize;
            let p = if first.0 != second.0 && third < 3 && normal[third] != 0.0 {
                let mut x = DVec3::ZERO;
                x[first.0 as usize] = first.1 as f64;
                x[second.0 as usize] = second.1 as f64;
                x[third] = (offset
                    - normal[first.0 as usize] * x[first.0 as usize]
                    - normal[second.0 as usize] * x[second.0 as usize])
                    / normal[third];
                x
            } else {
                lerp(p, q)
            };
            PolyVertex {
                key,
                p,
                next: placeholder,
            }
        }
    }
}
