//! Kim's (2013) naive T-junction search: "for each polygon edge, find every
//! other vertex lying on it" by testing every edge against every point,
//! O(triangles × points). It is the reference the fast finder is checked
//! against, so it is kept as plain as the definition (parallel over
//! triangles only to keep the reference usable on mid-sized meshes).

use super::edge_test::EdgeTest;
use super::{EdgeVertex, Prepared, TJunctionError};
use crate::mesh::TriangleMesh;
use rayon::prelude::*;

/// Largest number of (kept triangle × distinct point) pairs the
/// naive finder accepts: 2·10⁹, i.e. 6·10⁹ edge tests, about 12 s on one
/// core (1.2·10⁹ pairs took 7 s in release on the development machine).
/// Beyond it, [`find_naive`](super::find_naive) returns
/// [`TJunctionError::TooLarge`].
pub const NAIVE_MAX_PAIRS: u64 = 2_000_000_000;

/// Every edge of every kept triangle against every point.
pub(crate) fn find(
    mesh: &TriangleMesh,
    prep: &Prepared,
) -> Result<Vec<EdgeVertex>, TJunctionError> {
    let (triangles, points) = (prep.kept.len(), prep.points.len());
    if triangles as u64 * points as u64 > NAIVE_MAX_PAIRS {
        return Err(TJunctionError::TooLarge { triangles, points });
    }
    let mut found: Vec<EdgeVertex> = prep
        .kept
        .par_iter()
        .flat_map_iter(|&tri| {
            let idx = mesh.indices[tri as usize];
            let mut out = Vec::new();
            for edge in 0..3 {
                let (a, b) = (idx[edge], idx[(edge + 1) % 3]);
                let pa = mesh.positions[a as usize];
                let pb = mesh.positions[b as usize];
                let Some(test) = EdgeTest::new(pa, pb, prep.tol) else {
                    continue;
                };
                for (&vertex, &pv) in prep.points.rep.iter().zip(&prep.points.pos) {
                    if let Some(t) = test.test(pv) {
                        out.push(EdgeVertex {
                            tri,
                            edge: edge as u8,
                            vertex,
                            t,
                        });
                    }
                }
            }
            out
        })
        .collect();
    canonical_sort(&mut found);
    Ok(found)
}

/// Sort into the canonical order `(tri, edge, t, vertex)` shared by both
/// finders.
pub(crate) fn canonical_sort(found: &mut [EdgeVertex]) {
    found.par_sort_unstable_by(|x, y| {
        (x.tri, x.edge)
            .cmp(&(y.tri, y.edge))
            .then(x.t.total_cmp(&y.t))
            .then(x.vertex.cmp(&y.vertex))
    });
}
