//! `raykit cull`: visibility culling of a model — removes the triangles (or
//! parts) that no viewpoint outside the model can see: by ray tracing (the
//! default), or by Min's (2008) grid method.

use crate::measure::timed;
use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::tri::TestKind;
use raykit_core::{Part, TriangleMesh};
use raykit_cull::{
    compare, cull, cull_by_rays, evaluate_with_progress, CullOptions, CullStats, EvalOptions,
    EvalReport, Grid, GroundTruth, RayOptions,
};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

/// What is removed, as `--by` spells it.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ByArg {
    /// Each hidden triangle.
    Triangle,
    /// Whole parts (glTF nodes, OBJ objects/groups) with no visible triangle;
    /// a part with any visible triangle is kept entire.
    Part,
}

/// How visibility is found, as `--mode` spells it.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
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
  states (rays_per_removed: each removed triangle's own escape rays, the least over them).\n\
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
`rays`: views, rounds, rays, rays_per_triangle, rays_per_removed, converged, each round's log).\n\n\
--evaluate also runs the ray-traced ground truth on the input, independent of the rays mode (its\n\
own seeds, renders from 10,000+ viewpoints at two bounding radii (the rays mode's eyes are at\n\
three), random directions per face, a Pluecker triangle test instead of Moeller-Trumbore), sample counts doubled\n\
for 6 rounds and then held, until two rounds in a row find nothing (--eval-rounds at most), and\n\
reports the removal fractions (by triangles, area, parts), false removals (truly visible but\n\
removed) and missed removals (truly hidden but kept); the JSON report gains `ground_truth` and\n\
`evaluation`. --save-truth FILE.json keeps its labels; --truth FILE.json compares with saved\n\
labels instead of evaluating again. Exit status 2 when any triangle the ground truth sees was\n\
removed.")]
pub struct CullArgs {
    /// Input mesh (OBJ, PLY, PLY.GZ, STL, glTF/GLB, OFF).
    input: PathBuf,
    /// Output mesh, format from its extension (obj, ply, stl, off, gltf, glb; .gz
    /// compresses); never the input file. glTF/GLB keep one node per remaining part.
    output: PathBuf,
    /// How visibility is found: ray tracing, or Min's (2008) grid.
    #[arg(long, value_enum, default_value = "conservative")]
    mode: ModeArg,
    /// Rays mode: narrowest opening that counts, as a fraction of the
    /// bounding-box diagonal (0, the default: any single escaping ray shows
    /// its triangle; 0.0001 closes hairline cracks between CAD faces).
    #[arg(long, default_value_t = 0.0, value_parser = parse_opening)]
    min_opening: f32,
    /// Rays mode: most rounds of escape rays (it stops earlier when two
    /// rounds in a row find nothing new).
    #[arg(long, default_value_t = RayOptions::default().max_rounds as u32,
          value_parser = clap::value_parser!(u32).range(1..=64))]
    rounds: u32,
    /// Grid modes: grid points along the model's longest axis (5..=1024):
    /// finer grids see through smaller openings and remove more, at cubic
    /// cost.
    #[arg(long, default_value_t = CullOptions::default().resolution as u32,
          value_parser = clap::value_parser!(u32).range(Grid::MIN_RESOLUTION as i64..=Grid::MAX_RESOLUTION as i64))]
    resolution: u32,
    /// Remove hidden triangles, or whole parts with no visible triangle.
    #[arg(long, value_enum, default_value = "triangle")]
    by: ByArg,
    /// Min's (2008) rule alone (`--mode paper`; may remove visible
    /// triangles seen through openings finer than the grid).
    #[arg(long, conflicts_with_all = ["confirm", "mode"])]
    paper: bool,
    /// Conservative mode: also keep each candidate hidden triangle that
    /// random rays from its surface show to escape the model (slow).
    #[arg(long)]
    confirm: bool,
    /// Write the JSON report to this file.
    #[arg(long, value_name = "FILE.json")]
    report: Option<PathBuf>,
    /// Print the JSON report on stdout instead of the summary.
    #[arg(long)]
    json: bool,
    /// Compare the result with the ray-traced ground truth (slow); exit
    /// status 2 when a truly visible triangle was removed.
    #[arg(long)]
    evaluate: bool,
    /// Most rounds of the ground truth (each doubles the sample points per
    /// triangle, the directions per point and the viewpoints; it stops
    /// earlier when a round finds no new visible triangle).
    #[arg(long, default_value_t = EvalOptions::default().max_rounds as u32,
          value_parser = clap::value_parser!(u32).range(2..=raykit_cull::evaluate::MAX_ROUNDS as i64),
          requires = "evaluate")]
    eval_rounds: u32,
    /// Narrowest opening the ground truth sees through, as a fraction of the
    /// model's bounding-box diagonal (0, the default: any single ray that
    /// escapes shows its triangle). CAD tessellations leave hairline cracks
    /// between faces; with a width here, an escape must pass as a beam that
    /// wide, so rays through cracks do not make hidden parts "visible".
    #[arg(long, default_value_t = EvalOptions::default().min_opening, requires = "evaluate",
          value_parser = parse_opening)]
    eval_min_opening: f32,
    /// Write the ground truth's labels (visible triangle ids) to this file.
    #[arg(
        long,
        value_name = "FILE.json",
        requires = "evaluate",
        conflicts_with = "truth"
    )]
    save_truth: Option<PathBuf>,
    /// Compare with the labels saved by --save-truth on this input instead
    /// of evaluating again.
    #[arg(long, value_name = "FILE.json", requires = "evaluate")]
    truth: Option<PathBuf>,
}

