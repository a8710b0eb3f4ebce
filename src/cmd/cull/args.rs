//! The arguments of `raykit cull`.

use clap::{Args, ValueEnum};
use raykit_cull::{CullMode, CullOptions, EvalOptions, Grid, RayOptions, Removal};
use std::path::PathBuf;

/// What is removed, as `--by` spells it.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ByArg {
    /// Each hidden triangle.
    Triangle,
    /// Whole parts (glTF nodes, OBJ objects/groups) with no visible triangle;
    /// a part with any visible triangle is kept entire.
    Part,
}

/// How visibility is found, as `--mode` spells it.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ModeArg {
    /// Ray tracing: views from around the model, escape rays from every
    /// unseen triangle, escape directions shared between neighbours, rounds
    /// until two find nothing. Every kept triangle has a ray that escapes.
    Rays,
    /// Min's (2008) grid with the conservative additions.
    Conservative,
    /// Min's (2008) rule alone (the reproduction of the thesis).
    Paper,
}

/// Arguments of `raykit cull`.
#[derive(Args)]
#[command(after_help = "Modes (--mode):\n\
- rays: a triangle is visible when some ray leaving it (from either face) meets\n\
  nothing, so an eye far away along that ray sees it; all others are removed. Visibility is found\n\
  by ray tracing through an 8-wide BVH: pinhole views of 64x64 from 4,096 eyes around the model\n\
  (every triangle a view ray meets first is visible), then escape rays from every triangle not yet\n\
  seen (stratified points on it, stratified directions over the sphere, each from the face it\n\
  leaves), escape directions shared between neighbouring triangles (what is seen through a slit\n\
  is found by its neighbours' escapes), in rounds whose rays per triangle double and then hold,\n\
  triangles near visible ones getting 4 times more, until two rounds in a row find nothing new\n\
  (converged) or --rounds run out (the report says which).\n\
  Every kept triangle rests on a ray that escaped; a removed one survived the rays the report\n\
  states (rays_per_removed: each removed triangle's own escape rays, the least over them;\n\
  escape_fraction_95: a triangle escaping through at least this fraction of its point and direction\n\
  samples would have been found with 95% probability; rarer escapes may be missed).\n\
  --min-opening W demands that an escape pass as a beam W x the bounding-box diagonal wide, so that\n\
  hairline cracks between CAD faces do not count (the output says which definition was used).\n\
  Not yet the default: its search does not converge on large assemblies within minutes, so it can\n\
  remove triangles that more rays would show visible (see BENCHMARKS.md, ray-traced culling).\n\
