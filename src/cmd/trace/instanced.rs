//! `raykit trace` on an instanced scene (several `--mesh`, or
//! `--instanced`).

use super::args::TraceArgs;
use anyhow::{bail, Result};
use raykit_lab::args::backend::Backend;
use raykit_lab::measure::{per_second, pool, timed};
use serde_json::json;
use std::process::ExitCode;

/// Several meshes (or `--instanced`): an instanced scene under a two-level
/// BVH, each geometry's own `bvh8` over Möller; hits with geometry and
/// instance ids.
pub fn run_instanced(args: TraceArgs) -> Result<ExitCode> {
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
    crate::paths::ensure_output(&args.out, &inputs)?;
    let pool = pool(args.threads)?;
    let threads = pool.current_num_threads();
    super::warn_unused_kd_split(&args.build, accel);
    let opts = args.build.options();
    let input = pool.install(|| crate::instanced_arg::load(&args.mesh, &opts))?;
    let rays = raykit_io::read_rays(&args.rays)?;
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
        "bvh_build": opts.quality.name(),
        "test": "moller",
        "load_ms": input.load_s * 1e3,
        "build_ms": input.build_s * 1e3,
        "trace_ms": trace_s * 1e3,
        "rays": rays.len(),
        "mrays": per_second(rays.len(), trace_s) / 1e6,
        "per_s": per_second(rays.len(), trace_s),
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