/// The ground truth's labels as --save-truth writes them.
#[derive(Serialize, serde::Deserialize)]
struct SavedTruth {
    input: String,
    triangles: usize,
    rounds: usize,
    converged: bool,
    last_change: usize,
    rays: u64,
    seconds: f64,
    min_opening: f32,
    visible_ids: Vec<usize>,
}

/// The JSON report: the run's figures and the library's statistics.
#[derive(Serialize)]
struct Report<'a> {
    input: String,
    output: String,
    by: ByArg,
    mode: ModeArg,
    confirm: bool,
    resolution: u32,
    min_opening: f32,
    triangles_in: usize,
    triangles_out: usize,
    triangles_removed: usize,
    parts_in: usize,
    parts_out: usize,
    parts_removed: usize,
    load_s: f64,
    cull_s: f64,
    save_s: f64,
    stats: &'a CullStats,
    #[serde(skip_serializing_if = "Option::is_none")]
    ground_truth: Option<GroundTruth>,
    #[serde(skip_serializing_if = "Option::is_none")]
    evaluation: Option<EvalReport>,
}

/// Load, cull, write, report.
pub fn run(args: CullArgs) -> Result<ExitCode> {
    if raykit_io::MeshFormat::from_path(&args.output).is_none() {
        bail!(
            "{}: unknown mesh file extension; expected .obj, .ply, .stl, .off, .gltf or .glb (optionally .gz)",
            args.output.display()
        );
    }
    crate::paths::ensure_not_input(&args.output, &[args.input.as_path()])?;
    if let Some(r) = &args.report {
        crate::paths::ensure_not_input(r, &[args.input.as_path(), args.output.as_path()])?;
    }
    let mode = if args.paper {
        ModeArg::Paper
    } else {
        args.mode
    };
    if args.confirm && mode != ModeArg::Conservative {
        bail!("--confirm belongs to --mode conservative");
    }
    let options = match mode {
        ModeArg::Paper => CullOptions::paper(args.resolution as usize),
        _ => CullOptions {
            confirm: args.confirm.then(EvalOptions::confirmation),
            ..CullOptions::conservative(args.resolution as usize)
        },
    };
    let ray_options = RayOptions {
        min_opening: args.min_opening,
        max_rounds: args.rounds as usize,
        ..Default::default()
    };
    let bar = ProgressBar::new_spinner().with_style(
        ProgressStyle::with_template("{spinner} {msg} [{elapsed}]").expect("valid template"),
    );
    bar.enable_steady_tick(Duration::from_millis(100));
    bar.set_message(format!("reading {}", args.input.display()));
    let (mesh, load_s) = timed(|| raykit_io::load_mesh(&args.input));
    let mesh = match mesh {
        Ok(m) => m,
        Err(e) => {
            bar.finish_and_clear();
            return Err(e.into());
        }
    };
    bar.set_message(match mode {
        ModeArg::Rays => format!("culling {} triangles by rays", mesh.num_triangles()),
        _ => format!(
            "culling {} triangles at resolution {}",
            mesh.num_triangles(),
            args.resolution
        ),
    });
    let (result, cull_s) = timed(|| match mode {
        ModeArg::Rays => cull_by_rays(&mesh, &ray_options),
        _ => cull(&mesh, &options),
    });
    bar.finish_and_clear();
    let result = result.with_context(|| format!("{}", args.input.display()))?;
    let keep: Vec<bool> = match args.by {
        ByArg::Triangle => result.visible.clone(),
        ByArg::Part => (0..mesh.num_triangles())
            .map(|t| result.part_visible[mesh.part_of(t) as usize])
            .collect(),
    };
    let kept = keep_triangles(&mesh, &keep);
    if kept.num_triangles() == 0 {
        bail!(
            "{}: every triangle was found hidden; nothing to write",
            args.input.display()
        );
    }
    let (saved, save_s) = timed(|| raykit_io::save_mesh(&args.output, &kept));
    let (ground_truth, evaluation) = if args.evaluate {
        let truth = match &args.truth {
            Some(path) => load_truth(path, &args.input, mesh.num_triangles())?,
            None => {
                let truth = evaluate_input(&mesh, &args);
                if let Some(path) = &args.save_truth {
                    save_truth(path, &args, &truth)?;
                }
                truth
            }
        };
        let eval = compare(&truth, &keep, &mesh);
        (Some(truth), Some(eval))
    } else {
        (None, None)
    };
    saved.with_context(|| format!("cannot write {}", args.output.display()))?;
    let stats = &result.stats;
    let parts_out = kept.parts.len().max(1);
    let report = Report {
        input: args.input.display().to_string(),
        output: args.output.display().to_string(),
        by: args.by,
        mode,
        confirm: options.confirm.is_some(),
        resolution: args.resolution,
        min_opening: args.min_opening,
        triangles_in: mesh.num_triangles(),
        triangles_out: kept.num_triangles(),
        triangles_removed: mesh.num_triangles() - kept.num_triangles(),
        parts_in: stats.parts,
        parts_out,
        parts_removed: stats.parts - parts_out,
        load_s,
        cull_s,
        save_s,
        stats,
        ground_truth,
        evaluation,
    };
    let json = serde_json::to_string_pretty(&report)?;
    if let Some(path) = &args.report {
        raykit_io::write_atomic(path, |w| {
            w.write_all(json.as_bytes())?;
            w.write_all(b"\n")
        })
        .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if args.json {
        println!("{json}");
    } else {
        print_summary(&report, &args.output, args.report.as_deref());
    }
    match &report.evaluation {
        Some(e) if e.false_removals > 0 => Ok(ExitCode::from(2)),
        _ => Ok(ExitCode::SUCCESS),
    }
}

/// The ground truth of `mesh` with the arguments' settings, through an
/// 8-wide BVH over the Plücker test (Jones 2000): another triangle test
/// than the rays mode's Möller–Trumbore.
fn evaluate_input(mesh: &TriangleMesh, args: &CullArgs) -> GroundTruth {
    let accel = build_accel(
        AccelKind::Bvh8,
        TestKind::Plucker,
        mesh,
        &BuildOptions::default(),
    );
    let eval_options = EvalOptions {
        max_rounds: args.eval_rounds as usize,
        min_opening: args.eval_min_opening,
        ..Default::default()
    };
    let bar = ProgressBar::new(1).with_style(
        ProgressStyle::with_template(
            "ground truth, round {msg} {bar:30} {pos}/{len} [{elapsed}, eta {eta}]",
        )
        .expect("valid template"),
    );
    let truth = evaluate_with_progress(mesh, accel.as_ref(), &eval_options, &|p| {
        if p.done == 1 {
            bar.set_length(p.total);
            bar.reset_eta();
            bar.set_message(format!(
                "{} of at most {} ({} triangles visible so far; triangles, then viewpoints)",
                p.round + 1,
                eval_options.max_rounds,
                p.visible
            ));
        }
        bar.set_position(p.done);
    });
    bar.finish_and_clear();
    truth
}

fn save_truth(path: &Path, args: &CullArgs, truth: &GroundTruth) -> Result<()> {
    let saved = SavedTruth {
        input: args.input.display().to_string(),
        triangles: truth.visible.len(),
        rounds: truth.rounds,
        converged: truth.converged,
        last_change: truth.last_change,
        rays: truth.rays,
        seconds: truth.seconds,
        min_opening: args.eval_min_opening,
        visible_ids: (0..truth.visible.len())
            .filter(|&t| truth.visible[t])
            .collect(),
    };
    let json = serde_json::to_string(&saved)?;
    raykit_io::write_atomic(path, |w| {
        w.write_all(json.as_bytes())?;
        w.write_all(b"\n")
    })
    .with_context(|| format!("cannot write {}", path.display()))
}

/// Labels saved by --save-truth, checked against the input's triangles.
fn load_truth(path: &Path, input: &Path, triangles: usize) -> Result<GroundTruth> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let saved: SavedTruth = serde_json::from_str(&text).with_context(|| {
        format!(
            "{}: not a ground truth saved by --save-truth",
            path.display()
        )
    })?;
    if saved.triangles != triangles {
        bail!(
            "{}: field triangles is {}, but {} has {triangles} triangles",
            path.display(),
            saved.triangles,
            input.display()
        );
    }
    let mut visible = vec![false; triangles];
    for (i, &t) in saved.visible_ids.iter().enumerate() {
        match visible.get_mut(t) {
            Some(v) => *v = true,
            None => bail!(
                "{}: visible_ids[{i}] is {t}, beyond the {triangles} triangles",
                path.display()
            ),
        }
    }
    Ok(GroundTruth {
        visible_count: saved.visible_ids.len(),
        visible,
        rounds: saved.rounds,
        last_change: saved.last_change,
        converged: saved.converged,
        rays: saved.rays,
        seconds: saved.seconds,
        ..Default::default()
    })
}

