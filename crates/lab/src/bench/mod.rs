//! `raykit bench`: build time, memory and Mrays/s of structures ×
//! triangle tests (the default one, or every one with `--accel all --test
//! all`) on the standard ray sets, on one thread and on all threads.

#[cfg(feature = "embree")]
pub mod compare;
pub mod gpu;

use crate::args::backend::Backend;
use crate::args::scene_arg;
use crate::measure::{self, median_min_max, pool, spread_percent, timed, worse_spread};
use anyhow::{anyhow, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use raykit_core::accel::{build_accel, AccelKind};
use raykit_core::raysets::{self, RayKind};
use raykit_core::tri::TestKind;
use raykit_core::verify::{self, Verdict};
use raykit_core::{Accel, Hit, Ray, TriangleMesh};
use serde::Serialize;
use std::process::ExitCode;

/// Arguments of `raykit bench`.
#[derive(Args)]
#[command(
    after_help = "Each figure is the median of --reps runs, except that a structure whose build\n\
takes over 5 s on one thread has its builds timed once. The spread (max-min)/median\n\
of the ray timings is reported so noisy machines show (n/a with --reps 1). With\n\
--compare, the engines of a cell are timed in turn (each repetition times ours,\n\
then each Embree's), so that a burst of host noise falls on both. Every trace cell\n\
runs one untimed round before its timed ones. Brute force is timed on a\n\
sample of each ray set sized to take about a second. The ray sets are those of\n\
`raykit rays`."
)]
pub struct BenchArgs {
    /// Mesh file or builtin:NAME. With --compare the option may be
    /// repeated: every mesh is compared and a summary gives our best ratio
    /// per cell and mesh.
    #[arg(long, default_value = "builtin:cornell", action = clap::ArgAction::Append)]
    mesh: Vec<String>,
    /// Structures to measure, comma-separated, or `all` (default bvh8, the
    /// fastest; with --backend gpu, every GPU structure).
    #[arg(long)]
    accel: Option<String>,
    /// Triangle tests to measure, comma-separated, or `all` (default moller,
    /// the fastest with bvh8; with --backend gpu, every test).
    #[arg(long)]
    test: Option<String>,
    /// Image side of the ray sets (SIZE² primary and incoherent rays),
    /// 1-16384.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..=raykit_io::MAX_IMAGE_SIDE as i64))]
    size: u32,
    /// Repetitions of every measurement (the median is reported), 1-1000.
    #[arg(long, default_value_t = 3, value_parser = clap::builder::TypedValueParser::map(clap::value_parser!(u64).range(1..=1000), |v| v as usize))]
    reps: usize,
    /// Threads of the parallel runs (0 = one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Check this many rays of every set against brute force (the CPU
    /// structures; with --backend gpu every answer is checked against the
    /// CPU structure of the same kind instead).
    #[arg(long, value_name = "N")]
    verify: Option<usize>,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
    /// Compare with Embree in the same process (a build with `--features
    /// embree`): `embree` compares with Embree 4 and Embree 3 (Embree 4
    /// where it is found, see below), `embree4` or `embree3` with one
    /// version. Embree 3 is Debian's libembree-dev, linked; Embree 4 is
    /// loaded at run time from the file RAYKIT_EMBREE4 names, else from the
    /// `embreex` wheel that `python3` (or RAYKIT_PYTHON) imports (`pip
    /// install embreex`). Ours are the structures × tests that --accel/--test
    /// list (`all` means bvh8 and moller, our fastest); prints per cell
    /// ours, Embree 4 at its fastest query API (rtcIntersect1/4/8/16,
    /// named), Embree 3 and the ratios, the one-ray cells (our per-ray
    /// `Accel::intersect`/`occluded` against rtcIntersect1/rtcOccluded1, one
    /// thread), our SAH cost beside the build times, and checks that every
    /// answer agrees. Builds are timed rung for rung: ours as --bvh-build
    /// says (default `sah`) against Embree MEDIUM, and the trees we trace
    /// (`high` where --bvh-build is `sah`, else the builder given) against
    /// Embree HIGH, whose tree Embree traces. RAYKIT_EMBREE_CONFIG adds to
    /// Embree's device configuration (e.g. `isa=avx2`, `verbose=1`);
    /// RAYKIT_EMBREE_TRACE_MEDIUM (any value) makes Embree trace its MEDIUM
    /// build instead of its HIGH one.
    #[arg(long, value_name = "ENGINE")]
    compare: Option<String>,
    /// `gpu` measures the GPU kernels (kd-stack, kd-ropes, bvh-threaded,
    /// cwbvh × plucker, moller) instead, every answer checked against the CPU
    /// structure it mirrors (cwbvh: bvh8); see also `raykit experiment gpu`.
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    backend: Backend,
    #[command(flatten)]
    build: crate::args::build_args::BuildArgs,
}

