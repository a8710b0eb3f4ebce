//! T-junction elimination (Kim 2013, "Tree build heuristics for spatial
//! partitioning trees of 3D games", section on T-junctions).
//!
//! Cutting polygons along split planes (as the game-heuristic kd-tree build
//! does) leaves vertices lying on the edges of neighbouring polygons that were
//! not cut: **T-junctions**. They cause cracks and lighting seams, because the
//! two sides of the edge are no longer made of the same segments. Kim (2013)
//! removes them by finding, for every polygon edge, every other vertex lying on
//! it, inserting a copy of that vertex into the edge and re-tessellating the
//! polygon. Its naive form tests every edge against every vertex, O(n²).
//!
//! # Definitions used here
//! - **Points.** Vertices at identical positions (f32 `==` on each coordinate,
//!   so `-0.0` equals `0.0`) are one point: the finder welds by exact position
//!   and names each point by the smallest vertex index at that position among
//!   the vertices of the kept triangles. Vertices that no kept triangle uses
//!   are not points.
//! - **Rounding allowance** `r = ulps · 2^-23 · M`, where `M` is the largest
//!   coordinate magnitude of the mesh's positions: a cut point computed in
//!   f32 lies up to about one ulp of its coordinates off the edge it was cut
//!   from, which for small edges far from the origin is much more than
//!   `1e-6 · |AB|`. Two points no farther apart than `r` are at the same
//!   place (f32 noise, as left by independent transforms or tessellations of
//!   one CAD surface).
//! - **T-junction.** A point V and an edge AB of a kept triangle such that V is
//!   not at the place of A or B (`|VA| > r`, `|VB| > r`; with `ulps = 0` this
//!   is "not positionally equal"), the parameter `t` of V projected on AB lies
//!   strictly inside (0, 1), and the distance from V to the line AB is at most
//!   `tolerance · |AB| + r`, all computed in f64 (see [`TJunctionOptions`]).
//!   Edge `k` of triangle `[i0, i1, i2]` runs from corner `k` to corner
//!   `(k + 1) % 3`.
//! - **Degenerate triangles** (two corners at the same place, or a corner
//!   lying on the opposite edge by the test above, i.e. flat within the
//!   tolerance) have no usable area: they are dropped, and their vertices
//!   count as points only through other triangles. In a closed mesh this keeps
//!   the surface closed: the neighbour across the long edge of a dropped
//!   sliver receives its middle vertex as a T-junction.
//!
//! # Elimination
//! Each kept triangle receives the T-junction points of its three edges,
//! sorted along each edge, and is re-triangulated as the convex polygon they
//! form, with no new vertices (the inserted vertex's existing index is reused,
//! so normals and texture coordinates are those of that vertex), never
//! forming a triangle from three points of one edge (see `retriangulate.rs`).
//! Of several points of one edge at the same place, only the first along the
//! edge is inserted (the others are then at the place of a corner); a point
//! lying on two edges of a triangle (next to their shared corner) is
//! inserted into the first of them only.
//! The pieces keep the triangle's orientation, material and part, and come in
//! the order of their source triangles: the canonical order that makes the
//! naive and the fast forms give the same mesh. Because inserting points
//! creates new, shorter edges and diagonals, [`eliminate`] repeats find and
//! re-triangulate until a find pass comes back empty (at most
//! [`TJunctionOptions::max_rounds`] re-triangulations); the last, empty, pass
//! is the proof that no point lies on any edge.
//!
//! Limitation: distinct points closer together than about the tolerance
//! reach but farther apart than `r` (near-duplicates that are not rounding
//! noise, as in some CAD tessellations) cannot always be fixed this way: a
//! triangle having two of them as corners is usually flat within the
//! tolerance, and dropping it exposes one of them as a T-junction again. Such inputs stop after `max_rounds` with a few
//! T-junctions or flat triangles left, counted in the report
//! ([`TJunctionReport::remaining_t_junctions`]); welding vertices within a
//! distance (which moves geometry) is the usual cure and is not done here.
//!
//! Two finders give identical answers (same [`EdgeVertex`] list in the
//! canonical order, because both use the same predicate on the same points):
//! [`find_naive`] (Kim's (2013) reference, every edge against every point,
//! refusing inputs over [`NAIVE_MAX_PAIRS`]) and [`find_fast`] (a uniform
//! grid over the points; each edge visits only the cells along it).

use crate::mesh::{MeshError, TriangleMesh};
use serde::Serialize;
use std::fmt;
use std::time::Instant;

mod edge_test;
mod fast;
mod naive;
mod points;
mod retriangulate;

pub use naive::NAIVE_MAX_PAIRS;

