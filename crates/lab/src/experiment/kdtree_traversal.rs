//! `raykit experiment kdtree-traversal`: on this machine, node memory of ropes vs stack layouts; speed of
//! {stack, ropes, restart, backtrack} × {projection, Plücker, Möller} on
//! primary rays with Phong shading and on shadow rays, with the BVH2 and the
//! threaded BVH (Smits 1998) in the same table.

use super::{cached_dragon, shared_mesh, write_csv, write_text};
use crate::args::build_args::BuildArgs;
use crate::args::ranges::{self, image_side};
use crate::args::scene_arg;
use crate::measure::{median_min_max, pool, spread, spread_percent, timed, worse_spread};
use anyhow::Result;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use raykit_core::accel::kdtree::build_tree;
use raykit_core::accel::{build_accel, kd_accel_from_tree, AccelKind};
use raykit_core::raysets;
use raykit_core::tri::TestKind;
use raykit_core::{Accel, Ray};
use raykit_render::{render, RenderOptions};
use raykit_scene::PointLight;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `raykit experiment kdtree-traversal`.
#[derive(Args)]
#[command(
    after_help = "Default meshes: the shared teapot, bunny and dragon (res2), the built-in\n\
terrain and scattered scenes, and the full dragon when scripts/fetch-bench-data has\n\
fetched it into data-cache/. Every traversal shares one SAH build per mesh; each\n\
answer is checked ray by ray against the BVH2 with the same triangle test (itself\n\
tested against brute force)."
)]
pub struct KdTraversalArgs {
    /// Meshes (file or builtin:NAME); repeat the option for several.
    #[arg(long)]
    mesh: Vec<String>,
    /// Image side: SIZE² primary rays (shaded) and their shadow rays; 1 to
    /// 16384.
    #[arg(long, default_value_t = 512)]
    size: u32,
    /// Repetitions of every measurement (the median is reported); 1 to 1000.
    #[arg(long, default_value_t = 3)]
    reps: usize,
    /// Threads (single-kernel GPU variants are compared; 1 thread
    /// gives the steadiest CPU figures).
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Output folder for results.md, speed.csv, memory.csv and results.json.
    #[arg(long, default_value = "experiments/kdtree-traversal")]
    out: PathBuf,
    #[command(flatten)]
    build: BuildArgs,
}

/// Node memory of one layout on one mesh.
#[derive(Serialize, Clone)]
struct MemoryRow {
    mesh: String,
    triangles: usize,
    accel: &'static str,
    node_bytes: usize,
    node_kb: f64,
    bytes_per_triangle: f64,
    nodes: usize,
    leaves: usize,
    triangle_refs: usize,
    depth: u32,
}

/// Mrays/s of one structure × test on one mesh.
#[derive(Serialize, Clone)]
struct SpeedRow {
    mesh: String,
    accel: &'static str,
    test: &'static str,
    primary_phong_mrays: f64,
    shadow_mrays: f64,
    /// Worst (max − min) / median of the two timings; `None` (empty in the
    /// CSV, null in the JSON) with fewer than two repetitions.
    spread: Option<f64>,
    disagreements: usize,
}

const TESTS: [TestKind; 3] = [TestKind::Projection, TestKind::Plucker, TestKind::Moller];
const ACCELS: [AccelKind; 6] = [
    AccelKind::KdStack,
    AccelKind::KdRopes,
    AccelKind::KdRestart,
    AccelKind::KdBacktrack,
    AccelKind::Bvh2,
    AccelKind::ThreadedBvh,
];

fn default_meshes() -> Vec<String> {
    let mut m = vec![
        shared_mesh("teapot_992.obj"),
        shared_mesh("bunny_3674.obj"),
        shared_mesh("dragon_vrip_res2.ply.gz"),
        "builtin:terrain".to_string(),
        "builtin:scatter".to_string(),
    ];
    match cached_dragon() {
        Some(d) => m.push(d),
        None => eprintln!(
            "note: full dragon not in data-cache/ (run scripts/fetch-bench-data or pass --mesh); left out"
        ),
    }
    m
}