/// The triangles of `mesh` where `keep` is true, with only the vertices they
/// use (normals and texture coordinates follow) and only the parts that still
/// have triangles (renumbered in order); materials are kept as they are.
fn keep_triangles(mesh: &TriangleMesh, keep: &[bool]) -> TriangleMesh {
    const NONE: u32 = u32::MAX;
    let has_parts = !mesh.tri_part.is_empty() || !mesh.parts.is_empty();
    let n_parts = mesh.parts.len().max(
        (0..mesh.num_triangles())
            .map(|t| mesh.part_of(t) as usize + 1)
            .max()
            .unwrap_or(0),
    );
    let mut part_kept = vec![false; n_parts];
    for t in (0..mesh.num_triangles()).filter(|&t| keep[t]) {
        part_kept[mesh.part_of(t) as usize] = true;
    }
    let mut new_part = vec![NONE; n_parts];
    let mut parts = Vec::new();
    if has_parts {
        for (p, _) in part_kept.iter().enumerate().filter(|(_, &k)| k) {
            new_part[p] = parts.len() as u32;
            parts.push(mesh.parts.get(p).cloned().unwrap_or(Part {
                name: String::new(),
                node: None,
            }));
        }
    }
    let mut new_vertex = vec![NONE; mesh.positions.len()];
    let mut used = Vec::new();
    let mut indices = Vec::new();
    let mut tri_material = Vec::new();
    let mut tri_part = Vec::new();
    for t in (0..mesh.num_triangles()).filter(|&t| keep[t]) {
        indices.push(mesh.indices[t].map(|v| {
            let slot = &mut new_vertex[v as usize];
            if *slot == NONE {
                *slot = used.len() as u32;
                used.push(v as usize);
            }
            *slot
        }));
        if !mesh.tri_material.is_empty() {
            tri_material.push(mesh.tri_material[t]);
        }
        if has_parts {
            tri_part.push(new_part[mesh.part_of(t) as usize]);
        }
    }
    TriangleMesh {
        positions: used.iter().map(|&v| mesh.positions[v]).collect(),
        indices,
        normals: mesh
            .normals
            .as_ref()
            .map(|a| used.iter().map(|&v| a[v]).collect()),
        uvs: mesh
            .uvs
            .as_ref()
            .map(|a| used.iter().map(|&v| a[v]).collect()),
        materials: mesh.materials.clone(),
        tri_material,
        parts,
        tri_part,
    }
}

