//! `raykit experiment gpu`: Mrays/s
//! of each kernel (stack kd-tree, threaded BVH, compressed wide BVH) ×
//! triangle test (Plücker, Möller) on primary, shadow and incoherent rays,
//! timed on the GPU's own clock where it has one (the median of the runs,
//! with their spread and the share a launch costs), with the nodes and
//! bytes each ray fetches (counted by the kernels), the node memory of each
//! layout (Table 1) and the CPU's speed on the same structure beside it.
//! A ratio whose two sides' run ranges overlap is marked not significant.

use super::{cached_dragon, gpu_terrain, shared_mesh, write_csv, write_text};
use crate::args::backend::{cpu_twin, open_gpu};
use crate::args::build_args::BuildArgs;
use crate::args::ranges::image_side;
use crate::args::scene_arg;
use crate::bench::gpu::gpu_lists;
use crate::gpu_measure::{measure, Workload, SETS};
use crate::measure::{median_min_max, pool, timed};
use anyhow::Result;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use raykit_core::accel::{build_accel, AccelKind};
use raykit_core::raysets;
use raykit_core::tri::TestKind;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `raykit experiment gpu`.
#[derive(Args)]
#[command(
    after_help = "Default meshes: built-in shirley6 (Shirley's six-object test scene), the shared bunny\n\
and dragon (res2, 202k triangles, the size of the Fairy Forest scene), and the full\n\
871k dragon (the size of its Happy Buddha) when scripts/fetch-bench-data has fetched it.\n\
Every GPU answer is checked against the CPU structure of the same name. On Mesa's\n\
lavapipe (no GPU) the kernels run on the CPU cores: the figures then compare\n\
organisations, not hardware."
)]
pub struct GpuExperimentArgs {
    /// Meshes (file or builtin:NAME); repeat the option for several.
    #[arg(long)]
    mesh: Vec<String>,
    /// Image side of the ray sets (SIZE² primary and incoherent rays), 1 to
    /// 16384.
    #[arg(long, default_value_t = 512)]
    size: u32,
    /// Timed runs of every measurement, after two warm-up runs (the median
    /// is reported; at least 5).
    #[arg(long, default_value_t = 5)]
    reps: usize,
    /// Structures (`all` = kd-stack,kd-ropes,bvh-threaded,cwbvh).
    #[arg(long, default_value = "all")]
    accel: String,
    /// Triangle tests (`all` = plucker,moller).
    #[arg(long, default_value = "all")]
    test: String,
    /// DEMs for the terrain casters (repeat the option; default: the shared
    /// Terragen, SRTM and lidar DEMs; `none` skips the terrain part).
    #[arg(long)]
    dem: Vec<String>,
    /// Terrain view size `WIDTHxHEIGHT`.
    #[arg(long, default_value = "1024x768", value_parser = parse_view)]
    terrain_view: (u32, u32),
    /// Output folder for results.md, speed.csv, terrain.csv and results.json.
    #[arg(long, default_value = "experiments/gpu")]
    out: PathBuf,
    #[command(flatten)]
    build: BuildArgs,
}

/// One mesh × structure × test.
#[derive(Serialize, Clone)]
struct Row {
    mesh: String,
    triangles: usize,
    accel: &'static str,
    test: &'static str,
    node_kb: f64,
    device_mb: f64,
    gpu_primary: f64,
    gpu_shadow: f64,
    gpu_incoherent: f64,
    /// Slowest and fastest runs (Mrays/s) per set, for the significance of
    /// ratios.
    gpu_primary_lo: f64,
    gpu_primary_hi: f64,
    gpu_shadow_lo: f64,
    gpu_shadow_hi: f64,
    gpu_incoherent_lo: f64,
    gpu_incoherent_hi: f64,
    /// Largest share of a dispatch's time that a one-ray dispatch takes.
    launch_share: f64,
    nodes_primary: f64,
    nodes_shadow: f64,
    nodes_incoherent: f64,
    bytes_primary: f64,
    bytes_shadow: f64,
    bytes_incoherent: f64,
    tris_primary: f64,
    tris_shadow: f64,
    tris_incoherent: f64,
    clock: &'static str,
    cpu_primary: f64,
    cpu_shadow: f64,
    cpu_incoherent: f64,
    spread: f64,
    checked: usize,
    disagreements: usize,
    /// Disagreements where the ray grazes a triangle edge (f64): the GPU
    /// rounds division and fused multiply-adds its own way.
    edge_grazes: usize,
    ties: usize,
}

