//! `raykit tjunctions`: T-junction elimination (Kim 2013) on a mesh file.

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use raykit_core::tjunction::{eliminate, Method, TJunctionOptions, TJunctionReport};
use raykit_lab::measure::{pool, timed};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The finder, as `--method` spells it.
#[derive(Clone, Copy, ValueEnum)]
pub enum MethodArg {
    /// Uniform grid over the points; near-linear, parallel.
    Fast,
    /// The O(n²) reference: every edge against every point (refuses
    /// meshes with more than 2e9 triangle × point pairs).
    Naive,
}

/// Arguments of `raykit tjunctions`.
#[derive(Args)]
#[command(
    after_help = "A T-junction is a vertex lying inside another triangle's edge (left by cutting\n\
polygons, e.g. in a kd-tree build): within TOLERANCE x edge length (+ the f32 rounding allowance,\n\
--ulps) of the edge's line and strictly between its ends. Each such vertex is inserted into the\n\
edge and the triangle re-triangulated (no new vertices; parts and materials kept); degenerate\n\
(flat) triangles are dropped. Vertices at identical positions count as one point. Both methods\n\
give the same output mesh.\n\n\
Examples:\n  raykit tjunctions level.obj level_fixed.obj\n  \
raykit tjunctions cut.ply fixed.ply --method naive --json\n  \
raykit tjunctions bunny.obj fixed.ply --kd-cut 8 --cut-out cut.ply   (cut by Kim's (2013) kd-tree first)\n\n\
Prints a summary (or, with --json, a JSON report on stdout: the library's report fields\n\
t_junctions, inserted, degenerate_dropped, triangles_in, triangles_out, rounds, remaining_*,\n\
find_s, retriangulate_s, plus input, output, options, threads, load_s, save_s)."
)]
pub struct TJunctionsArgs {
    /// Input mesh (OBJ, PLY, PLY.GZ, STL, glTF/GLB, OFF).
    input: PathBuf,
    /// Output mesh, format from its extension (obj, ply, stl, off, gltf, glb; .gz
    /// compresses); never the input file.
    output: PathBuf,
    /// Finder: fast (grid, parallel) or naive (the O(n²) reference).
    #[arg(long, value_enum, default_value = "fast")]
    method: MethodArg,
    /// Allowed distance from an edge's line, relative to the edge length.
    #[arg(long, default_value_t = 1e-6)]
    tolerance: f64,
    /// f32 rounding allowance in ulps of the mesh's largest coordinate: extra
    /// distance from the line, and the distance within which two vertices are
    /// at the same place.
    #[arg(long, default_value_t = 4.0)]
    ulps: f64,
    /// Most find + re-triangulate rounds (later rounds fix what the first
    /// one exposes).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u64).range(1..=1000))]
    max_rounds: u64,
    /// Worker threads (0 = one per core; at most 4096).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Print the report as JSON on stdout instead of the summary.
    #[arg(long)]
    json: bool,
    /// First cut the mesh with Kim's (2013) game kd-tree of weight H (0..=20):
    /// straddling triangles are cut at the split planes, leaving the
    /// T-junctions that are then removed.
    #[arg(long, value_name = "H", value_parser = clap::value_parser!(u8).range(0..=20))]
    kd_cut: Option<u8>,
    /// With --kd-cut: nodes with at most this many pieces become leaves.
    #[arg(long, default_value_t = 8)]
    kd_leaf: usize,
    /// With --kd-cut: also write the cut mesh (before elimination) here.
    #[arg(long, value_name = "FILE")]
    cut_out: Option<PathBuf>,
}

/// The JSON report: the library's report plus the run's context.
#[derive(Serialize)]
struct Report<'a> {
    input: String,
    output: String,
    options: TJunctionOptions,
    threads: usize,
    load_s: f64,
    save_s: f64,
    #[serde(flatten)]
    report: &'a TJunctionReport,
}