- conservative (the default): Min's (2008) grid method (below) keeping what its evidence does not\n\
  clearly hide: few false removals, but it removes far less than is hidden.\n\
- paper: Min's (2008) rule alone, for the reproduction of the thesis.\n\n\
Grid modes: a grid of RESOLUTION points along the model's longest axis is laid around it, the\n\
directed distance field (distance to the nearest surface along +-x, +-y, +-z from every grid\n\
point, by axis rays through a BVH) is computed, and a front propagated from the grid's outer\n\
boundary marks the points reachable from outside; triangles the outside points' axis rays meet are\n\
visible. An opening narrower than about one grid spacing (longest side / RESOLUTION) is closed to\n\
the front, so what is seen only through it looks hidden. The conservative mode also keeps\n\
triangles within one spacing behind a visible surface, triangles in grid cells with an outside\n\
corner, and candidates next to kept triangles that random rays show to escape; --confirm also\n\
tests every remaining candidate by rays. --paper is --mode paper.\n\n\
Examples:\n  raykit cull engine.glb engine_outside.glb\n  \
raykit cull engine.glb engine_outside.glb --mode rays --rounds 6\n  \
raykit cull assembly.obj shell.obj --by part --report cull.json\n  \
raykit cull engine.glb out.glb --mode rays --min-opening 0.0001\n  \
raykit cull engine.glb out.glb --mode paper --resolution 128\n\n\
Prints triangles and parts before, after and removed, and the times; --report FILE.json (or --json,\n\
on stdout instead of the summary) writes a JSON report: input, output, by, mode, confirm,\n\
resolution, min_opening, triangles_in/out/removed, parts_in/out/removed, load_s, cull_s, save_s,\n\
and stats (the library's CullStats: the grid modes' grid, field and step times; the rays mode's\n\
`rays`: views, rounds, rays, rays_per_triangle, rays_per_removed, escape_fraction_95, converged,\n\
each round's log).\n\n\
--evaluate also runs the ray-traced ground truth on the input, independent of the rays mode (its\n\
own seeds, renders from 10,000+ viewpoints at two bounding radii (the rays mode's eyes are at\n\
three), random directions per face, a Pluecker triangle test instead of Moeller-Trumbore), sample counts doubled\n\
for 6 rounds and then held, until two rounds in a row find nothing (--eval-rounds at most), and\n\
reports the removal fractions (by triangles, area, parts), false removals (truly visible but\n\
removed) and missed removals (truly hidden but kept); the JSON report gains `ground_truth` and\n\
`evaluation`. --save-truth FILE.json keeps its labels; --truth FILE.json compares with saved\n\
labels instead of evaluating again. Exit status 3 when any triangle the ground truth sees was\n\
removed (2 is a usage error, 1 any other failure).")]
pub struct CullArgs {
    /// Input mesh (OBJ, PLY, PLY.GZ, STL, glTF/GLB, OFF).
    pub(super) input: PathBuf,
    /// Output mesh, format from its extension (obj, ply, stl, off, gltf, glb; .gz
    /// compresses); never the input file. glTF/GLB keep one node per remaining part;
    /// from a glTF/GLB input they keep its instancing: a mesh that several nodes place is
    /// written once for all of them that keep the same triangles of it.
    pub(super) output: PathBuf,
    /// How visibility is found: ray tracing, or Min's (2008) grid.
    #[arg(long, value_enum, default_value = "conservative")]
    pub(super) mode: ModeArg,
    /// Rays mode: narrowest opening that counts, as a fraction of the
    /// bounding-box diagonal (0, the default: any single escaping ray shows
    /// its triangle; 0.0001 closes hairline cracks between CAD faces).
    #[arg(long, default_value_t = 0.0, value_parser = parse_opening)]
    pub(super) min_opening: f32,
    /// Rays mode: most rounds of escape rays (it stops earlier when two
    /// rounds in a row find nothing new).
    #[arg(long, default_value_t = RayOptions::default().max_rounds as u32,
          value_parser = clap::value_parser!(u32).range(1..=64))]
    pub(super) rounds: u32,
    /// Grid modes: grid points along the model's longest axis (5..=1024):
    /// finer grids see through smaller openings and remove more, at cubic
    /// cost.
    #[arg(long, default_value_t = CullOptions::default().resolution as u32,
          value_parser = clap::value_parser!(u32).range(Grid::MIN_RESOLUTION as i64..=Grid::MAX_RESOLUTION as i64))]
    pub(super) resolution: u32,
    /// Remove hidden triangles, or whole parts with no visible triangle.
    #[arg(long, value_enum, default_value = "triangle")]
    pub(super) by: ByArg,
    /// glTF/GLB input and output: every node of a mesh keeps what any of
    /// them sees, so that each mesh is written once, as in the input. It
    /// removes less: every triangle that a node's own result keeps stays.
    #[arg(long)]
    pub(super) shared_meshes: bool,
    /// Min's (2008) rule alone (`--mode paper`; may remove visible
    /// triangles seen through openings finer than the grid).
    #[arg(long, conflicts_with_all = ["confirm", "mode"])]
    pub(super) paper: bool,
    /// Conservative mode: also keep each candidate hidden triangle that
    /// random rays from its surface show to escape the model (slow).
    #[arg(long)]
    pub(super) confirm: bool,
    /// Write the JSON report to this file.
    #[arg(long, value_name = "FILE.json")]
    pub(super) report: Option<PathBuf>,
    /// Print the JSON report on stdout instead of the summary.
    #[arg(long)]
    pub(super) json: bool,
    /// Compare the result with the ray-traced ground truth (slow); exit
    /// status 3 when a truly visible triangle was removed.
    #[arg(long)]
    pub(super) evaluate: bool,
    /// Most rounds of the ground truth (each doubles the sample points per
    /// triangle, the directions per point and the viewpoints; it stops
    /// earlier when a round finds no new visible triangle).
    #[arg(long, default_value_t = EvalOptions::default().max_rounds as u32,
          value_parser = clap::value_parser!(u32).range(2..=raykit_cull::evaluate::MAX_ROUNDS as i64),
          requires = "evaluate")]
    pub(super) eval_rounds: u32,
    /// Narrowest opening the ground truth sees through, as a fraction of the
    /// model's bounding-box diagonal (0, the default: any single ray that
    /// escapes shows its triangle). CAD tessellations leave hairline cracks
    /// between faces; with a width here, an escape must pass as a beam that
    /// wide, so rays through cracks do not make hidden parts "visible".
    #[arg(long, default_value_t = EvalOptions::default().min_opening, requires = "evaluate",
          value_parser = parse_opening)]
    pub(super) eval_min_opening: f32,
    /// Write the ground truth's labels (visible triangle ids) to this file.
    #[arg(
        long,
        value_name = "FILE.json",
        requires = "evaluate",
        conflicts_with = "truth"
    )]
    pub(super) save_truth: Option<PathBuf>,
    /// Compare with the labels saved by --save-truth on this input instead
    /// of evaluating again.
    #[arg(long, value_name = "FILE.json", requires = "evaluate")]
    pub(super) truth: Option<PathBuf>,
}

impl From<ByArg> for Removal {
    fn from(a: ByArg) -> Removal {
        match a {
            ByArg::Triangle => Removal::Triangle,
            ByArg::Part => Removal::Part,
        }
    }
}

impl From<ModeArg> for CullMode {
    fn from(a: ModeArg) -> CullMode {
        match a {
            ModeArg::Rays => CullMode::Rays,
            ModeArg::Conservative => CullMode::Conservative,
            ModeArg::Paper => CullMode::Paper,
        }
    }
}

/// `--eval-min-opening`: a fraction of the diagonal in [0, 0.1].
fn parse_opening(s: &str) -> Result<f32, String> {
    let v: f32 = s
        .parse()
        .map_err(|_| format!("'{s}' is not a number; expected a fraction such as 0.0001"))?;
    if (0.0..=0.1).contains(&v) {
        Ok(v)
    } else {
        Err(format!(
            "{s} is outside 0..=0.1 (a fraction of the bounding-box diagonal)"
        ))
    }
}