/// Tolerances of the T-junction test (Kim 2013: "distance to the edge line
/// ≈ 0 and within the segment").
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TJunctionOptions {
    /// Distance allowed from the edge line, relative to the edge length.
    /// Default `1e-6`.
    pub tolerance: f64,
    /// Rounding allowance `r` in units of `2^-23 · M`, `M` the largest
    /// coordinate magnitude of the mesh (f32 ulps of the mesh's largest
    /// coordinate): extra distance from the edge line, and the distance
    /// within which two points are at the same place. Default `4`.
    pub ulps: f64,
    /// Most re-triangulation rounds [`eliminate`] runs (each followed by a
    /// find pass). Default `4`; one is enough unless points lie within the
    /// tolerance of each other.
    pub max_rounds: usize,
}

impl Default for TJunctionOptions {
    fn default() -> Self {
        TJunctionOptions {
            tolerance: 1e-6,
            ulps: 4.0,
            max_rounds: 4,
        }
    }
}

/// A T-junction: `vertex` lies inside edge `edge` of triangle `tri`
/// (Kim 2013). Lists are in the canonical order `(tri, edge, t, vertex)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct EdgeVertex {
    /// Triangle index in the mesh.
    pub tri: u32,
    /// Edge 0, 1 or 2: from corner `edge` to corner `(edge + 1) % 3`.
    pub edge: u8,
    /// Vertex index of the point (the smallest index at its position).
    pub vertex: u32,
    /// Position along the edge, strictly inside (0, 1).
    pub t: f64,
}

/// Which finder [`eliminate`] uses (Kim's (2013) naive O(n²) one or ours).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Every edge against every point: O(triangles × points).
    Naive,
    /// Uniform grid over the points, edges walk their cells; parallel.
    Fast,
}

impl Method {
    /// Lower-case name, as the command line spells it (`raykit tjunctions
    /// --method`).
    pub fn name(self) -> &'static str {
        match self {
            Method::Naive => "naive",
            Method::Fast => "fast",
        }
    }
}

/// Why T-junction elimination refused its input (Kim's (2013) naive finder is
/// O(n²), so it has a size limit).
#[derive(Clone, Debug, PartialEq)]
pub enum TJunctionError {
    /// The mesh fails [`TriangleMesh::validate`].
    Invalid(MeshError),
    /// An option is out of range (negative or not finite).
    Options(String),
    /// The naive finder would test more than [`NAIVE_MAX_PAIRS`] triangle ×
    /// point pairs.
    TooLarge {
        /// Kept (non-degenerate) triangles.
        triangles: usize,
        /// Distinct points.
        points: usize,
    },
}

impl fmt::Display for TJunctionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TJunctionError::Invalid(e) => write!(f, "invalid mesh: {e}"),
            TJunctionError::Options(s) => write!(f, "invalid T-junction option: {s}"),
            TJunctionError::TooLarge { triangles, points } => write!(
                f,
                "the naive T-junction finder tests every edge against every point: \
                 {triangles} triangles × {points} points = {} pairs is over its limit of \
                 {NAIVE_MAX_PAIRS}; use the fast method",
                *triangles as u128 * *points as u128
            ),
        }
    }
}

impl std::error::Error for TJunctionError {}

/// What [`eliminate`] did: the quantities Kim (2013) measures (T-junctions,
/// triangles, elimination time) and what the rounds did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TJunctionReport {
    /// Finder used.
    pub method: Method,
    /// T-junctions of the input mesh (first find pass).
    pub t_junctions: usize,
    /// T-junctions fixed over all rounds (equals `t_junctions` when one
    /// round was enough).
    pub t_junctions_fixed: usize,
    /// Points inserted into edges over all rounds (each adds one triangle;
    /// fewer than `t_junctions_fixed` when points of one edge are at the
    /// same place).
    pub inserted: usize,
    /// Degenerate (flat) triangles dropped over all rounds.
    pub degenerate_dropped: usize,
    /// Distinct points of the input.
    pub points: usize,
    /// Triangles of the input.
    pub triangles_in: usize,
    /// Triangles of the output.
    pub triangles_out: usize,
    /// Re-triangulation rounds run (0: the input had nothing to fix).
    pub rounds: usize,
    /// T-junctions still in the output: 0 unless `max_rounds` was reached,
    /// which happens when distinct points lie within about the tolerance of
    /// each other (every triangle using two of them is flat, dropping it
    /// exposes the point again): see the module docs.
    pub remaining_t_junctions: usize,
    /// Degenerate (flat) triangles still in the output (same condition).
    pub remaining_degenerate: usize,
    /// Seconds spent finding (all passes, welding included).
    pub find_s: f64,
    /// Seconds spent re-triangulating (all rounds).
    pub retriangulate_s: f64,
}

/// The input of one find pass: kept triangles and distinct points.
pub(crate) struct Prepared {
    /// Indices of the non-degenerate triangles, ascending.
    pub kept: Vec<u32>,
    /// The distinct points of the kept triangles.
    pub points: points::Points,
    /// The distances of the test for this mesh.
    pub tol: edge_test::Tolerance,
}

