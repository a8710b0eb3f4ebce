//! The fast T-junction finder: the naive search of Kim 2013 with a uniform
//! grid (spatial hashing) over the points, so each edge is tested only
//! against the points near it.
//!
//! The cell size is the median edge length (the mean is pulled up by the
//! few long edges of CAD meshes, whose dense clusters then crowd a cell), so
//! a typical edge touches a few cells and a cell holds a few points. The
//! cells are kept in a hash map from cell key to a run of the points sorted
//! by key. An edge is cut into pieces no longer
//! than a cell; each piece's box, grown by the edge's reach (the largest
//! distance [`EdgeTest::test`] accepts) and a rounding margin, is looked up
//! cell by cell. Every point that passes the test lies within the reach of
//! some piece, and cell coordinates are a monotone function of position, so
//! the candidates are a superset of the answers; the same predicate then
//! decides, which makes the result identical to the naive one. Cost: at
//! most 8 cell lookups per cell length of edge (while the reach is below a
//! cell), near-linear in the mesh size, parallel over triangles.

use super::edge_test::EdgeTest;
use super::naive::canonical_sort;
use super::{EdgeVertex, Prepared};
use crate::mesh::TriangleMesh;
use glam::DVec3;
use rayon::prelude::*;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Cells per axis at most (keys stay below 2^63).
const MAX_CELLS_PER_AXIS: f64 = (1u64 << 20) as f64;
/// Pieces an edge is cut into at most (a longer piece only visits more cells).
const MAX_PIECES: usize = 1 << 16;