/// Speed on one ray set.
#[derive(Serialize)]
struct SetResult {
    kind: &'static str,
    rays: usize,
    mrays_1t: f64,
    mrays_nt: f64,
    /// Worst (max − min) / median of the timings on one and on all
    /// threads; `None` (null) with fewer than two repetitions.
    spread: Option<f64>,
    verify: Option<Verdict>,
}

/// One structure × test.
#[derive(Serialize)]
struct Row {
    accel: &'static str,
    test: &'static str,
    build_ms: f64,
    build_ms_1t: f64,
    bytes: usize,
    nodes: usize,
    depth: u32,
    sah_cost: f64,
    sets: Vec<SetResult>,
}

/// The whole run.
#[derive(Serialize)]
struct Report {
    mesh: String,
    triangles: usize,
    threads: usize,
    reps: usize,
    load_ms: f64,
    rows: Vec<Row>,
}

fn parse_list<K: Copy>(
    s: &str,
    all: &[K],
    name: fn(K) -> &'static str,
    what: &str,
) -> Result<Vec<K>> {
    if s == "all" {
        return Ok(all.to_vec());
    }
    let mut chosen: Vec<K> = Vec::new();
    for n in s.split(',') {
        let k = all
            .iter()
            .copied()
            .find(|k| name(*k) == n.trim())
            .ok_or_else(|| {
                let names: Vec<_> = all.iter().map(|k| name(*k)).collect();
                anyhow!(
                    "unknown {what} '{n}'; expected `all` or some of: {}",
                    names.join(", ")
                )
            })?;
        // A name given twice is measured once.
        if !chosen.iter().any(|c| name(*c) == name(k)) {
            chosen.push(k);
        }
    }
    Ok(chosen)
}