/// Load, eliminate, write, report.
pub fn run(args: TJunctionsArgs) -> Result<ExitCode> {
    if raykit_io::MeshFormat::from_path(&args.output).is_none() {
        bail!(
            "{}: unknown mesh file extension; expected .obj, .ply, .stl, .off, .gltf or .glb (optionally .gz)",
            args.output.display()
        );
    }
    crate::paths::ensure_output(&args.output, &[args.input.as_path()])?;
    if let Some(cut) = &args.cut_out {
        if args.kd_cut.is_none() {
            bail!("--cut-out needs --kd-cut H");
        }
        crate::paths::ensure_output(cut, &[args.input.as_path()])?;
        crate::paths::ensure_distinct(&args.output, cut, "the output", "--cut-out")?;
    }
    let opts = TJunctionOptions {
        tolerance: args.tolerance,
        ulps: args.ulps,
        max_rounds: args.max_rounds as usize,
    };
    let method = match args.method {
        MethodArg::Fast => Method::Fast,
        MethodArg::Naive => Method::Naive,
    };
    let pool = pool(args.threads)?;
    let (mesh, load_s) = timed(|| raykit_io::load_mesh(&args.input));
    let mut mesh = mesh?;
    // The cut mesh and the output are put in place together at the end, so
    // that a failed run leaves both as they were.
    let mut outputs = raykit_io::OutputSet::new();
    if let Some(h) = args.kd_cut {
        mesh = pool.install(|| kd_cut(&mesh, h, &args, &mut outputs))?;
    }
    let bar = crate::stage::spinner(format!(
        "T-junctions of {} triangles ({})",
        mesh.num_triangles(),
        method.name()
    ));
    let result = pool.install(|| eliminate(&mesh, method, &opts));
    bar.finish_and_clear();
    let (fixed, report) = result.with_context(|| format!("{}", args.input.display()))?;
    if fixed.num_triangles() == 0 {
        bail!(
            "{}: every triangle is degenerate (flat within the tolerance); nothing to write",
            args.input.display()
        );
    }
    let (saved, save_s) = timed(|| raykit_io::stage_mesh(&mut outputs, &args.output, &fixed));
    saved.with_context(|| format!("cannot write {}", args.output.display()))?;
    outputs
        .commit()
        .context("cannot put the outputs in place")?;
    if let Some(path) = &args.cut_out {
        eprintln!("wrote the cut mesh to {}", path.display());
    }
    if args.json {
        let full = Report {
            input: args.input.display().to_string(),
            output: args.output.display().to_string(),
            options: opts,
            threads: pool.current_num_threads(),
            load_s,
            save_s,
            report: &report,
        };
        println!("{}", serde_json::to_string_pretty(&full)?);
    } else {
        print_summary(&args.input, &args.output, &report, load_s, save_s);
    }
    if report.remaining_t_junctions + report.remaining_degenerate > 0 {
        eprintln!(
            "raykit: warning: {} T-junctions and {} flat triangles remain after {} rounds: \
             the mesh has distinct vertices about the tolerance apart, which no re-triangulation \
             separates. If those vertices are meant to be distinct (a fine mesh far from the \
             origin, where {} ulps of the coordinates is wider than its spacing), lower --ulps \
             or --tolerance; if they are meant to be one, weld them first",
            report.remaining_t_junctions, report.remaining_degenerate, report.rounds, args.ulps
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// Cut `mesh` with the game kd-tree of weight `h` and report it; the cut
/// mesh goes to `--cut-out` among the run's `outputs`.
fn kd_cut(
    mesh: &raykit_core::TriangleMesh,
    h: u8,
    args: &TJunctionsArgs,
    outputs: &mut raykit_io::OutputSet,
) -> Result<raykit_core::TriangleMesh> {
    use raykit_core::accel::kdtree::{build_game, cut_mesh, KdOptions, KdSplit};
    let opts = KdOptions {
        split: KdSplit::Game(h),
        max_leaf_size: args.kd_leaf.max(1),
        ..KdOptions::default()
    };
    let ((_, _, game), build_s) = timed(|| build_game(mesh, h, &opts));
    let cut = cut_mesh(mesh, &game);
    eprintln!(
        "kd-tree game:{h}: {} pieces cut ({} triangles split), {} -> {} triangles, {:.1} ms",
        game.cuts,
        cut.split_triangles,
        mesh.num_triangles(),
        cut.mesh.num_triangles(),
        build_s * 1e3
    );
    if let Some(path) = &args.cut_out {
        raykit_io::stage_mesh(outputs, path, &cut.mesh)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(cut.mesh)
}

fn print_summary(input: &Path, output: &Path, r: &TJunctionReport, load_s: f64, save_s: f64) {
    println!(
        "{}: {} triangles, {} distinct points",
        input.display(),
        r.triangles_in,
        r.points
    );
    println!(
        "T-junctions found: {} ({} inserted over {} rounds), degenerate triangles dropped: {}",
        r.t_junctions, r.inserted, r.rounds, r.degenerate_dropped
    );
    println!("triangles: {} -> {}", r.triangles_in, r.triangles_out);
    println!(
        "time: find {:.1} ms ({}), re-triangulate {:.1} ms, load {:.1} ms, save {:.1} ms",
        r.find_s * 1e3,
        r.method.name(),
        r.retriangulate_s * 1e3,
        load_s * 1e3,
        save_s * 1e3
    );
    println!("wrote {}", output.display());
}
