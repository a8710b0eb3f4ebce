//! `raykit trace --backend gpu`: the ray file traced by raykit-gpu's kernels.

use super::args::TraceArgs;
use super::brute_check::check_against_brute;
use super::warn_unused_kd_split;
use anyhow::{anyhow, Result};
use raykit_core::tri::TestKind;
use raykit_gpu::{GpuAccelKind, GpuScene, GpuTracer};
use raykit_lab::args::backend::{gpu_accel, open_gpu};
use raykit_lab::args::scene_arg;
use raykit_lab::measure::{per_second, pool, timed};
use serde_json::json;
use std::process::ExitCode;

/// `--backend gpu`: the same job on the GPU kernels.
pub fn run_gpu(args: TraceArgs) -> Result<ExitCode> {
    let kind = gpu_accel(args.accel.as_deref().unwrap_or("kd-stack"))?;
    let test = TestKind::from_name(&args.test)
        .filter(|t| raykit_gpu::gpu_test_supported(*t))
        .ok_or_else(|| {
            anyhow!(
                "--test '{}' has no GPU kernel; with --backend gpu use plucker or moller",
                args.test
            )
        })?;
    crate::paths::ensure_output(
        &args.out,
        &[&args.rays, std::path::Path::new(&args.mesh[0])],
    )?;
    let ctx = open_gpu()?;
    let pool = pool(args.threads)?;
    let (scene, load_s) = timed(|| scene_arg::load(&args.mesh[0]));
    let mesh = scene?.mesh;
    let rays = raykit_io::read_rays(&args.rays)?;
    let opts = args.build.options();
    let is_kd = matches!(kind, GpuAccelKind::KdStack | GpuAccelKind::KdRopes);
    if !is_kd {
        warn_unused_kd_split(&args.build, kind.name());
    }
    let gpu = |e: raykit_gpu::GpuError| anyhow!("{e}");
    let scene = pool
        .install(|| GpuScene::build(&ctx, &mesh, kind, test, &opts))
        .map_err(gpu)?;
    let tracer = GpuTracer::new(&ctx, &scene).map_err(gpu)?;
    let (mut hits, mut occluded) = (Vec::new(), Vec::new());
    let start = std::time::Instant::now();
    let kernel_s = if args.occlusion {
        let (o, s) = tracer.occluded_timed(&rays).map_err(gpu)?;
        occluded = o;
        s
    } else {
        let (h, s) = tracer.intersect_timed(&rays).map_err(gpu)?;
        hits = h;
        s
    };
    let trace_s = start.elapsed().as_secs_f64();
    if args.occlusion {
        raykit_io::write_occlusion(&args.out, &occluded)?;
    } else {
        raykit_io::write_hits(&args.out, &hits)?;
    }
    let mut stats = json!({
        "backend": "gpu",
        "adapter": ctx.describe(),
        "accel": kind.name(),
        "bvh_build": opts.quality.name(),
        "test": test.name(),
        "load_ms": load_s * 1e3,
        "build_ms": scene.build_seconds * 1e3,
        "upload_ms": scene.upload_seconds * 1e3,
        "trace_ms": trace_s * 1e3,
        "kernel_ms": kernel_s * 1e3,
        "rays": rays.len(),
        "mrays": per_second(rays.len(), trace_s) / 1e6,
        "per_s": per_second(rays.len(), trace_s),
        "kernel_mrays": per_second(rays.len(), kernel_s) / 1e6,
    });
    if is_kd {
        stats["kd_split"] = json!(opts.kd.split.name());
    }
    eprintln!("{stats}");
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