/// Run the benchmark.
pub fn run(args: BenchArgs) -> Result<ExitCode> {
    if let Some(engine) = &args.compare {
        if args.backend == Backend::Gpu {
            anyhow::bail!(
                "--compare {engine} measures the CPU engines; it does not take --backend gpu"
            );
        }
        return compare(&args, engine);
    }
    let [mesh_spec] = &args.mesh[..] else {
        anyhow::bail!("--mesh may be given several times only with --compare; this measurement takes one mesh");
    };
    if args.backend == Backend::Gpu {
        if let Some(k) = args.verify {
            eprintln!(
                "raykit: warning: --verify {k} is not used with --backend gpu: every GPU answer \
                 is checked against the CPU structure of the same kind"
            );
        }
        return gpu::run(gpu::GpuBenchSetup {
            mesh: mesh_spec,
            accel: args.accel.as_deref().unwrap_or("all"),
            test: args.test.as_deref().unwrap_or("all"),
            size: args.size,
            reps: args.reps.max(1),
            json: args.json,
            options: args.build.options(),
        });
    }
    let accels = parse_list(
        args.accel
            .as_deref()
            .unwrap_or(crate::args::build_args::DEFAULT_ACCEL),
        &AccelKind::ALL,
        AccelKind::name,
        "--accel",
    )?;
    let tests = parse_list(
        args.test.as_deref().unwrap_or("moller"),
        &TestKind::ALL,
        TestKind::name,
        "--test",
    )?;
    let reps = args.reps.max(1);
    let one = pool(1)?;
    let all = pool(args.threads)?;
    let threads = all.current_num_threads();
    let (scene, load_s) = timed(|| scene_arg::load(mesh_spec));
    let mesh = scene?.mesh;
    let opts = args.build.options();
    eprintln!(
        "{}: {} triangles; generating ray sets ({}²)…",
        mesh_spec,
        mesh.num_triangles(),
        args.size
    );
    let sets = all.install(|| {
        let helper = build_accel(AccelKind::Bvh8, TestKind::Moller, &mesh, &opts);
        raysets::standard_sets(&mesh, helper.as_ref(), args.size, 1)
    });
    let brute_sample = (2e8 / mesh.num_triangles().max(1) as f64).clamp(64.0, 1e9) as usize;
    let steps = (accels.len() * tests.len() * (1 + 2 * RayKind::ALL.len())) as u64;
    let bar = ProgressBar::new(steps).with_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} {msg} [{elapsed}<{eta}]")
            .expect("valid template"),
    );
    let mut rows = Vec::new();
    for &test in &tests {
        // Brute-force answers on the verification samples, shared by all structures.
        let reference = args.verify.map(|k| {
            bar.set_message(format!("brute force reference, {}", test.name()));
            let brute = build_accel(AccelKind::Brute, test, &mesh, &opts);
            all.install(|| {
                RayKind::ALL
                    .iter()
                    .enumerate()
                    .map(|(si, kind)| {
                        answers(
                            brute.as_ref(),
                            &pick(&sets[si], k),
                            *kind == RayKind::Shadow,
                        )
                    })
                    .collect::<Vec<_>>()
            })
        });
        for &kind in &accels {
            bar.set_message(format!("{} × {}: build", kind.name(), test.name()));
            let mut builds = Vec::new();
            let mut builds_1t = Vec::new();
            let mut accel = None;
            for _ in 0..reps {
                let (a, s) = all.install(|| timed(|| build_accel(kind, test, &mesh, &opts)));
                builds.push(s * 1e3);
                drop(a);
                let (a, s) = one.install(|| timed(|| build_accel(kind, test, &mesh, &opts)));
                builds_1t.push(s * 1e3);
                accel = Some(a);
                if s > 5.0 {
                    break;
                }
            }
            let accel = accel.expect("at least one build");
            bar.inc(1);
            let stats = accel.stats();
            let mut results = Vec::new();
            for (si, kind_set) in RayKind::ALL.into_iter().enumerate() {
                let rays = if kind == AccelKind::Brute {
                    pick(&sets[si], brute_sample)
                } else {
                    sets[si].clone()
                };
                let shadow = kind_set == RayKind::Shadow;
                let mut spread = None;
                let mut speed = |p: &rayon::ThreadPool| {
                    bar.set_message(format!(
                        "{} × {}: {} rays",
                        kind.name(),
                        test.name(),
                        kind_set.name()
                    ));
                    let times: Vec<f64> = (0..reps)
                        .map(|_| p.install(|| timed(|| answers(accel.as_ref(), &rays, shadow)).1))
                        .collect();
                    spread = worse_spread(spread, measure::spread(&times));
                    bar.inc(1);
                    rays.len() as f64 / median_min_max(&times).0 / 1e6
                };
                // One untimed round, so that the first timed column does not
                // pay for the first touch of the tree and the rays.
                all.install(|| answers(accel.as_ref(), &rays, shadow));
                let mrays_1t = speed(&one);
                let mrays_nt = speed(&all);
                let verify = reference
                    .as_ref()
                    .filter(|_| kind != AccelKind::Brute)
                    .map(|r| {
                        let k = args.verify.unwrap_or(0);
                        let got =
                            all.install(|| answers(accel.as_ref(), &pick(&sets[si], k), shadow));
                        got.compare(&r[si])
                    });
                results.push(SetResult {
                    kind: kind_set.name(),
                    rays: rays.len(),
                    mrays_1t,
                    mrays_nt,
                    spread,
                    verify,
                });
            }
            rows.push(Row {
                accel: kind.name(),
                test: test.name(),
                build_ms: median_min_max(&builds).0,
                build_ms_1t: median_min_max(&builds_1t).0,
                bytes: stats.bytes,
                nodes: stats.nodes,
                depth: stats.depth,
                sah_cost: stats.sah_cost,
                sets: results,
            });
        }
    }
    bar.finish_and_clear();
    let report = Report {
        mesh: mesh_spec.clone(),
        triangles: mesh.num_triangles(),
        threads,
        reps,
        load_ms: load_s * 1e3,
        rows,
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_table(&report, &mesh);
    }
    let failed = report
        .rows
        .iter()
        .flat_map(|r| &r.sets)
        .any(|s| s.verify.as_ref().is_some_and(|v| !v.ok()));
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

