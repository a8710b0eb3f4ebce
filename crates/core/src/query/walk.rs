//! Tree queries: walk an [`Accel`]'s regions, prune those outside the shape,
//! test the triangles of the leaves reached exactly; and the brute-force
//! references that test every triangle.

use super::exact::Triangle64;
use super::shapes::QueryShape;
use crate::accel::Accel;
use crate::mesh::TriangleMesh;
use serde::Serialize;

/// Work done by one tree query, for timing experiments such as Kim's (2013)
/// frustum queries per split heuristic.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct QueryStats {
    /// Regions (nodes) tested against the shape.
    pub regions_tested: usize,
    /// Regions pruned by that test (their subtrees were skipped).
    pub regions_pruned: usize,
    /// Leaves reached.
    pub leaves: usize,
    /// Triangle references met in those leaves (a triangle stored in several
    /// leaves counts once per leaf).
    pub triangle_refs: usize,
    /// Exact triangle tests run (each triangle at most once).
    pub triangles_tested: usize,
}

/// The answer of a tree query: sorted unique ids and the work done.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct QueryResult {
    /// Sorted unique triangle (or part) ids.
    pub ids: Vec<u32>,
    /// Work done.
    pub stats: QueryStats,
}

/// Triangle `i` of `mesh` in f64.
#[inline]
pub(crate) fn triangle64(mesh: &TriangleMesh, i: usize) -> Triangle64 {
    mesh.triangle(i).map(|p| p.as_dvec3())
}

/// One bit per triangle, so a triangle reported by several leaves is tested
/// once.
struct BitSet(Vec<u64>);

impl BitSet {
    fn new(n: usize) -> Self {
        BitSet(vec![0; n.div_ceil(64)])
    }

    /// Set bit `i`; true when it was clear.
    #[inline]
    fn insert(&mut self, i: usize) -> bool {
        let (w, b) = (i / 64, 1u64 << (i % 64));
        let fresh = self.0[w] & b == 0;
        self.0[w] |= b;
        fresh
    }
}

/// Walk `accel` (built over `mesh`) with `shape`, and hand each triangle of
/// the leaves reached (once, however many leaves store it) to `decide`,
/// with a closure that runs the exact test; `decide` may skip it. Triangle
/// ids outside the mesh are ignored.
fn walk<S: QueryShape + ?Sized>(
    accel: &dyn Accel,
    mesh: &TriangleMesh,
    shape: &S,
    decide: &mut dyn FnMut(usize, &mut dyn FnMut() -> bool),
) -> QueryStats {
    let n = mesh.num_triangles();
    let mut seen = BitSet::new(n);
    let mut stats = QueryStats::default();
    let (mut regions_tested, mut regions_pruned) = (0, 0);
    accel.visit_regions(
        &mut |region| {
            regions_tested += 1;
            let go = shape.may_overlap_region(region);
            regions_pruned += usize::from(!go);
            go
        },
        &mut |prims| {
            stats.leaves += 1;
            stats.triangle_refs += prims.len();
            for &t in prims {
                let t = t as usize;
                if t < n && seen.insert(t) {
                    decide(t, &mut || {
                        stats.triangles_tested += 1;
                        shape.overlaps_triangle(&triangle64(mesh, t))
                    });
                }
            }
        },
    );
    stats.regions_tested = regions_tested;
    stats.regions_pruned = regions_pruned;
    stats
}

/// The triangles of `mesh` sharing at least one point with `shape`, found
/// through `accel` (which must have been built over `mesh`): Kim's (2013)
/// tree queries for frustum culling and collision, in the general form.
pub fn triangles_overlapping<S: QueryShape + ?Sized>(
    accel: &dyn Accel,
    mesh: &TriangleMesh,
    shape: &S,
) -> QueryResult {
    let mut ids = Vec::new();
    let stats = walk(accel, mesh, shape, &mut |t, test| {
        if test() {
            ids.push(t as u32);
        }
    });
    ids.sort_unstable();
    QueryResult { ids, stats }
}

/// The parts (objects, [`TriangleMesh::part_of`]) having at least one
/// triangle that shares a point with `shape`: Kim's (2013) "which objects
/// lie at least partly inside the view frustum". Once a part is found, its
/// other triangles are not tested.
pub fn parts_overlapping<S: QueryShape + ?Sized>(
    accel: &dyn Accel,
    mesh: &TriangleMesh,
    shape: &S,
) -> QueryResult {
    let mut found = vec![false; mesh.parts.len().max(1)];
    let stats = walk(accel, mesh, shape, &mut |t, test| {
        let p = mesh.part_of(t) as usize;
        if !found.get(p).copied().unwrap_or(false) && test() {
            if p >= found.len() {
                found.resize(p + 1, false);
            }
            found[p] = true;
        }
    });
    let ids = (0..found.len() as u32)
        .filter(|&p| found[p as usize])
        .collect();
    QueryResult { ids, stats }
}

/// Reference for [`triangles_overlapping`]: the exact test on every
/// triangle, no tree.
pub fn triangles_overlapping_brute<S: QueryShape + ?Sized>(
    mesh: &TriangleMesh,
    shape: &S,
) -> Vec<u32> {
    (0..mesh.num_triangles())
        .filter(|&t| shape.overlaps_triangle(&triangle64(mesh, t)))
        .map(|t| t as u32)
        .collect()
}

/// Reference for [`parts_overlapping`]: the parts of the triangles
/// [`triangles_overlapping_brute`] finds, sorted and unique.
pub fn parts_overlapping_brute<S: QueryShape + ?Sized>(mesh: &TriangleMesh, shape: &S) -> Vec<u32> {
    let mut parts: Vec<u32> = triangles_overlapping_brute(mesh, shape)
        .into_iter()
        .map(|t| mesh.part_of(t as usize))
        .collect();
    parts.sort_unstable();
    parts.dedup();
    parts
}
