//! raykit visibility culling of CAD models, after Min (2008) (global
//! visibility culling): remove the triangles that no viewpoint outside the
//! model can see.
//!
//! The steps of Min (2008), one module each:
//! 1. [`grid`] a regular grid around the model, and [`distance_field`] the
//!    directed distance field on it — per point, the distance to the nearest
//!    surface along ±x, ±y, ±z and the triangle found there (here by casting
//!    axis-aligned rays through a [`raykit_core::accel::Bvh2`]);
//! 2. [`propagate`] front propagation from the grid's outer boundary
//!    (fast-marching tags Known / Trial / Far), classifying points outside;
//! 3. [`visible`] the triangles met by outside points' directed distances
//!    are visible, all others hidden.
//!
//! **What the resolution trades.** The grid sees the outside only through
//! steps between its points: an opening narrower than about one spacing, or a
//! gap between surfaces thinner than one, is closed to the front, so what is
//! seen only through it is hidden by the plain method (a false removal), and
//! a visible surface no axis ray of an outside point reaches is missed too.
//! Time and memory grow with the cube of the resolution (lines × hits per
//! line for the field, one byte per point for each of the free steps and the
//! tags). The default *conservative* mode therefore keeps what the evidence
//! does not clearly hide:
//! - triangles within [`CullOptions::depth_cells`] spacings behind a visible
//!   surface along an outside point's ray (a dilation);
//! - triangles in grid cells with an outside corner
//!   ([`visible::touches_outside`]);
//! - candidates next to kept triangles that rays show to escape the model:
//!   random rays from their surface, and the escape directions found from
//!   their neighbours ([`visible::confirm_frontier`], [`shared_escapes`]);
//! - when asked for ([`CullOptions::confirm`]), every remaining candidate
//!   the ground truth's own search finds visible
//!   ([`evaluate::evaluate_beyond`]).
//!
//! Higher resolutions remove more hidden triangles; the conservative
//! additions trade removals for safety. They make false removals rare, but
//! are evidence, not a proof: `raykit experiment cull` counts them against
//! the ray-traced ground truth.

pub mod distance_field;
pub mod escape;
pub mod evaluate;
pub mod grid;
pub mod independent;
pub mod propagate;
pub mod rays;
pub mod report;
pub mod saved_truth;
pub mod shared_escapes;
pub mod synthetic;
pub mod visible;

pub use distance_field::{DirectedDistanceField, DirectedHit, Direction};
pub use escape::{beam_escapes, escape_direction, is_degenerate, RayConfirm};
pub use evaluate::{
    compare, evaluate, evaluate_beyond, evaluate_with_progress, EvalOptions, EvalProgress,
    EvalReport, GroundTruth, RoundLog,
};
pub use grid::Grid;
pub use independent::independent_truth;
pub use propagate::{propagate, Classification, Tag};
pub use rays::{visible_by_rays, RayOptions, RayRound, RayStats};
pub use report::{CullMode, CullReport, Instancing, Removal};
pub use saved_truth::{SavedTruth, SavedTruthMismatch};
pub use visible::{confirm_frontier, touches_outside, visible_from_outside};

use raykit_core::accel::{build_accel, Accel, AccelKind, BuildOptions};
use raykit_core::tri::TestKind;
use raykit_core::{MeshError, TriangleMesh, UnitScale};
use serde::Serialize;
use std::time::Instant;

/// Settings of [`cull`] (Min's (2008) grid size and our conservative mode).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CullOptions {
    /// Grid points along the model's longest axis (Min (2008) used 64–256).
    pub resolution: usize,
    /// Conservative mode (the default): keep what the evidence does not
    /// clearly hide. Off: Min's (2008) rule alone.
    pub conservative: bool,
    /// Conservative mode: triangles within this many spacings behind the
    /// first surface on an outside point's ray are kept.
    pub depth_cells: f32,
    /// Conservative mode: keep triangles in grid cells with an outside corner
    /// ([`visible::touches_outside`]).
    pub contact: bool,
    /// Conservative mode: confirmation by rays of the candidates next to
    /// kept triangles, with escape directions shared between neighbours
    /// (`Some`, the default; see [`visible::confirm_frontier`]).
    pub frontier: Option<RayConfirm>,
    /// Conservative mode: confirmation of every remaining candidate by the
    /// ground truth's own search ([`evaluate::evaluate_beyond`]: rays from
    /// the surface, renders, shared escape directions, doubled each round);
    /// `None`, the default: off — its cost grows with the hidden triangles.
    pub confirm: Option<EvalOptions>,
}