/// `k` rays spread evenly over the set.
fn pick(rays: &[Ray], k: usize) -> Vec<Ray> {
    verify::sample(rays.len(), k)
        .into_iter()
        .map(|i| rays[i])
        .collect()
}

/// Answers of one batch: nearest hits, or occlusion for shadow rays.
enum Answers {
    Hits(Vec<Option<Hit>>),
    Occluded(Vec<bool>),
}

impl Answers {
    fn compare(&self, reference: &Answers) -> Verdict {
        match (reference, self) {
            (Answers::Hits(r), Answers::Hits(g)) => verify::compare_hits(r, g),
            (Answers::Occluded(r), Answers::Occluded(g)) => verify::compare_occlusion(r, g),
            _ => unreachable!("same set, same kind of answer"),
        }
    }
}

fn answers(accel: &dyn Accel, rays: &[Ray], shadow: bool) -> Answers {
    if shadow {
        let mut out = vec![false; rays.len()];
        accel.occluded_batch(rays, &mut out);
        Answers::Occluded(out)
    } else {
        let mut out = vec![None; rays.len()];
        accel.intersect_batch(rays, &mut out);
        Answers::Hits(out)
    }
}

fn print_table(report: &Report, mesh: &TriangleMesh) {
    println!(
        "{}: {} triangles, {} threads, median of {} runs (load {:.0} ms)",
        report.mesh,
        mesh.num_triangles(),
        report.threads,
        report.reps,
        report.load_ms
    );
    let n = report.threads;
    println!(
        "{:<13} {:<10} {:>9} {:>9} {:>8} {:>7} | {:>8} {:>8} | {:>8} {:>8} | {:>8} {:>8} | {:>6}",
        "accel",
        "test",
        "build ms",
        "build 1T",
        "MB",
        "SAH",
        "prim 1T",
        format!("prim {n}T"),
        "shad 1T",
        format!("shad {n}T"),
        "inc 1T",
        format!("inc {n}T"),
        "noise"
    );
    for r in &report.rows {
        let s = &r.sets;
        let spread = s.iter().map(|x| x.spread).fold(None, worse_spread);
        println!(
            "{:<13} {:<10} {:>9.1} {:>9.1} {:>8.1} {:>7.1} | {:>8} {:>8} | {:>8} {:>8} | {:>8} {:>8} | {:>6}",
            r.accel,
            r.test,
            r.build_ms,
            r.build_ms_1t,
            r.bytes as f64 / 1e6,
            r.sah_cost,
            rate(s[0].mrays_1t),
            rate(s[0].mrays_nt),
            rate(s[1].mrays_1t),
            rate(s[1].mrays_nt),
            rate(s[2].mrays_1t),
            rate(s[2].mrays_nt),
            spread_percent(spread)
        );
    }
    println!("Mrays/s: primary and incoherent = nearest hit; shadow = occlusion (any hit). noise = worst (max-min)/median, n/a with fewer than 2 runs.");
    let checked: Vec<_> = report
        .rows
        .iter()
        .flat_map(|r| {
            r.sets
                .iter()
                .filter_map(move |s| s.verify.as_ref().map(|v| (r, s, v)))
        })
        .collect();
    if checked.is_empty() {
        return;
    }
    let rays: usize = checked.iter().map(|c| c.2.checked).sum();
    let ties: usize = checked.iter().map(|c| c.2.ties).sum();
    let failed: Vec<_> = checked.iter().filter(|c| !c.2.ok()).collect();
    println!(
        "verify: {} answers ({} structure × test × set cells) compared with brute force: {} cells disagree, {} ties on shared edges or coincident triangles",
        rays,
        checked.len(),
        failed.len(),
        ties
    );
    for (r, s, v) in failed {
        println!(
            "  FAILED {} × {} {}: {} of {} rays hit/miss, {} distance",
            r.accel, r.test, s.kind, v.hit_miss, v.checked, v.distance
        );
    }
}