fn parse_view(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once('x')
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, got '{s}'"))?;
    let n = |v: &str| {
        v.parse::<u32>()
            .ok()
            .filter(|&x| (1..=16384).contains(&x))
            .ok_or_else(|| format!("'{v}' is not a size from 1 to 16384"))
    };
    Ok((n(w)?, n(h)?))
}

fn default_dems() -> Vec<String> {
    [
        "RealisticTerrain_Large.ter",
        "N57E011.hgt",
        "lidar_dem_400.tif",
    ]
    .iter()
    .map(|f| {
        super::shared_data()
            .join("terrain")
            .join(f)
            .to_string_lossy()
            .into_owned()
    })
    .collect()
}

fn default_meshes() -> Vec<String> {
    let mut m = vec![
        "builtin:shirley6".to_string(),
        shared_mesh("bunny_3674.obj"),
        shared_mesh("dragon_vrip_res2.ply.gz"),
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
pub fn run(args: GpuExperimentArgs) -> Result<ExitCode> {
    image_side("--size", args.size)?;
    let (accels, tests) = gpu_lists(&args.accel, &args.test)?;
    let dems = match args.dem.as_slice() {
        [] => default_dems(),
        [n] if n == "none" => Vec::new(),
        d => d.to_vec(),
    };
    // Every DEM is read before the meshes are measured, so that a missing
    // or broken file is refused at once rather than after the long part.
    let dems = dems
        .iter()
        .map(|d| gpu_terrain::load(d))
        .collect::<Result<Vec<_>>>()?;
    let ctx = open_gpu()?;
    let meshes = if args.mesh.is_empty() {
        default_meshes()
    } else {
        args.mesh.clone()
    };
    let opts = args.build.options();
    let all = pool(0)?;
    let reps = args.reps.max(5);
    let mut rows = Vec::new();
    for spec in &meshes {
        let scene = scene_arg::load(spec)?;
        let mesh = &scene.mesh;
        let sets = all.install(|| {
            let helper = build_accel(AccelKind::Bvh2, TestKind::Moller, mesh, &opts);
            raysets::standard_sets(mesh, helper.as_ref(), args.size, 1)
        });
        let bar = ProgressBar::new((accels.len() * tests.len() * 4) as u64).with_style(
            ProgressStyle::with_template("{prefix} {bar:30} {pos}/{len} {msg}")
                .expect("valid template"),
        );
        bar.set_prefix(scene.name.clone());
        let work = Workload {
            mesh,
            opts: &opts,
            sets: &sets,
            reps,
        };
        for &test in &tests {
            for &kind in &accels {
                let g = measure(&ctx, &work, kind, test, |m| {
                    bar.set_message(m.to_string());
                    bar.inc(1);
                })?;
                bar.set_message(format!("{} × {}: CPU", kind.name(), test.name()));
                let cpu = all.install(|| build_accel(cpu_twin(kind), test, mesh, &opts));
                let mut cpu_rates = [0.0; 3];
                let mut spread = g.cells.iter().map(|c| c.spread).fold(0.0, f64::max);
                for (si, set) in SETS.iter().enumerate() {
                    let rays = &sets[si];
                    let times: Vec<f64> = (0..reps)
                        .map(|_| {
                            all.install(|| {
                                timed(|| {
                                    if *set == "shadow" {
                                        let mut o = vec![false; rays.len()];
                                        cpu.occluded_batch(rays, &mut o);
                                    } else {
                                        let mut h = vec![None; rays.len()];
                                        cpu.intersect_batch(rays, &mut h);
                                    }
                                })
                                .1
                            })
                        })
                        .collect();
                    let (med, lo, hi) = median_min_max(&times);
                    spread = spread.max((hi - lo) / med);
                    cpu_rates[si] = rays.len() as f64 / med / 1e6;
                }
                rows.push(Row {
                    mesh: scene.name.clone(),
                    triangles: mesh.num_triangles(),
                    accel: g.accel,
                    test: g.test,
                    node_kb: g.node_bytes as f64 / 1024.0,
                    device_mb: g.bytes as f64 / 1e6,
                    gpu_primary: g.cells[0].mrays,
                    gpu_shadow: g.cells[1].mrays,
                    gpu_incoherent: g.cells[2].mrays,
                    gpu_primary_lo: g.cells[0].mrays_lo,
                    gpu_primary_hi: g.cells[0].mrays_hi,
                    gpu_shadow_lo: g.cells[1].mrays_lo,
                    gpu_shadow_hi: g.cells[1].mrays_hi,
                    gpu_incoherent_lo: g.cells[2].mrays_lo,
                    gpu_incoherent_hi: g.cells[2].mrays_hi,
                    launch_share: g.cells.iter().map(|c| c.launch_share).fold(0.0, f64::max),
                    nodes_primary: g.cells[0].nodes_per_ray,
                    nodes_shadow: g.cells[1].nodes_per_ray,
                    nodes_incoherent: g.cells[2].nodes_per_ray,
                    bytes_primary: g.cells[0].bytes_per_ray,
                    bytes_shadow: g.cells[1].bytes_per_ray,
                    bytes_incoherent: g.cells[2].bytes_per_ray,
                    tris_primary: g.cells[0].tris_per_ray,
                    tris_shadow: g.cells[1].tris_per_ray,
                    tris_incoherent: g.cells[2].tris_per_ray,
                    clock: g.clock,
                    cpu_primary: cpu_rates[0],
                    cpu_shadow: cpu_rates[1],
                    cpu_incoherent: cpu_rates[2],
                    spread,
                    checked: g.cells.iter().map(|c| c.verify.checked).sum(),
                    disagreements: g.cells.iter().map(|c| c.verify.disagreements()).sum(),
                    edge_grazes: g.cells.iter().map(|c| c.verify.edge_grazes).sum(),
                    ties: g.cells.iter().map(|c| c.verify.ties).sum(),
                });
            }
        }
        bar.finish_and_clear();
    }
    let mut terrain = Vec::new();
    for dem in &dems {
        eprintln!("terrain: {}…", dem.path());
        terrain.push(all.install(|| gpu_terrain::measure_dem(&ctx, dem, args.terrain_view, reps))?);
    }
    let mut md = markdown(&rows, &args, &ctx.describe(), all.current_num_threads());
    if !terrain.is_empty() {
        md += &gpu_terrain::markdown(&terrain, all.current_num_threads());
        write_csv(&args.out, "terrain.csv", &terrain)?;
    }
    print!("{md}");
    write_text(&args.out, "results.md", &md)?;
    write_csv(&args.out, "speed.csv", &rows)?;
    let json = serde_json::json!({ "adapter": ctx.describe(), "size": args.size, "reps": reps, "rows": rows, "terrain": terrain });
    write_text(
        &args.out,
        "results.json",
        &serde_json::to_string_pretty(&json)?,
    )?;
    eprintln!(
        "wrote {}/results.md, speed.csv, results.json",
        args.out.display()
    );
    let bad: usize = rows.iter().map(|r| r.disagreements - r.edge_grazes).sum();
    if bad > 0 {
        eprintln!(
            "raykit: {bad} GPU answers disagree with the CPU other than at edge grazes (see the table)"
        );
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

fn markdown(rows: &[Row], args: &GpuExperimentArgs, adapter: &str, threads: usize) -> String {
    let clock = rows.first().map_or("–", |r| r.clock);
    let mut s = format!(
        "# GPU kernels\n\n`raykit experiment gpu --size {} --reps {}` on {adapter}; CPU figures on {threads} threads.\n\n",
        args.size,
        args.reps.max(5)
    );
    s += &format!(
        "Mrays/s, median of {} timed runs after two warm-up runs, timed with {clock}; uploads and read-back excluded. \
         CPU: the structure the kernel mirrors (cwbvh: bvh8) through the batch API. Shadow = occlusion (any hit). \
         noise = (slowest − fastest) / median over every cell of the row; launch = a one-ray dispatch's time as a share \
         of the batch's (the fixed cost each measurement carries; below 5% the batch is large enough).\n\n",
        args.reps.max(5)
    );
    s += "| mesh | triangles | accel | test | node KB | device MB | GPU primary | GPU shadow | GPU incoherent | CPU primary | CPU shadow | CPU incoherent | noise | launch | checked | differ | of which edge grazes | ties |\n|---|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {} | {:.1} | {:.1} | {:.3} | {:.3} | {:.3} | {:.2} | {:.2} | {:.2} | {:.0}% | {:.1}% | {} | {} | {} | {} |\n",
            r.mesh, r.triangles, r.accel, r.test, r.node_kb, r.device_mb, r.gpu_primary, r.gpu_shadow,
            r.gpu_incoherent, r.cpu_primary, r.cpu_shadow, r.cpu_incoherent, r.spread * 100.0,
            r.launch_share * 100.0, r.checked, r.disagreements, r.edge_grazes, r.ties
        );
    }
    s += "\n## What each ray fetches (counted by the kernels; the same on any device)\n\nPer ray: nodes visited, triangle records tested, bytes of nodes, index entries and triangle records fetched.\n\n| mesh | accel | test | primary nodes | primary tris | primary bytes | shadow nodes | shadow tris | shadow bytes | incoherent nodes | incoherent tris | incoherent bytes |\n|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {:.1} | {:.1} | {:.0} | {:.1} | {:.1} | {:.0} | {:.1} | {:.1} | {:.0} |\n",
            r.mesh, r.accel, r.test, r.nodes_primary, r.tris_primary, r.bytes_primary,
            r.nodes_shadow, r.tris_shadow, r.bytes_shadow, r.nodes_incoherent,
            r.tris_incoherent, r.bytes_incoherent
        );
    }
    let mut meshes: Vec<&str> = Vec::new();
    for r in rows {
        if !meshes.contains(&r.mesh.as_str()) {
            meshes.push(&r.mesh);
        }
    }
    // (median, slowest, fastest) Mrays/s of a cell.
    let get = |m: &str, a: &str, t: &str, set: usize| {
        rows.iter()
            .find(|r| r.mesh == m && r.accel == a && r.test == t)
            .map(|r| {
                [
                    (r.gpu_primary, r.gpu_primary_lo, r.gpu_primary_hi),
                    (r.gpu_shadow, r.gpu_shadow_lo, r.gpu_shadow_hi),
                    (r.gpu_incoherent, r.gpu_incoherent_lo, r.gpu_incoherent_hi),
                ][set]
            })
    };
    let pairs: [(&str, &str, &str, &str); 9] = [
        ("kd-stack", "plucker", "kd-ropes", "plucker"),
        ("kd-stack", "moller", "kd-ropes", "moller"),
        ("kd-stack", "plucker", "bvh-threaded", "plucker"),
        ("kd-stack", "moller", "bvh-threaded", "moller"),
        ("cwbvh", "plucker", "kd-stack", "plucker"),
        ("cwbvh", "moller", "kd-stack", "moller"),
        ("kd-stack", "plucker", "kd-stack", "moller"),
        ("bvh-threaded", "plucker", "bvh-threaded", "moller"),
        ("cwbvh", "plucker", "cwbvh", "moller"),
    ];
    s += "\n## Ratios on the GPU\n\nMedian ÷ median; *not significant* where the two cells' ranges of runs (slowest to fastest) overlap.\n\n| mesh | set |";
    for (a, t, b, u) in pairs {
        s += &if t == u {
            format!(" {a} ÷ {b} ({t}) |")
        } else {
            format!(" {t} ÷ {u} ({a}) |")
        };
    }
    s += "\n|---|---|";
    s += &"---:|".repeat(pairs.len());
    s += "\n";
    for m in meshes {
        for (si, set) in SETS.iter().enumerate() {
            s += &format!("| {m} | {set} |");
            for (a, t, b, u) in pairs {
                s += &format!(" {} |", ratio(get(m, a, t, si), get(m, b, u, si)));
            }
            s += "\n";
        }
    }
    s
}

/// `x ÷ y` of two (median, slowest, fastest) cells, marked not significant
/// when their ranges overlap.
fn ratio(x: Option<(f64, f64, f64)>, y: Option<(f64, f64, f64)>) -> String {
    match (x, y) {
        (Some(x), Some(y)) if y.0 > 0.0 => {
            let significant = x.1 > y.2 || x.2 < y.1;
            if significant {
                format!("{:.2}×", x.0 / y.0)
            } else {
                format!("{:.2}× *not significant*", x.0 / y.0)
            }
        }
        _ => "–".to_string(),
    }
}