fn print_summary(r: &Report<'_>, output: &Path, report: Option<&Path>) {
    let s = r.stats;
    match &s.rays {
        Some(x) => println!(
            "{}: {} triangles, {} parts; visible = {}",
            r.input,
            r.triangles_in,
            r.parts_in,
            if x.beam > 0.0 {
                format!(
                    "an escaping beam {:.4e} wide ({} of the diagonal) from either face",
                    x.beam, r.min_opening
                )
            } else {
                "any escaping ray from either face".to_string()
            }
        ),
        None => println!(
            "{}: {} triangles, {} parts; grid {}x{}x{} (spacing {:.4}), {} of {} points outside",
            r.input,
            r.triangles_in,
            r.parts_in,
            s.grid[0],
            s.grid[1],
            s.grid[2],
            s.spacing,
            s.outside_points,
            s.points
        ),
    }
    let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
    println!(
        "triangles: {} -> {} ({} removed, {:.1}%)",
        r.triangles_in,
        r.triangles_out,
        r.triangles_removed,
        pct(r.triangles_removed, r.triangles_in)
    );
    println!(
        "parts: {} -> {} ({} removed, {:.1}%)",
        r.parts_in,
        r.parts_out,
        r.parts_removed,
        pct(r.parts_removed, r.parts_in)
    );
    if let Some(x) = &s.rays {
        println!(
            "rays: {} seen by {} views of {}x{}, {} by escape rays and shared directions in {} rounds \
             ({}; last round added {}); {} rays, {:.0} per triangle; every removed triangle survived \
             at least {} escape rays of its own; {} zero-area triangles removed",
            x.by_views,
            x.viewpoints,
            x.image,
            x.image,
            x.by_escape_rays,
            x.rounds,
            if x.converged {
                "converged: the last two found nothing"
            } else {
                "not converged"
            },
            x.last_round_added,
            x.rays,
            x.rays_per_triangle,
            x.rays_per_removed,
            x.degenerate
        );
    }
    if r.mode == ModeArg::Conservative {
        println!(
            "conservative mode kept {} triangles by dilation, {} by contact with outside cells, {} by \
             escaping rays at the frontier{}{}",
            s.kept_by_dilation,
            s.kept_by_contact,
            s.kept_by_frontier,
            if s.frontier_cut_short {
                " (ray budget reached: a finer --resolution or --confirm searches more)"
            } else {
                ""
            },
            if r.confirm {
                format!(", {} by escaping rays elsewhere", s.kept_by_rays)
            } else {
                String::new()
            }
        );
    }
    if s.rays.is_some() {
        println!(
            "time: load {:.1} ms, BVH {:.1} ms, rays {:.1} ms, save {:.1} ms",
            r.load_s * 1e3,
            s.accel_seconds * 1e3,
            s.visible_seconds * 1e3,
            r.save_s * 1e3
        );
    } else {
        println!(
            "time: load {:.1} ms, BVH {:.1} ms, distance field {:.1} ms, propagation {:.1} ms, \
             visible set {:.1} ms, save {:.1} ms",
            r.load_s * 1e3,
            s.accel_seconds * 1e3,
            s.distance_field_seconds * 1e3,
            s.propagation_seconds * 1e3,
            s.visible_seconds * 1e3,
            r.save_s * 1e3
        );
    }
    if let (Some(g), Some(e)) = (&r.ground_truth, &r.evaluation) {
        println!(
            "ground truth: {} of {} triangles visible ({} rounds, last added {}{}; {} points x {} \
             directions per face, {} viewpoints of {}x{}; {} rays, {:.1} s)",
            g.visible_count,
            r.triangles_in,
            g.rounds,
            g.last_change,
            if g.converged { "" } else { ", not converged" },
            g.points,
            g.directions,
            g.viewpoints,
            g.image,
            g.image,
            g.rays,
            g.seconds
        );
        println!(
            "evaluation: removed {:.1}% of triangles, {:.1}% of area, {:.1}% of parts; \
             false removals {} (area {:.4e}{}), missed removals {} ({:.1}% of {} truly hidden)",
            100.0 * e.removed_fraction_triangles,
            100.0 * e.removed_fraction_area,
            100.0 * e.removed_fraction_parts,
            e.false_removals,
            e.false_removal_area,
            if e.false_removal_ids.is_empty() {
                String::new()
            } else {
                format!(", first ids {:?}", e.false_removal_ids)
            },
            e.missed_removals,
            100.0 * e.missed_fraction,
            e.truly_hidden
        );
    }
    println!("wrote {}", output.display());
    if let Some(p) = report {
        println!("wrote the report to {}", p.display());
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