/// Run the experiment.
pub fn run(args: KdTraversalArgs) -> Result<ExitCode> {
    image_side("--size", args.size)?;
    let reps = ranges::reps(args.reps)?;
    let meshes = if args.mesh.is_empty() {
        default_meshes()
    } else {
        args.mesh.clone()
    };
    let opts = args.build.options();
    let threads = pool(args.threads)?;
    let mut memory = Vec::new();
    let mut speed = Vec::new();
    for spec in &meshes {
        let mut scene = scene_arg::load(spec)?;
        if scene.mesh.normals.is_none() {
            scene.mesh.compute_vertex_normals();
        }
        let mesh = &scene.mesh;
        let name = scene.name.clone();
        let camera = raysets::standard_camera(mesh);
        let light = raysets::standard_light(&mesh.bounds());
        let lights = if scene.lights.is_empty() {
            vec![PointLight::new(light, raykit_core::Vec3::splat(1.0)).into()]
        } else {
            scene.lights.clone()
        };
        let reference = build_accel(AccelKind::Bvh2, TestKind::Moller, mesh, &opts);
        let primary = raysets::primary(&camera, args.size);
        let mut prim_hits = vec![None; primary.len()];
        reference.intersect_batch(&primary, &mut prim_hits);
        let shadow = raysets::shadow(mesh, &primary, &prim_hits, light);

        eprintln!(
            "{name}: {} triangles, building the SAH kd-tree…",
            mesh.num_triangles()
        );
        let ((root, cell), kd_build_s) = threads.install(|| timed(|| build_tree(mesh, &opts.kd)));
        let bar = ProgressBar::new((TESTS.len() * ACCELS.len()) as u64).with_style(
            ProgressStyle::with_template("{prefix} {bar:30} {pos}/{len} {msg}").unwrap(),
        );
        bar.set_prefix(name.clone());
        for test in TESTS {
            // Each test is checked against the BVH2 with the same test (two
            // tests may differ on rays through cracks of open meshes).
            let reference = build_accel(AccelKind::Bvh2, test, mesh, &opts);
            let mut prim_ref = vec![None; primary.len()];
            reference.intersect_batch(&primary, &mut prim_ref);
            let mut shadow_ref = vec![false; shadow.len()];
            reference.occluded_batch(&shadow, &mut shadow_ref);
            for kind in ACCELS {
                bar.set_message(format!("{} × {}", kind.name(), test.name()));
                let accel = kd_accel_from_tree(kind, test, mesh, &root, &cell, &opts, kd_build_s)
                    .unwrap_or_else(|| build_accel(kind, test, mesh, &opts));
                if test == TestKind::Moller {
                    let s = accel.stats();
                    memory.push(MemoryRow {
                        mesh: name.clone(),
                        triangles: mesh.num_triangles(),
                        accel: kind.name(),
                        node_bytes: s.node_bytes,
                        node_kb: s.node_bytes as f64 / 1024.0,
                        bytes_per_triangle: s.node_bytes as f64
                            / mesh.num_triangles().max(1) as f64,
                        nodes: s.nodes,
                        leaves: s.leaves,
                        triangle_refs: s.triangle_refs,
                        depth: s.depth,
                    });
                }
                let row = threads.install(|| {
                    measure(
                        accel.as_ref(),
                        &scene.mesh,
                        &lights,
                        &camera,
                        args.size,
                        &shadow,
                        reps,
                    )
                });
                let mut hits = vec![None; primary.len()];
                let mut occ = vec![false; shadow.len()];
                threads.install(|| {
                    accel.intersect_batch(&primary, &mut hits);
                    accel.occluded_batch(&shadow, &mut occ);
                });
                let disagreements = raykit_core::verify::compare_hits(&prim_ref, &hits)
                    .disagreements()
                    + shadow_ref.iter().zip(&occ).filter(|(a, b)| a != b).count();
                speed.push(SpeedRow {
                    mesh: name.clone(),
                    accel: kind.name(),
                    test: test.name(),
                    primary_phong_mrays: row.0,
                    shadow_mrays: row.1,
                    spread: row.2,
                    disagreements,
                });
                bar.inc(1);
            }
        }
        bar.finish_and_clear();
        eprintln!("{name}: kd-tree build {:.2} s", kd_build_s);
    }
    let md = markdown(&memory, &speed, &args, &meshes);
    print!("{md}");
    write_text(&args.out, "results.md", &md)?;
    write_csv(&args.out, "memory.csv", &memory)?;
    write_csv(&args.out, "speed.csv", &speed)?;
    let json = serde_json::json!({ "memory": memory, "speed": speed, "size": args.size, "threads": args.threads, "reps": reps });
    write_text(
        &args.out,
        "results.json",
        &serde_json::to_string_pretty(&json)?,
    )?;
    eprintln!(
        "wrote {}/results.md, memory.csv, speed.csv, results.json",
        args.out.display()
    );
    let bad: usize = speed.iter().map(|r| r.disagreements).sum();
    if bad > 0 {
        eprintln!("raykit: {bad} answers disagree with the BVH2 reference (see the table)");
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

/// Median Mrays/s of Phong-shaded primary rays and of shadow rays, and the
/// worst spread (max - min) / median (`None` with fewer than two
/// repetitions).
fn measure(
    accel: &dyn Accel,
    mesh: &raykit_core::TriangleMesh,
    lights: &[raykit_scene::Light],
    camera: &raykit_core::Camera,
    size: u32,
    shadow: &[Ray],
    reps: usize,
) -> (f64, f64, Option<f64>) {
    let ropts = RenderOptions {
        width: size,
        height: size,
        shadows: false,
        ..RenderOptions::default()
    };
    let mut prim = Vec::new();
    let mut shad = Vec::new();
    let mut occ = vec![false; shadow.len()];
    for _ in 0..reps {
        let (_, t) = timed(|| render(mesh, lights, accel, camera, &ropts, &|_| {}));
        prim.push((size as f64).powi(2) / t / 1e6);
        let (_, t) = timed(|| accel.occluded_batch(shadow, &mut occ));
        shad.push(shadow.len() as f64 / t / 1e6);
    }
    (
        median_min_max(&prim).0,
        median_min_max(&shad).0,
        worse_spread(spread(&prim), spread(&shad)),
    )
}

fn markdown(
    memory: &[MemoryRow],
    speed: &[SpeedRow],
    args: &KdTraversalArgs,
    meshes: &[String],
) -> String {
    let mut s = String::new();
    s += &format!(
        "# kd-tree traversal experiment\n\n`raykit experiment kdtree-traversal --size {} --reps {} --threads {}` on {} mesh(es).\n\n",
        args.size,
        args.reps,
        args.threads,
        meshes.len()
    );
    s += "## Node memory\n\nStructure bytes without the precomputed triangles (kd-trees: 8-byte nodes + per-traversal extras; the index list is counted with the triangles).\n\n";
    s += "| mesh | triangles | accel | node KB | bytes/triangle | nodes | leaves | refs | depth |\n|---|---:|---|---:|---:|---:|---:|---:|---:|\n";
    for r in memory {
        s += &format!(
            "| {} | {} | {} | {:.1} | {:.1} | {} | {} | {} | {} |\n",
            r.mesh,
            r.triangles,
            r.accel,
            r.node_kb,
            r.bytes_per_triangle,
            r.nodes,
            r.leaves,
            r.triangle_refs,
            r.depth
        );
    }
    s += "\n## Mrays/s: primary rays with Phong shading / shadow rays\n\n";
    let mut names: Vec<&str> = Vec::new();
    for r in speed {
        if !names.contains(&r.mesh.as_str()) {
            names.push(&r.mesh);
        }
    }
    for m in names {
        s += &format!(
            "### {m}\n\n| accel | projection | plucker | moller |\n|---|---:|---:|---:|\n"
        );
        for kind in ACCELS {
            let cells: Vec<String> = TESTS
                .iter()
                .map(|t| {
                    speed
                        .iter()
                        .find(|r| r.mesh == m && r.accel == kind.name() && r.test == t.name())
                        .map(|r| format!("{:.2} / {:.2}", r.primary_phong_mrays, r.shadow_mrays))
                        .unwrap_or_default()
                })
                .collect();
            s += &format!("| {} | {} |\n", kind.name(), cells.join(" | "));
        }
        let spread = speed
            .iter()
            .filter(|r| r.mesh == m)
            .map(|r| r.spread)
            .fold(None, worse_spread);
        let bad: usize = speed
            .iter()
            .filter(|r| r.mesh == m)
            .map(|r| r.disagreements)
            .sum();
        s += &format!(
            "\nWorst spread (max-min)/median: {}. Disagreements with the BVH2: {bad}.\n\n",
            spread_percent(spread)
        );
    }
    s
}