impl Default for CullOptions {
    fn default() -> Self {
        CullOptions {
            resolution: 128,
            conservative: true,
            depth_cells: 1.0,
            contact: true,
            frontier: Some(RayConfirm::default()),
            confirm: None,
        }
    }
}

impl CullOptions {
    /// Min's (2008) method alone at `resolution`, with no conservative
    /// additions.
    pub fn paper(resolution: usize) -> Self {
        CullOptions {
            resolution,
            conservative: false,
            depth_cells: 0.0,
            contact: false,
            frontier: None,
            confirm: None,
        }
    }

    /// The default conservative mode at `resolution`.
    pub fn conservative(resolution: usize) -> Self {
        CullOptions {
            resolution,
            ..Default::default()
        }
    }
}

/// Figures of one run: Min's (2008) table columns and more.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct CullStats {
    /// Grid points per axis.
    pub grid: [usize; 3],
    /// Grid spacing in model units.
    pub spacing: f32,
    /// Grid points in all.
    pub points: usize,
    /// Points classified outside by front propagation.
    pub outside_points: usize,
    /// Surface crossings stored in the directed distance field.
    pub field_hits: usize,
    /// Seconds to build the BVH.
    pub accel_seconds: f64,
    /// Seconds to compute the directed distance field (Min's (2008) first time).
    pub distance_field_seconds: f64,
    /// Seconds of front propagation, free-step bits included (Min's (2008) second time).
    pub propagation_seconds: f64,
    /// Seconds to mark visible triangles, conservative additions included.
    pub visible_seconds: f64,
    /// Triangles in the model.
    pub triangles: usize,
    /// Triangles removed (hidden).
    pub triangles_removed: usize,
    /// Triangles kept only by the depth dilation.
    pub kept_by_dilation: usize,
    /// Triangles kept only by their contact with outside grid cells.
    pub kept_by_contact: usize,
    /// Triangles kept only by the confirmation at the frontier.
    pub kept_by_frontier: usize,
    /// True when the frontier's ray budget
    /// ([`visible::FRONTIER_RAY_BUDGET`]) cut its search short.
    pub frontier_cut_short: bool,
    /// Triangles kept only by the confirmation by rays of every candidate.
    pub kept_by_rays: usize,
    /// Parts in the model.
    pub parts: usize,
    /// Parts all of whose triangles are removed.
    pub parts_removed: usize,
    /// The ray-traced visibility's figures ([`cull_by_rays`]; `None` for
    /// the grid modes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rays: Option<RayStats>,
}

/// What [`cull`] found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CullResult {
    /// Per triangle: true when kept (visible or not clearly hidden).
    pub visible: Vec<bool>,
    /// Per part (`mesh.parts`, or one part when the mesh has none): true when
    /// some triangle of it is kept.
    pub part_visible: Vec<bool>,
    /// Figures of the run.
    pub stats: CullStats,
}

