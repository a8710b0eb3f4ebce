//! `raykit trace`: trace a ray file and write hits or occlusion bytes.

use crate::backend::{gpu_accel, open_gpu, Backend};
use crate::measure::{pool, timed};
use crate::scene_arg;
use crate::verify;
use anyhow::{anyhow, bail, Result};
use clap::Args;
use raykit_core::accel::{build_accel, AccelKind};
use raykit_core::tri::TestKind;
use raykit_core::Ray;
use raykit_gpu::{GpuScene, GpuTracer};
use serde_json::json;
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `raykit trace`.
#[derive(Args)]
#[command(after_help = "Prints one JSON line of statistics on stderr:\n\
{\"accel\", \"bvh_build\", \"test\", \"api\", \"load_ms\", \"build_ms\", \"trace_ms\", \"rays\", \"mrays\", \"threads\"}\n\
(trace_ms excludes loading and building; api: batch, or one-ray with --one-ray). Hit file: per ray f32 t, u32 prim (8 bytes; a miss is\n\
t = +inf, prim = 4294967295). Occlusion file: one byte per ray (1 = occluded).\n\n\
Several --mesh (or --instanced): an instanced scene under a two-level BVH, each file a geometry\n\
placed once, a glTF file one geometry per mesh and one instance per node. Its hit file: per ray\n\
f32 t, u32 prim, u32 geometry, u32 instance (16 bytes; a miss is t = +inf and all ids 4294967295;\n\
prim indexes the geometry's mesh). The JSON line adds \"geometries\", \"instances\",\n\
\"stored_triangles\", \"instanced_triangles\", \"scene_bytes\" and per --mesh its id ranges\n\
(\"inputs\").")]
pub struct TraceArgs {
    /// Mesh file or builtin:NAME; give several (--mesh A --mesh B) for an
    /// instanced scene whose hits name geometry and instance.
    #[arg(long, required = true)]
    mesh: Vec<String>,
    /// Trace as an instanced scene even with one --mesh (a glTF file keeps
    /// its instancing: one geometry per mesh, one instance per node); the
    /// hit file then has the geometry and instance ids.
    #[arg(long)]
    instanced: bool,
    /// Ray file (from `raykit rays` or another engine).
    #[arg(long)]
    rays: PathBuf,
    /// Output hit file (or occlusion file with --occlusion).
    #[arg(long)]
    out: PathBuf,
    /// Acceleration structure (`raykit info accels`; default bvh8, the
    /// fastest, or kd-stack with --backend gpu, which also takes
    /// bvh-threaded and brute). The JSON line names the one used.
    #[arg(long)]
    accel: Option<String>,
    /// Ray/triangle test (`raykit info tests`).
    #[arg(long, default_value = "moller")]
    test: String,
    /// Answer "is anything hit" (shadow rays) instead of the nearest hit.
    #[arg(long)]
    occlusion: bool,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Trace each ray through the one-ray API (`Accel::intersect` /
    /// `Accel::occluded`, one call per ray, as a library user looping over
    /// rays does) instead of the batch path with its ray packets; the
    /// answers are the same. CPU only.
    #[arg(long)]
    one_ray: bool,
    /// Also trace this many rays (spread over the file) with brute force and
    /// the same triangle test, report disagreements and fail if any.
    #[arg(long, value_name = "N")]
    verify: Option<usize>,
    /// Trace on the CPU (all cores) or on the GPU (wgpu compute kernels;
    /// the JSON line then names the adapter and adds the kernel time).
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    backend: Backend,
    #[command(flatten)]
    build: crate::build_args::BuildArgs,
}

/// Parse `--accel` and `--test`.
pub fn parse_names(accel: &str, test: &str) -> Result<(AccelKind, TestKind)> {
    let a = AccelKind::from_name(accel).ok_or_else(|| {
        let names: Vec<_> = AccelKind::ALL.iter().map(|k| k.name()).collect();
        anyhow!(
            "unknown --accel '{accel}'; expected one of: {}",
            names.join(", ")
        )
    })?;
    let t = TestKind::from_name(test).ok_or_else(|| {
        let names: Vec<_> = TestKind::ALL.iter().map(|k| k.name()).collect();
        anyhow!(
            "unknown --test '{test}'; expected one of: {}",
            names.join(", ")
        )
    })?;
    Ok((a, t))
}

/// Trace the file.
pub fn run(args: TraceArgs) -> Result<ExitCode> {
    if args.instanced || args.mesh.len() > 1 {
        return run_instanced(args);
    }
    if args.backend == Backend::Gpu {
        if args.one_ray {
            bail!("--one-ray traces on the CPU; drop it or --backend gpu");
        }
        return run_gpu(args);
    }
    let (kind, test) = parse_names(
        args.accel
            .as_deref()
            .unwrap_or(crate::build_args::DEFAULT_ACCEL),
        &args.test,
    )?;
    crate::paths::ensure_not_input(
        &args.out,
        &[&args.rays, std::path::Path::new(&args.mesh[0])],
    )?;
    let pool = pool(args.threads)?;
    let threads = pool.current_num_threads();
    let (scene, load_s) = timed(|| scene_arg::load(&args.mesh[0]));
    let mesh = scene?.mesh;
    let rays = raykit_io::read_rays(&args.rays)?;
    if rays.is_empty() {
        bail!("{}: the ray file holds no rays", args.rays.display());
    }
    let opts = args.build.options();
    let (accel, build_s) = pool.install(|| timed(|| build_accel(kind, test, &mesh, &opts)));
    let (hits, occluded);
    let trace_s;
    if args.occlusion {
        let mut out = vec![false; rays.len()];
        trace_s = pool.install(|| {
            timed(|| {
                if args.one_ray {
                    crate::one_ray::occluded_each(accel.as_ref(), &rays, &mut out)
                } else {
                    accel.occluded_batch(&rays, &mut out)
                }
            })
            .1
        });
        raykit_io::write_occlusion(&args.out, &out)?;
        occluded = Some(out);
        hits = None;
    } else {
        let mut out = vec![None; rays.len()];
        trace_s = pool.install(|| {
            timed(|| {
                if args.one_ray {
                    crate::one_ray::intersect_each(accel.as_ref(), &rays, &mut out)
                } else {
                    accel.intersect_batch(&rays, &mut out)
                }
            })
            .1
        });
        raykit_io::write_hits(&args.out, &out)?;
        hits = Some(out);
        occluded = None;
    }
    eprintln!(
        "{}",
        json!({
            "accel": kind.name(),
            "bvh_build": crate::build_args::quality_name(opts.quality),
            "test": test.name(),
            "api": if args.one_ray { "one-ray" } else { "batch" },
            "load_ms": load_s * 1e3,
            "build_ms": build_s * 1e3,
            "trace_ms": trace_s * 1e3,
            "rays": rays.len(),
            "mrays": rays.len() as f64 / trace_s / 1e6,
            "threads": threads,
        })
    );
    let Some(k) = args.verify else {
        return Ok(ExitCode::SUCCESS);
    };
    check_against_brute(
        false,
        &mesh,
        &rays,
        test,
        &opts,
        k,
        &pool,
        hits.as_deref(),
        occluded.as_deref(),
    )
}

/// `--verify N`: recheck N rays spread over the file with brute force and
/// the same triangle test; fail on any disagreement. On the GPU
/// (`gpu_rounding`), whose division and fused multiply-adds may round
/// differently from the CPU, disagreements where the ray grazes a triangle
/// edge (f64, see [`verify::edge_grazes`]) are counted apart and allowed;
/// for occlusion only the blockers brute force finds can be checked, so a
/// GPU that catches an edge brute force misses still fails.
#[allow(clippy::too_many_arguments)]
fn check_against_brute(
    gpu_rounding: bool,
    mesh: &raykit_core::TriangleMesh,
    rays: &[Ray],
    test: TestKind,
    opts: &raykit_core::accel::BuildOptions,
    k: usize,
    pool: &rayon::ThreadPool,
    hits: Option<&[Option<raykit_core::Hit>]>,
    occluded: Option<&[bool]>,
) -> Result<ExitCode> {
    let idx = verify::sample(rays.len(), k);
    let sample: Vec<Ray> = idx.iter().map(|&i| rays[i]).collect();
    let brute = build_accel(AccelKind::Brute, test, mesh, opts);
    let verdict = pool.install(|| {
        if let Some(h) = hits {
            let mut want = vec![None; sample.len()];
            brute.intersect_batch(&sample, &mut want);
            let got: Vec<_> = idx.iter().map(|&i| h[i]).collect();
            let mut v = verify::compare_hits(&want, &got);
            if gpu_rounding {
                v.edge_grazes = verify::edge_grazes(mesh, &sample, &want, &got);
            }
            v
        } else {
            let o = occluded.expect("one of the two is set");
            let mut want = vec![false; sample.len()];
            brute.occluded_batch(&sample, &mut want);
            let got: Vec<_> = idx.iter().map(|&i| o[i]).collect();
            let mut v = verify::compare_occlusion(&want, &got);
            if gpu_rounding {
                (v.edge_grazes, _) = verify::occlusion_grazes(mesh, &sample, &want, &got, |r| {
                    let mut near = vec![None; r.len()];
                    brute.intersect_batch(r, &mut near);
                    (near.clone(), near)
                });
            }
            v
        }
    });
    eprintln!(
        "{}",
        json!({ "verify": "brute", "test": test.name(), "result": verdict, "ok": verdict.ok() })
    );
    Ok(if verdict.ok() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// `--backend gpu`: the same job on the GPU kernels.
fn run_gpu(args: TraceArgs) -> Result<ExitCode> {
    let kind = gpu_accel(args.accel.as_deref().unwrap_or("kd-stack"))?;
    let test = TestKind::from_name(&args.test)
        .filter(|t| raykit_gpu::gpu_test_supported(*t))
        .ok_or_else(|| {
            anyhow!(
                "--test '{}' has no GPU kernel; with --backend gpu use plucker or moller",
                args.test
            )
        })?;
    crate::paths::ensure_not_input(
        &args.out,
        &[&args.rays, std::path::Path::new(&args.mesh[0])],
    )?;
    let ctx = open_gpu()?;
    let pool = pool(args.threads)?;
    let (scene, load_s) = timed(|| scene_arg::load(&args.mesh[0]));
    let mesh = scene?.mesh;
    let rays = raykit_io::read_rays(&args.rays)?;
    if rays.is_empty() {
        bail!("{}: the ray file holds no rays", args.rays.display());
    }
    let opts = args.build.options();
    let gpu = |e: raykit_gpu::GpuError| anyhow!("{e}");
    let scene = pool
        .install(|| GpuScene::build(&ctx, &mesh, kind, test, &opts))
        .map_err(gpu)?;
    let tracer = GpuTracer::new(&ctx, &scene).map_err(gpu)?;
    let (mut hits, mut occluded) = (Vec::new(), Vec::new());
    let mut kernel_s = 0.0;
    let start = std::time::Instant::now();
    for chunk in rays.chunks(raykit_gpu::CHUNK) {
        let up = tracer.upload(chunk).map_err(gpu)?;
        kernel_s += tracer.run(&up, args.occlusion).map_err(gpu)?;
        if args.occlusion {
            occluded.extend(tracer.occlusion(&up).map_err(gpu)?);
        } else {
            hits.extend(tracer.hits(&up).map_err(gpu)?);
        }
    }
    let trace_s = start.elapsed().as_secs_f64();
    if args.occlusion {
        raykit_io::write_occlusion(&args.out, &occluded)?;
    } else {
        raykit_io::write_hits(&args.out, &hits)?;
    }
    eprintln!(
        "{}",
        json!({
            "backend": "gpu",
            "adapter": ctx.describe(),
            "accel": kind.name(),
            "bvh_build": crate::build_args::quality_name(opts.quality),
            "test": test.name(),
            "load_ms": load_s * 1e3,
            "build_ms": scene.build_seconds * 1e3,
            "upload_ms": scene.upload_seconds * 1e3,
            "trace_ms": trace_s * 1e3,
            "kernel_ms": kernel_s * 1e3,
            "rays": rays.len(),
            "mrays": rays.len() as f64 / trace_s / 1e6,
            "kernel_mrays": rays.len() as f64 / kernel_s / 1e6,
        })
    );
    let Some(k) = args.verify else {
        return Ok(ExitCode::SUCCESS);
    };
    let (h, o) = if args.occlusion {
        (None, Some(&occluded[..]))
    } else {
        (Some(&hits[..]), None)
    };
    check_against_brute(true, &mesh, &rays, test, &opts, k, &pool, h, o)
}

/// Several meshes (or `--instanced`): an instanced scene under a two-level
/// BVH, each geometry's own `bvh8` over Möller; hits with geometry and
/// instance ids.
fn run_instanced(args: TraceArgs) -> Result<ExitCode> {
    if args.backend == Backend::Gpu {
        bail!("an instanced scene (several --mesh or --instanced) traces on the CPU only");
    }
    if args.one_ray {
        bail!("--one-ray takes one mesh; an instanced scene traces through its batch API");
    }
    if args.verify.is_some() {
        bail!("--verify takes one mesh; an instanced scene is checked by its tests against the flattened scene");
    }
    let accel = args.accel.as_deref().unwrap_or("bvh8");
    if accel != "bvh8" || args.test != "moller" {
        bail!(
            "an instanced scene's geometries use bvh8 over moller (got --accel {accel} --test {})",
            args.test
        );
    }
    let mut inputs: Vec<&std::path::Path> = vec![&args.rays];
    inputs.extend(args.mesh.iter().map(std::path::Path::new));
    crate::paths::ensure_not_input(&args.out, &inputs)?;
    let pool = pool(args.threads)?;
    let threads = pool.current_num_threads();
    let opts = args.build.options();
    let input = pool.install(|| crate::instanced_arg::load(&args.mesh, &opts))?;
    let rays = raykit_io::read_rays(&args.rays)?;
    if rays.is_empty() {
        bail!("{}: the ray file holds no rays", args.rays.display());
    }
    let scene = &input.scene;
    let mask = raykit_core::instancing::MASK_ALL;
    let trace_s;
    if args.occlusion {
        let mut out = vec![false; rays.len()];
        trace_s = pool.install(|| timed(|| scene.occluded_batch(&rays, mask, &mut out)).1);
        raykit_io::write_occlusion(&args.out, &out)?;
    } else {
        let mut out = vec![None; rays.len()];
        trace_s = pool.install(|| timed(|| scene.intersect_batch(&rays, mask, &mut out)).1);
        raykit_io::write_scene_hits(&args.out, &out)?;
    }
    let mut stats = json!({
        "accel": "bvh8",
        "instanced": true,
        "bvh_build": crate::build_args::quality_name(opts.quality),
        "test": "moller",
        "load_ms": input.load_s * 1e3,
        "build_ms": input.build_s * 1e3,
        "trace_ms": trace_s * 1e3,
        "rays": rays.len(),
        "mrays": rays.len() as f64 / trace_s / 1e6,
        "threads": threads,
    });
    if let (Some(o), serde_json::Value::Object(extra)) = (
        stats.as_object_mut(),
        crate::instanced_arg::stats_json(&input),
    ) {
        o.extend(extra);
    }
    eprintln!("{stats}");
    Ok(ExitCode::SUCCESS)
}