/// A multiplicative hash for the grid's `u64` cell keys.
#[derive(Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(self.0 ^ b as u64);
        }
    }
    #[inline]
    fn write_u64(&mut self, x: u64) {
        self.0 = (x ^ (x >> 31)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
    #[inline]
    fn finish(&self) -> u64 {
        self.0 ^ (self.0 >> 29)
    }
}

/// Points bucketed by cell.
struct Grid {
    origin: DVec3,
    inv_h: f64,
    h: f64,
    dims: [i64; 3],
    /// Cell key → range in `items`.
    cells: HashMap<u64, (u32, u32), BuildHasherDefault<CellHasher>>,
    /// Point indices ordered by cell.
    items: Vec<u32>,
}

impl Grid {
    fn build(mesh: &TriangleMesh, prep: &Prepared) -> Grid {
        let (lo, hi) = prep.points.pos.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(p.as_dvec3()), hi.max(p.as_dvec3())),
        );
        // Median edge length: robust to the few long edges and dense
        // clusters of CAD meshes, where the mean gives crowded cells.
        let mut lengths: Vec<f64> = prep
            .kept
            .par_iter()
            .flat_map_iter(|&t| {
                let [a, b, c] = mesh.triangle(t as usize).map(|p| p.as_dvec3());
                [a.distance(b), b.distance(c), c.distance(a)]
            })
            .collect();
        let mid = lengths.len() / 2;
        let mut h = if lengths.is_empty() {
            1.0
        } else {
            *lengths.select_nth_unstable_by(mid, f64::total_cmp).1
        };
        let extent = (hi - lo).max(DVec3::ZERO);
        h = h.max(extent.max_element() / MAX_CELLS_PER_AXIS);
        if !(h > 0.0 && h.is_finite()) {
            h = 1.0;
        }
        let origin = if lo.is_finite() { lo } else { DVec3::ZERO };
        let dims = (extent / h).floor().as_i64vec3().to_array().map(|d| d + 1);
        let mut grid = Grid {
            origin,
            inv_h: 1.0 / h,
            h,
            dims,
            cells: HashMap::default(),
            items: Vec::new(),
        };
        let mut keyed: Vec<(u64, u32)> = prep
            .points
            .pos
            .par_iter()
            .enumerate()
            .map(|(i, p)| (grid.key(grid.cell(p.as_dvec3())), i as u32))
            .collect();
        keyed.par_sort_unstable();
        grid.cells.reserve(keyed.len());
        let mut start = 0;
        for run in keyed.chunk_by(|x, y| x.0 == y.0) {
            let end = start + run.len();
            grid.cells.insert(run[0].0, (start as u32, end as u32));
            start = end;
        }
        grid.items = keyed.into_iter().map(|(_, i)| i).collect();
        grid
    }

    /// Cell coordinates of `p`, clamped to the grid (monotone in `p`;
    /// truncation is the floor once negatives are clamped to 0).
    #[inline]
    fn cell(&self, p: DVec3) -> [i64; 3] {
        let c = ((p - self.origin) * self.inv_h).max(DVec3::ZERO);
        [
            (c.x as i64).min(self.dims[0] - 1),
            (c.y as i64).min(self.dims[1] - 1),
            (c.z as i64).min(self.dims[2] - 1),
        ]
    }

    #[inline]
    fn key(&self, c: [i64; 3]) -> u64 {
        (c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2])) as u64
    }

    /// Append to `out` every point in a cell that the box `[lo, hi]` touches.
    fn gather(&self, lo: DVec3, hi: DVec3, out: &mut Vec<u32>) {
        let (l, u) = (self.cell(lo), self.cell(hi));
        for z in l[2]..=u[2] {
            for y in l[1]..=u[1] {
                for x in l[0]..=u[0] {
                    if let Some(&(s, e)) = self.cells.get(&self.key([x, y, z])) {
                        out.extend_from_slice(&self.items[s as usize..e as usize]);
                    }
                }
            }
        }
    }

    /// Indices of the points that may pass `test`: sorted, without repeats.
    fn candidates(&self, test: &EdgeTest, out: &mut Vec<u32>) {
        out.clear();
        let (a, b) = test.ends();
        let ab = b - a;
        let scale = a.abs().max_element().max(b.abs().max_element());
        // Rounding of the piece ends below is ~1e-16 of the coordinates.
        let margin = test.reach() * (1.0 + 1e-9) + 1e-9 * self.h + 1e-12 * scale;
        let q = ab.length() * self.inv_h;
        let pieces = (q as usize + usize::from(q.fract() > 0.0)).clamp(1, MAX_PIECES);
        let inv = 1.0 / pieces as f64;
        for i in 0..pieces {
            let p0 = a + ab * (i as f64 * inv);
            let p1 = if i + 1 == pieces {
                b
            } else {
                a + ab * ((i + 1) as f64 * inv)
            };
            let p0 = if i == 0 { a } else { p0 };
            self.gather(p0.min(p1) - margin, p0.max(p1) + margin, out);
        }
        if pieces > 1 {
            out.sort_unstable();
            out.dedup();
        }
    }
}

/// Find every T-junction of the kept triangles, in the canonical order.
pub(crate) fn find(mesh: &TriangleMesh, prep: &Prepared) -> Vec<EdgeVertex> {
    if prep.points.len() == 0 {
        return Vec::new();
    }
    let grid = Grid::build(mesh, prep);
    let per_triangle: Vec<Vec<EdgeVertex>> = prep
        .kept
        .par_iter()
        .map_init(Vec::new, |scratch, &tri| {
            let idx = mesh.indices[tri as usize];
            let mut out = Vec::new();
            for edge in 0..3 {
                let pa = mesh.positions[idx[edge] as usize];
                let pb = mesh.positions[idx[(edge + 1) % 3] as usize];
                let Some(test) = EdgeTest::new(pa, pb, prep.tol) else {
                    continue;
                };
                grid.candidates(&test, scratch);
                for &p in scratch.iter() {
                    if let Some(t) = test.test(prep.points.pos[p as usize]) {
                        out.push(EdgeVertex {
                            tri,
                            edge: edge as u8,
                            vertex: prep.points.rep[p as usize],
                            t,
                        });
                    }
                }
            }
            out
        })
        .collect();
    let mut found: Vec<EdgeVertex> = per_triangle.into_iter().flatten().collect();
    canonical_sort(&mut found);
    found
}