/// Classify every triangle of `mesh` as kept or removed (Min's (2008) global
/// visibility culling). An empty mesh gives an empty result; a mesh failing
/// [`TriangleMesh::validate`] otherwise gives its error.
pub fn cull(mesh: &TriangleMesh, options: &CullOptions) -> Result<CullResult, MeshError> {
    let (unit, scaled) = UnitScale::of(mesh);
    let mesh = &*scaled;
    let Some((accel, mut stats)) = prepare(mesh, AccelKind::Bvh2)? else {
        return Ok(result_for(mesh, Vec::new(), CullStats::default()));
    };

    let grid = Grid::around(&mesh.bounds(), options.resolution);
    let clock = Instant::now();
    let field = DirectedDistanceField::compute(accel.as_ref(), &grid);
    stats.distance_field_seconds = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let class = propagate(&grid, &field.free_steps());
    stats.propagation_seconds = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let n = mesh.num_triangles();
    let mut visible = visible_from_outside(&field, &class, n, 0.0);
    if options.conservative {
        let seen = visible.iter().filter(|&&v| v).count();
        if options.depth_cells > 0.0 {
            visible = visible_from_outside(&field, &class, n, options.depth_cells);
        }
        stats.kept_by_dilation = visible.iter().filter(|&&v| v).count() - seen;
        if options.contact {
            stats.kept_by_contact = touches_outside(mesh, &grid, &class, &mut visible);
        }
        if let Some(c) = &options.frontier {
            // Sharing cells of two grid spacings: the frontier's scale.
            let cells = options.resolution.div_ceil(2).clamp(8, 512);
            (stats.kept_by_frontier, stats.frontier_cut_short) =
                confirm_frontier(mesh, accel.as_ref(), &mut visible, c, cells);
        }
        if let Some(c) = &options.confirm {
            // Triangles without area have no face to judge: kept.
            for (t, v) in visible.iter_mut().enumerate() {
                *v |= is_degenerate(mesh, t);
            }
            let before = visible.iter().filter(|&&v| v).count();
            let truth = evaluate_beyond(mesh, accel.as_ref(), c, visible, &|_| {});
            visible = truth.visible;
            stats.kept_by_rays = truth.visible_count - before;
        }
    }
    stats.visible_seconds = clock.elapsed().as_secs_f64();

    stats.grid = grid.dims;
    stats.spacing = unit.to_model(grid.spacing);
    stats.points = grid.len();
    stats.outside_points = class.outside;
    stats.field_hits = field.hit_count();
    Ok(result_for(mesh, visible, stats))
}

/// Classify every triangle of `mesh` as kept (visible from outside) or
/// removed by ray tracing alone ([`rays`]: views from around the model,
/// escape rays from every unseen triangle, escape directions shared
/// between neighbours, rounds until two find nothing), through an 8-wide
/// BVH over Möller–Trumbore packs. An empty mesh gives an empty result; a
/// mesh failing [`TriangleMesh::validate`] otherwise gives its error.
pub fn cull_by_rays(mesh: &TriangleMesh, options: &RayOptions) -> Result<CullResult, MeshError> {
    let (unit, scaled) = UnitScale::of(mesh);
    let mesh = &*scaled;
    let Some((accel, mut stats)) = prepare(mesh, AccelKind::Bvh8)? else {
        return Ok(result_for(mesh, Vec::new(), CullStats::default()));
    };
    let clock = Instant::now();
    let (visible, mut ray_stats) = visible_by_rays(mesh, accel.as_ref(), options);
    ray_stats.beam = unit.to_model(ray_stats.beam);
    stats.visible_seconds = clock.elapsed().as_secs_f64();
    stats.rays = Some(ray_stats);
    Ok(result_for(mesh, visible, stats))
}

/// A built structure and the figures of its build.
type Prepared = (Box<dyn Accel>, CullStats);

/// The checked mesh's structure `kind` over Möller–Trumbore, timed into
/// fresh figures; `None` for an empty mesh, the error of
/// [`TriangleMesh::validate`] for a bad one.
fn prepare(mesh: &TriangleMesh, kind: AccelKind) -> Result<Option<Prepared>, MeshError> {
    match mesh.validate() {
        Ok(()) => {}
        Err(MeshError::Empty) => return Ok(None),
        Err(e) => return Err(e),
    }
    let mut stats = CullStats::default();
    let clock = Instant::now();
    let accel = build_accel(kind, TestKind::Moller, mesh, &BuildOptions::default());
    stats.accel_seconds = clock.elapsed().as_secs_f64();
    Ok(Some((accel, stats)))
}

/// Fill in per-part visibility and the removal counts.
fn result_for(mesh: &TriangleMesh, visible: Vec<bool>, mut stats: CullStats) -> CullResult {
    let max_part = (0..mesh.num_triangles().min(visible.len()))
        .map(|t| mesh.part_of(t) as usize + 1)
        .max()
        .unwrap_or(0);
    let parts = mesh
        .parts
        .len()
        .max(max_part)
        .max(usize::from(!visible.is_empty()));
    let mut part_visible = vec![false; parts];
    for (t, &v) in visible.iter().enumerate() {
        if v {
            part_visible[mesh.part_of(t) as usize] = true;
        }
    }
    stats.triangles = visible.len();
    stats.triangles_removed = visible.iter().filter(|&&v| !v).count();
    stats.parts = parts;
    stats.parts_removed = part_visible.iter().filter(|&&v| !v).count();
    CullResult {
        visible,
        part_visible,
        stats,
    }
}