/// Mrays/s with enough digits to show slow structures too.
fn rate(mrays: f64) -> String {
    if mrays >= 1.0 {
        format!("{mrays:.2}")
    } else if mrays >= 0.01 {
        format!("{mrays:.3}")
    } else {
        format!("{mrays:.5}")
    }
}

/// `--compare ENGINE`.
fn compare(args: &BenchArgs, engine: &str) -> Result<ExitCode> {
    let (want3, want4) = match engine {
        "embree" => (true, true),
        "embree3" => (true, false),
        "embree4" => (false, true),
        _ => anyhow::bail!(
            "unknown --compare engine '{engine}': expected embree (both versions), embree4 or embree3"
        ),
    };
    #[cfg(feature = "embree")]
    {
        use raykit_embree::Embree4;
        let embree4 = if !want4 {
            None
        } else {
            match Embree4::load() {
                Ok(lib) => {
                    eprintln!("Embree {} from {}", lib.version, lib.path.display());
                    Some(lib)
                }
                // `embree` compares with whichever versions there are.
                Err(e) if want3 => {
                    eprintln!("note: comparing with Embree 3 only: {e:#}");
                    None
                }
                Err(e) => return Err(e),
            }
        };
        let one = |s: &str, default: &str| {
            if s == "all" {
                default.to_string()
            } else {
                s.to_string()
            }
        };
        let kinds = parse_list(
            &one(args.accel.as_deref().unwrap_or("all"), "bvh8"),
            &AccelKind::ALL,
            AccelKind::name,
            "--accel",
        )?;
        let tests = parse_list(
            &one(args.test.as_deref().unwrap_or("all"), "moller"),
            &TestKind::ALL,
            TestKind::name,
            "--test",
        )?;
        let ours = kinds
            .iter()
            .flat_map(|&k| tests.iter().map(move |&t| (k, t)))
            .collect();
        let meshes = args
            .mesh
            .iter()
            .map(|m| Ok((m.clone(), scene_arg::load(m)?.mesh)))
            .collect::<Result<Vec<_>>>()?;
        compare::run(compare::CompareSetup {
            meshes: &meshes,
            ours,
            options: args.build.options(),
            size: args.size,
            reps: args.reps.max(1),
            threads: args.threads,
            json: args.json,
            yardsticks: compare::Yardsticks {
                embree3: want3,
                embree4,
            },
        })
    }
    #[cfg(not(feature = "embree"))]
    {
        let _ = (args, want3, want4);
        anyhow::bail!(
        "this raykit was built without Embree: install libembree-dev (apt-get install libembree-dev) \
         and build with `cargo build --release --features embree`"
    )
    }
}