/// Check the options and the mesh (the input of every public entry point).
fn check(mesh: &TriangleMesh, opts: &TJunctionOptions) -> Result<(), TJunctionError> {
    check_options(opts)?;
    mesh.validate().map_err(TJunctionError::Invalid)
}

/// Classify the triangles and weld the points of a checked mesh.
fn prepare(mesh: &TriangleMesh, opts: &TJunctionOptions) -> Prepared {
    let tol = edge_test::Tolerance::of(mesh, opts);
    let kept = edge_test::kept_triangles(mesh, tol);
    let points = points::distinct_points(mesh, &kept);
    Prepared { kept, points, tol }
}

fn check_options(opts: &TJunctionOptions) -> Result<(), TJunctionError> {
    for (name, v) in [("tolerance", opts.tolerance), ("ulps", opts.ulps)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(TJunctionError::Options(format!(
                "{name} must be finite and at least 0, got {v}"
            )));
        }
    }
    if opts.tolerance >= 0.5 {
        return Err(TJunctionError::Options(format!(
            "tolerance is relative to the edge length and must be below 0.5, got {}",
            opts.tolerance
        )));
    }
    Ok(())
}

fn find_prepared(
    mesh: &TriangleMesh,
    prep: &Prepared,
    method: Method,
) -> Result<Vec<EdgeVertex>, TJunctionError> {
    match method {
        Method::Naive => naive::find(mesh, prep),
        Method::Fast => Ok(fast::find(mesh, prep)),
    }
}

/// Kim's (2013) naive T-junction finder: every edge of every non-degenerate
/// triangle against every point, O(triangles × points). The reference for
/// [`find_fast`]; refuses meshes where triangles × points exceeds
/// [`NAIVE_MAX_PAIRS`]. Result in the canonical order `(tri, edge, t, vertex)`.
pub fn find_naive(
    mesh: &TriangleMesh,
    opts: &TJunctionOptions,
) -> Result<Vec<EdgeVertex>, TJunctionError> {
    check(mesh, opts)?;
    naive::find(mesh, &prepare(mesh, opts))
}

/// The fast T-junction finder: the same answers as [`find_naive`] (Kim's (2013)
/// definition, same predicate, same canonical order) from a uniform grid over
/// the points, each edge testing only the points in the cells it passes
/// through; near-linear in the mesh size and parallel over triangles (rayon).
pub fn find_fast(
    mesh: &TriangleMesh,
    opts: &TJunctionOptions,
) -> Result<Vec<EdgeVertex>, TJunctionError> {
    check(mesh, opts)?;
    Ok(fast::find(mesh, &prepare(mesh, opts)))
}

/// Kim's (2013) T-junction elimination: find the T-junctions with `method`,
/// insert each point into its edge and re-triangulate (see the module docs),
/// repeating until a find pass finds nothing or `max_rounds` is reached.
/// Returns the new mesh (same vertex arrays, materials and parts; new
/// triangles) and a report. The naive and fast methods return identical
/// meshes.
pub fn eliminate(
    mesh: &TriangleMesh,
    method: Method,
    opts: &TJunctionOptions,
) -> Result<(TriangleMesh, TJunctionReport), TJunctionError> {
    let mut report = TJunctionReport {
        method,
        t_junctions: 0,
        t_junctions_fixed: 0,
        inserted: 0,
        degenerate_dropped: 0,
        points: 0,
        triangles_in: mesh.num_triangles(),
        triangles_out: 0,
        rounds: 0,
        remaining_t_junctions: 0,
        remaining_degenerate: 0,
        find_s: 0.0,
        retriangulate_s: 0.0,
    };
    check(mesh, opts)?;
    // Later rounds work on our own output, valid by construction (it may
    // only become empty, when every triangle was degenerate).
    let mut current: Option<TriangleMesh> = None;
    loop {
        let m = current.as_ref().unwrap_or(mesh);
        let start = Instant::now();
        let prep = prepare(m, opts);
        let found = find_prepared(m, &prep, method)?;
        report.find_s += start.elapsed().as_secs_f64();
        let dropped = m.num_triangles() - prep.kept.len();
        if report.rounds == 0 {
            report.t_junctions = found.len();
            report.points = prep.points.len();
        }
        if found.is_empty() && dropped == 0 {
            break;
        }
        if report.rounds == opts.max_rounds {
            report.remaining_t_junctions = found.len();
            report.remaining_degenerate = dropped;
            break;
        }
        let start = Instant::now();
        let (next, inserted) = retriangulate::retriangulate(m, &prep, &found);
        report.inserted += inserted;
        report.retriangulate_s += start.elapsed().as_secs_f64();
        report.t_junctions_fixed += found.len();
        report.degenerate_dropped += dropped;
        report.rounds += 1;
        current = Some(next);
    }
    let out = current.unwrap_or_else(|| mesh.clone());
    report.triangles_out = out.num_triangles();
    Ok((out, report))
}

#[cfg(test)]
mod tests;
